// Z-buffered scan conversion of the display triangles with perspective-correct interpolation (edge functions,
// Pineda 1988, "A parallel algorithm for polygon rasterization"; near-plane clipping after Sutherland and
// Hodgman 1974). See render.h for what each shading shows.
#include "aarad/refine/render.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>

namespace aarad::refine {
namespace {

struct ClipVertex {
  Vec3 camera;  // x right, y up, z forward
  Rgb value;
};

struct ScreenVertex {
  double x, y;     // pixels, y down
  double inv_z;    // 1 / camera depth
  Rgb value_over_z;
};

// Keeps the part of the polygon with z >= near.
int clip_near(const std::array<ClipVertex, 3>& in, double near, std::array<ClipVertex, 4>& out) {
  int count = 0;
  for (int i = 0; i < 3; ++i) {
    const ClipVertex& a = in[static_cast<std::size_t>(i)];
    const ClipVertex& b = in[static_cast<std::size_t>((i + 1) % 3)];
    const bool a_in = a.camera.z >= near;
    const bool b_in = b.camera.z >= near;
    if (a_in) out[static_cast<std::size_t>(count++)] = a;
    if (a_in != b_in) {
      const double t = (near - a.camera.z) / (b.camera.z - a.camera.z);
      out[static_cast<std::size_t>(count++)] = {a.camera + t * (b.camera - a.camera), a.value + (b.value - a.value) * t};
    }
  }
  return count;
}

// The pixels [first, last] of an axis of `size` pixels that the screen span [low, high] reaches (first > last when
// none). Clamped before the conversion to int: a triangle clipped at the near plane can reach far beyond the image,
// past what an int holds, when the field of view is narrow.
std::pair<int, int> pixel_span(double low, double high, int size) {
  const double first = std::clamp(std::floor(low), 0.0, static_cast<double>(size));
  const double last = std::clamp(std::ceil(high), -1.0, static_cast<double>(size - 1));
  return {static_cast<int>(first), static_cast<int>(last)};
}

}  // namespace

Rendering render(const mesh::DisplayMesh& display, std::span<const Rgb> node_values, const Camera& camera,
                 int width, int height, Shading shading, double scale) {
  Rendering result{Image(width, height),
                   std::vector<mesh::NodeId>(static_cast<std::size_t>(width) * static_cast<std::size_t>(height),
                                             mesh::kNoNode),
                   scale};
  if (width <= 0 || height <= 0 || display.positions.empty()) return result;
  std::vector<double> depth(result.leaf.size(), 0.0);  // 1 / z; larger is nearer, 0 is empty

  const Vec3 forward = glm::normalize(camera.forward);
  const Vec3 right = glm::normalize(glm::cross(forward, camera.up));
  const Vec3 up = glm::cross(right, forward);
  const double tan_half = std::tan(0.5 * camera.vertical_fov);
  const double aspect = static_cast<double>(width) / height;

  Vec3 low = display.positions.front(), high = low;
  for (const Vec3& p : display.positions) {
    low = glm::min(low, p);
    high = glm::max(high, p);
  }
  const double near = 1e-6 * std::max(glm::length(high - low), glm::length(camera.eye - low));

  const auto to_camera = [&](const Vec3& p) {
    const Vec3 d = p - camera.eye;
    return Vec3(glm::dot(d, right), glm::dot(d, up), glm::dot(d, forward));
  };
  const auto to_screen = [&](const ClipVertex& v) {
    const double inv_z = 1.0 / v.camera.z;
    const double sx = v.camera.x * inv_z / (tan_half * aspect);
    const double sy = v.camera.y * inv_z / tan_half;
    return ScreenVertex{(sx + 1.0) * 0.5 * width, (1.0 - sy) * 0.5 * height, inv_z, v.value * inv_z};
  };

  std::array<ClipVertex, 4> clipped;
  for (std::size_t t = 0; t < display.triangles.size(); ++t) {
    const auto& tri = display.triangles[t];
    const Vec3& p0 = display.positions[tri[0]];
    const Vec3& p1 = display.positions[tri[1]];
    const Vec3& p2 = display.positions[tri[2]];
    // Back faces (seen from behind their front side) are culled.
    if (glm::dot(glm::cross(p1 - p0, p2 - p0), camera.eye - p0) <= 0.0) continue;
    const mesh::NodeId leaf = display.triangle_leaf[t];
    std::array<ClipVertex, 3> corners;
    for (std::size_t k = 0; k < 3; ++k) {
      const Rgb value = shading == Shading::kFlat ? node_values[leaf] : display.vertex_values[tri[k]];
      corners[k] = {to_camera(display.positions[tri[k]]), value};
    }
    const int count = clip_near(corners, near, clipped);
    for (int k = 1; k + 1 < count; ++k) {
      const ScreenVertex a = to_screen(clipped[0]);
      const ScreenVertex b = to_screen(clipped[static_cast<std::size_t>(k)]);
      const ScreenVertex c = to_screen(clipped[static_cast<std::size_t>(k + 1)]);
      const double area = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
      if (area == 0.0 || !std::isfinite(area)) continue;
      const double sign = area > 0.0 ? 1.0 : -1.0;
      const auto [x0, x1] = pixel_span(std::min({a.x, b.x, c.x}), std::max({a.x, b.x, c.x}), width);
      const auto [y0, y1] = pixel_span(std::min({a.y, b.y, c.y}), std::max({a.y, b.y, c.y}), height);
      for (int y = y0; y <= y1; ++y) {
        const double py = y + 0.5;
        for (int x = x0; x <= x1; ++x) {
          const double px = x + 0.5;
          const double w0 = sign * ((c.x - b.x) * (py - b.y) - (px - b.x) * (c.y - b.y));
          const double w1 = sign * ((a.x - c.x) * (py - c.y) - (px - c.x) * (a.y - c.y));
          const double w2 = sign * ((b.x - a.x) * (py - a.y) - (px - a.x) * (b.y - a.y));
          if (w0 < 0.0 || w1 < 0.0 || w2 < 0.0) continue;
          const double total = w0 + w1 + w2;
          const double inv_z = (w0 * a.inv_z + w1 * b.inv_z + w2 * c.inv_z) / total;
          const std::size_t index = static_cast<std::size_t>(y) * width + x;
          if (inv_z <= depth[index]) continue;
          depth[index] = inv_z;
          result.leaf[index] = leaf;
          const Rgb value =
              (a.value_over_z * w0 + b.value_over_z * w1 + c.value_over_z * w2) / (total * inv_z) * scale;
          float* pixel = result.image.at(x, y);
          pixel[0] = static_cast<float>(value.r);
          pixel[1] = static_cast<float>(value.g);
          pixel[2] = static_cast<float>(value.b);
        }
      }
    }
  }
  return result;
}

double image_scale(double exposure) {
  return exposure > 0.0 && std::isfinite(exposure) ? std::ldexp(1.0, std::ilogb(exposure)) : 1.0;
}

void draw_leaf_edges(Image8& image, const std::vector<mesh::NodeId>& leaf) {
  const int w = image.width, h = image.height;
  std::vector<std::uint8_t> on_edge(leaf.size(), 0);
  // Between two elements the line is drawn on the first pixel; between an element and the background, on the
  // element's, so that the outline stays on the scene on every side (drawn on the first pixel, it was painted
  // into the black background above and left of the scene).
  const auto mark = [&](std::size_t i, std::size_t j) {
    if (leaf[i] != leaf[j]) on_edge[leaf[i] == mesh::kNoNode ? j : i] = 1;
  };
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      if (x + 1 < w) mark(i, i + 1);
      if (y + 1 < h) mark(i, i + w);
    }
  }
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      if (!on_edge[static_cast<std::size_t>(y) * w + x]) continue;
      std::uint8_t* p = image.at(x, y);
      const double luma = 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
      for (int c = 0; c < 3; ++c) {
        p[c] = luma > 96.0 ? static_cast<std::uint8_t>(p[c] / 4) : static_cast<std::uint8_t>(255 - (255 - p[c]) / 3);
      }
    }
  }
}

}  // namespace aarad::refine
