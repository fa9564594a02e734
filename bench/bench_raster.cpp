// Throughput and accuracy of aarad's exact area scan converter (core/area_rasterizer.h, the algorithm of
// Figure 4 of Chandran et al., section 2.1) next to three 8-bit anti-aliasing rasterizers fed the very
// same polygons: FreeType's smooth rasterizer (FT_Outline_Render, direct spans), stb_truetype's
// stbtt_Rasterize and Anti-Grain Geometry's rasterizer_scanline_aa with scanline_u8.
//
// Every library's output is consumed the same way: the coverage of every pixel it reports is added to a
// double image (what a hemicube does with it). Items are polygons. Before the benchmarks run, each
// library's largest per-pixel coverage error against the exact area (polygon ∩ pixel in exact rationals)
// is printed. docs/benchmarks.md ("Raster") records the results.
#include "aarad/core/area_rasterizer.h"

#include <CGAL/Exact_rational.h>
#include <agg_rasterizer_scanline_aa.h>
#include <agg_scanline_u.h>
#include <benchmark/benchmark.h>
#include <ft2build.h>
#include FT_FREETYPE_H
#include FT_OUTLINE_H
#include <stb_truetype.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <vector>

namespace {

using aarad::Vec2;
using Polygon = std::vector<Vec2>;

constexpr int kSide = 256;         // viewport: kSide x kSide pixels
constexpr int kPolygons = 512;     // per shape
constexpr int kErrorPolygons = 96;  // per shape, checked against the exact reference at start-up

// ---- The seeded polygon sets -------------------------------------------------------------------------

class Random {
 public:
  explicit Random(std::uint64_t seed) : engine_(seed) {}
  double uniform(double lo, double hi) { return lo + (hi - lo) * (static_cast<double>(engine_() >> 11) * 0x1p-53); }
  int integer(int lo, int hi) { return lo + static_cast<int>(engine_() % static_cast<std::uint64_t>(hi - lo + 1)); }

 private:
  std::mt19937_64 engine_;
};

// Convex: 3 to 8 points of a sheared, rotated ellipse at sorted random angles. Concave: a star with 5 to
// 12 vertices, one per sector at a random radius. Sizes (the larger side of the bounding box)
// log-uniform in [2, 200] pixels; every polygon lies inside the viewport; half of them clockwise.
std::vector<Polygon> make_polygons(bool convex, std::uint64_t seed) {
  Random random(seed);
  std::vector<Polygon> polygons;
  for (int k = 0; k < kPolygons; ++k) {
    const double size = std::exp(random.uniform(std::log(2.0), std::log(200.0)));
    const double half = 0.5 * size;
    Polygon polygon;
    if (convex) {
      const int n = random.integer(3, 8);
      std::vector<double> angles(static_cast<std::size_t>(n));
      for (double& a : angles) a = random.uniform(0.0, 2.0 * aarad::kPi);
      std::sort(angles.begin(), angles.end());
      const double ry = half * random.uniform(0.2, 1.0), shear = random.uniform(-0.5, 0.5);
      const double turn = random.uniform(0.0, aarad::kPi), c = std::cos(turn), s = std::sin(turn);
      for (double a : angles) {
        const double px = half * std::cos(a), py = ry * std::sin(a);
        const double qx = px + shear * py;
        polygon.push_back(Vec2{c * qx - s * py, s * qx + c * py});
      }
    } else {
      const int n = random.integer(5, 12);
      const double start = random.uniform(0.0, 2.0 * aarad::kPi);
      for (int i = 0; i < n; ++i) {
        const double a = start + (i + random.uniform(0.0, 0.9)) * 2.0 * aarad::kPi / n;
        const double r = half * random.uniform(0.25, 1.0);
        polygon.push_back(r * Vec2{std::cos(a), std::sin(a)});
      }
    }
    // Scale to the drawn size (the larger side of the bounding box), then place it inside the viewport.
    Vec2 low = polygon[0], high = polygon[0];
    for (const Vec2& v : polygon) low = glm::min(low, v), high = glm::max(high, v);
    const double scale = size / std::max(high.x - low.x, high.y - low.y);
    const Vec2 extent = scale * (high - low);
    const Vec2 corner{random.uniform(0.0, kSide - extent.x), random.uniform(0.0, kSide - extent.y)};
    for (Vec2& v : polygon) v = corner + scale * (v - low);
    if (k % 2) std::reverse(polygon.begin(), polygon.end());
    polygons.push_back(std::move(polygon));
  }
  return polygons;
}

const std::vector<Polygon>& polygons(bool convex) {
  static const std::vector<Polygon> convex_set = make_polygons(true, 4242);
  static const std::vector<Polygon> concave_set = make_polygons(false, 4243);
  return convex ? convex_set : concave_set;
}

struct Box {
  int x0, y0, x1, y1;  // pixel rows/columns [x0, x1) x [y0, y1)
};

Box pixel_box(const Polygon& polygon) {
  double min_x = polygon[0].x, max_x = min_x, min_y = polygon[0].y, max_y = min_y;
  for (const Vec2& v : polygon) {
    min_x = std::min(min_x, v.x), max_x = std::max(max_x, v.x);
    min_y = std::min(min_y, v.y), max_y = std::max(max_y, v.y);
  }
  return {std::max(0, static_cast<int>(std::floor(min_x))), std::max(0, static_cast<int>(std::floor(min_y))),
          std::min(kSide, static_cast<int>(std::ceil(max_x))), std::min(kSide, static_cast<int>(std::ceil(max_y)))};
}

// ---- The four rasterizers, each adding coverage to a kSide x kSide double image ----------------------

// aarad reports pixels column by column, so its image is stored column by column (x * kSide + y), as the
// scanline libraries' images are stored row by row; AaradRowMajor shows the cost of the other layout.
struct Aarad {
  static constexpr bool kColumnMajor = true;
  aarad::AreaRasterizer rasterizer{kSide, kSide};
  void operator()(const Polygon& polygon, double* image) {
    rasterizer.rasterize(polygon, [image](int x, int y, double coverage) { image[x * kSide + y] += coverage; });
  }
};

struct AaradRowMajor {
  static constexpr bool kColumnMajor = false;
  aarad::AreaRasterizer rasterizer{kSide, kSide};
  void operator()(const Polygon& polygon, double* image) {
    rasterizer.rasterize(polygon, [image](int x, int y, double coverage) { image[y * kSide + x] += coverage; });
  }
};

class FreeType {
 public:
  FreeType() {
    if (FT_Init_FreeType(&library_) != 0) std::abort();
  }
  ~FreeType() { FT_Done_FreeType(library_); }
  FreeType(const FreeType&) = delete;
  FreeType& operator=(const FreeType&) = delete;

  void operator()(const Polygon& polygon, double* image) {
    const int n = static_cast<int>(polygon.size());
    for (int i = 0; i < n; ++i) {  // 26.6 fixed point
      points_[static_cast<std::size_t>(i)].x = std::lround(polygon[static_cast<std::size_t>(i)].x * 64.0);
      points_[static_cast<std::size_t>(i)].y = std::lround(polygon[static_cast<std::size_t>(i)].y * 64.0);
      tags_[static_cast<std::size_t>(i)] = FT_CURVE_TAG_ON;
    }
    short last = static_cast<short>(n - 1);
    FT_Outline outline{};
    outline.n_contours = 1;
    outline.n_points = static_cast<short>(n);
    outline.points = points_.data();
    outline.tags = tags_.data();
    outline.contours = &last;
    outline.flags = FT_OUTLINE_NONE;
    FT_Raster_Params params{};
    params.source = &outline;
    params.flags = FT_RASTER_FLAG_AA | FT_RASTER_FLAG_DIRECT | FT_RASTER_FLAG_CLIP;
    params.gray_spans = &FreeType::spans;
    params.user = image;
    params.clip_box = {0, 0, kSide, kSide};
    FT_Outline_Render(library_, &outline, &params);
  }

 private:
  static void spans(int y, int count, const FT_Span* spans, void* user) {
    double* row = static_cast<double*>(user) + y * kSide;
    for (int i = 0; i < count; ++i) {
      const double coverage = spans[i].coverage * (1.0 / 255.0);
      for (int k = 0; k < spans[i].len; ++k) row[spans[i].x + k] += coverage;
    }
  }

  FT_Library library_ = nullptr;
  std::array<FT_Vector, 16> points_{};
  std::array<char, 16> tags_{};
};

class Stb {
 public:
  void operator()(const Polygon& polygon, double* image) {
    const int n = static_cast<int>(polygon.size());
    for (int i = 0; i < n; ++i) {  // stbtt_vertex holds shorts: 1/64 pixel units, scaled back below
      stbtt_vertex& v = vertices_[static_cast<std::size_t>(i)];
      v = stbtt_vertex{};
      v.type = i == 0 ? STBTT_vmove : STBTT_vline;
      v.x = static_cast<short>(std::lround(polygon[static_cast<std::size_t>(i)].x * 64.0));
      v.y = static_cast<short>(std::lround(polygon[static_cast<std::size_t>(i)].y * 64.0));
    }
    const Box box = pixel_box(polygon);
    // stb's bitmap runs top-down: with invert, device y' = kSide - y; bitmap row j is y' in
    // [off_y + j, off_y + j + 1), that is our pixel row box.y1 - 1 - j.
    stbtt__bitmap bitmap{box.x1 - box.x0, box.y1 - box.y0, box.x1 - box.x0, pixels_.data()};
    if (bitmap.w <= 0 || bitmap.h <= 0) return;
    stbtt_Rasterize(&bitmap, 0.35f, vertices_.data(), n, 1.0f / 64.0f, 1.0f / 64.0f, 0.0f, static_cast<float>(kSide),
                    box.x0, kSide - box.y1, 1, nullptr);
    for (int j = 0; j < bitmap.h; ++j) {
      double* row = image + (box.y1 - 1 - j) * kSide + box.x0;
      const unsigned char* source = bitmap.pixels + j * bitmap.stride;
      for (int i = 0; i < bitmap.w; ++i)
        if (source[i]) row[i] += source[i] * (1.0 / 255.0);
    }
  }

 private:
  std::array<stbtt_vertex, 16> vertices_{};
  std::vector<unsigned char> pixels_ = std::vector<unsigned char>(kSide * kSide);
};

class Agg {
 public:
  Agg() { rasterizer_.clip_box(0, 0, kSide, kSide); }

  void operator()(const Polygon& polygon, double* image) {
    rasterizer_.reset();
    rasterizer_.move_to_d(polygon[0].x, polygon[0].y);
    for (std::size_t i = 1; i < polygon.size(); ++i) rasterizer_.line_to_d(polygon[i].x, polygon[i].y);
    rasterizer_.close_polygon();
    if (!rasterizer_.rewind_scanlines()) return;
    scanline_.reset(rasterizer_.min_x(), rasterizer_.max_x());
    while (rasterizer_.sweep_scanline(scanline_)) {
      double* row = image + scanline_.y() * kSide;
      unsigned spans = scanline_.num_spans();
      for (auto span = scanline_.begin(); spans > 0; --spans, ++span)
        for (int k = 0; k < span->len; ++k) row[span->x + k] += span->covers[k] * (1.0 / 255.0);
    }
  }

 private:
  agg::rasterizer_scanline_aa<> rasterizer_;
  agg::scanline_u8 scanline_;
};

// ---- Exact reference: polygon ∩ pixel in exact rationals ----------------------------------------------

using Q = CGAL::Exact_rational;
struct QPoint {
  Q x, y;
};

std::vector<QPoint> clip(const std::vector<QPoint>& polygon, bool vertical_line, const Q& c, bool keep_above) {
  std::vector<QPoint> out;
  const std::size_t n = polygon.size();
  auto coord = [vertical_line](const QPoint& p) -> const Q& { return vertical_line ? p.x : p.y; };
  for (std::size_t i = 0; i < n; ++i) {
    const QPoint& a = polygon[i];
    const QPoint& b = polygon[(i + 1) % n];
    const bool a_in = keep_above ? coord(a) >= c : coord(a) <= c;
    const bool b_in = keep_above ? coord(b) >= c : coord(b) <= c;
    if (a_in) out.push_back(a);
    if (a_in != b_in) {
      const Q t = (c - coord(a)) / (coord(b) - coord(a));
      out.push_back({a.x + t * (b.x - a.x), a.y + t * (b.y - a.y)});
    }
  }
  return out;
}

Q twice_area(const std::vector<QPoint>& polygon) {
  Q sum = 0;
  for (std::size_t i = 0; i < polygon.size(); ++i) {
    const QPoint& a = polygon[i];
    const QPoint& b = polygon[(i + 1) % polygon.size()];
    sum += a.x * b.y - b.x * a.y;
  }
  return sum;
}

// Exact coverage over the polygon's pixel box, row-major within the box.
std::vector<double> exact_coverage(const Polygon& polygon, const Box& box) {
  const int w = box.x1 - box.x0;
  std::vector<double> out(static_cast<std::size_t>(w * (box.y1 - box.y0)), 0.0);
  std::vector<QPoint> q;
  for (const Vec2& v : polygon) q.push_back({Q(v.x), Q(v.y)});
  const Q orientation = twice_area(q) > 0 ? Q(1) : Q(-1);
  for (int x = box.x0; x < box.x1; ++x) {
    const std::vector<QPoint> strip = clip(clip(q, true, Q(x), true), true, Q(x + 1), false);
    Q below = 0;
    for (int y = box.y0; y < box.y1; ++y) {
      const Q next = twice_area(clip(strip, false, Q(y + 1), false));
      out[static_cast<std::size_t>((y - box.y0) * w + (x - box.x0))] = CGAL::to_double((next - below) * orientation / 2);
      below = next;
    }
  }
  return out;
}

template <class Rasterizer>
constexpr bool column_major() {
  if constexpr (requires { Rasterizer::kColumnMajor; })
    return Rasterizer::kColumnMajor;
  else
    return false;
}

template <class Rasterizer>
double largest_error(Rasterizer& rasterize, const std::vector<Polygon>& set,
                     const std::vector<std::vector<double>>& reference) {
  std::vector<double> image(kSide * kSide, 0.0);
  double worst = 0.0;
  for (std::size_t k = 0; k < reference.size(); ++k) {
    std::fill(image.begin(), image.end(), 0.0);
    rasterize(set[k], image.data());
    const Box box = pixel_box(set[k]);
    const int w = box.x1 - box.x0;
    for (int y = 0; y < kSide; ++y)
      for (int x = 0; x < kSide; ++x) {
        const bool inside = x >= box.x0 && x < box.x1 && y >= box.y0 && y < box.y1;
        const double exact =
            inside ? reference[k][static_cast<std::size_t>((y - box.y0) * w + (x - box.x0))] : 0.0;
        const int index = column_major<Rasterizer>() ? x * kSide + y : y * kSide + x;
        worst = std::max(worst, std::abs(image[static_cast<std::size_t>(index)] - exact));
      }
  }
  return worst;
}

void print_error_report() {
  const auto start = std::chrono::steady_clock::now();
  Aarad aarad_rasterizer;
  FreeType freetype;
  Stb stb;
  Agg agg;
  std::printf("Largest per-pixel coverage error against the exact area (first %d polygons of each set):\n",
              kErrorPolygons);
  std::printf("%-10s %14s %14s\n", "library", "convex", "concave");
  std::array<std::array<double, 2>, 4> errors{};
  for (int shape = 0; shape < 2; ++shape) {
    const std::vector<Polygon>& set = polygons(shape == 0);
    std::vector<std::vector<double>> reference;
    for (int k = 0; k < kErrorPolygons; ++k) reference.push_back(exact_coverage(set[static_cast<std::size_t>(k)], pixel_box(set[static_cast<std::size_t>(k)])));
    errors[0][static_cast<std::size_t>(shape)] = largest_error(aarad_rasterizer, set, reference);
    errors[1][static_cast<std::size_t>(shape)] = largest_error(freetype, set, reference);
    errors[2][static_cast<std::size_t>(shape)] = largest_error(stb, set, reference);
    errors[3][static_cast<std::size_t>(shape)] = largest_error(agg, set, reference);
  }
  const char* names[] = {"aarad", "freetype", "stb", "agg"};
  for (std::size_t i = 0; i < 4; ++i) std::printf("%-10s %14.3g %14.3g\n", names[i], errors[i][0], errors[i][1]);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("(exact reference in %.1f s; 1/256 = %.3g)\n\n", seconds, 1.0 / 256.0);
  std::fflush(stdout);
}

// ---- Benchmarks ----------------------------------------------------------------------------------------

template <class Rasterizer>
void run(benchmark::State& state, bool convex) {
  const std::vector<Polygon>& set = polygons(convex);
  Rasterizer rasterize;
  std::vector<double> image(kSide * kSide, 0.0);
  for (auto _ : state) {
    for (const Polygon& polygon : set) rasterize(polygon, image.data());
    benchmark::DoNotOptimize(image.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(set.size()));
}

void BM_Raster_aarad_convex(benchmark::State& state) { run<Aarad>(state, true); }
void BM_Raster_freetype_convex(benchmark::State& state) { run<FreeType>(state, true); }
void BM_Raster_stb_convex(benchmark::State& state) { run<Stb>(state, true); }
void BM_Raster_agg_convex(benchmark::State& state) { run<Agg>(state, true); }
void BM_Raster_aarad_concave(benchmark::State& state) { run<Aarad>(state, false); }
void BM_Raster_aarad_convex_rowmajor_image(benchmark::State& state) { run<AaradRowMajor>(state, true); }
void BM_Raster_freetype_concave(benchmark::State& state) { run<FreeType>(state, false); }
void BM_Raster_stb_concave(benchmark::State& state) { run<Stb>(state, false); }
void BM_Raster_agg_concave(benchmark::State& state) { run<Agg>(state, false); }

BENCHMARK(BM_Raster_aarad_convex);
BENCHMARK(BM_Raster_freetype_convex);
BENCHMARK(BM_Raster_stb_convex);
BENCHMARK(BM_Raster_agg_convex);
BENCHMARK(BM_Raster_aarad_concave);
BENCHMARK(BM_Raster_freetype_concave);
BENCHMARK(BM_Raster_stb_concave);
BENCHMARK(BM_Raster_agg_concave);
BENCHMARK(BM_Raster_aarad_convex_rowmajor_image);

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  print_error_report();
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
