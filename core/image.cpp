// Image writing through OpenImageIO and the display tone map (see image.h and docs/solver.md).
#include "aarad/core/image.h"

#include "aarad/core/atomic_file.h"
#include "aarad/core/error.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string_view>
#include <vector>

namespace aarad {

double srgb_encode(double linear) {
  const double v = std::clamp(linear, 0.0, 1.0);
  return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
}

std::array<std::uint8_t, 3> ToneMap::operator()(const Rgb& radiosity) const {
  std::array<std::uint8_t, 3> out{};
  for (int c = 0; c < 3; ++c) {
    out[static_cast<std::size_t>(c)] =
        static_cast<std::uint8_t>(std::lround(255.0 * srgb_encode(exposure * radiosity[c])));
  }
  return out;
}

ToneMap ToneMap::from_percentile(std::span<const Rgb> values, std::span<const double> weights, double percentile) {
  const std::size_t n = std::min(values.size(), weights.size());
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), std::size_t{0});
  // Sort by value, ties by index, so the result does not depend on the sort's stability.
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    const double va = values[a].max_component();
    const double vb = values[b].max_component();
    return va != vb ? va < vb : a < b;
  });
  double total = 0.0;
  for (std::size_t i = 0; i < n; ++i) total += std::max(weights[i], 0.0);
  ToneMap map;
  if (total <= 0.0) return map;
  const double target = std::clamp(percentile, 0.0, 1.0) * total;
  double cumulative = 0.0;
  double level = 0.0;
  for (std::size_t i : order) {
    cumulative += std::max(weights[i], 0.0);
    level = values[i].max_component();
    if (cumulative >= target) break;
  }
  if (level > 0.0 && std::isfinite(level)) map.exposure = 1.0 / level;
  return map;
}

Image8 tone_map(const Image& image, const ToneMap& map) {
  Image8 out(image.width, image.height);
  for (std::size_t i = 0; i + 2 < image.pixels.size(); i += 3) {
    const auto v = map(Rgb(image.pixels[i], image.pixels[i + 1], image.pixels[i + 2]));
    out.pixels[i] = v[0];
    out.pixels[i + 1] = v[1];
    out.pixels[i + 2] = v[2];
  }
  return out;
}

namespace {

// Encodes the image in memory and writes the bytes whole. OpenImageIO's PNG writer does not report a failed
// write (on a full disk it left an empty file and no error), so the file is written by write_bytes_atomically,
// which checks.
void write_with_oiio(const char* format, const std::filesystem::path& path, const OIIO::ImageSpec& spec,
                     OIIO::TypeDesc type, const void* data) {
  auto output = OIIO::ImageOutput::create(format);
  if (!output || !output->supports("ioproxy"))
    throw Error("cannot write " + path.string() + ": OpenImageIO has no " + format + " writer to memory");
  std::vector<unsigned char> encoded;
  OIIO::Filesystem::IOVecOutput memory(encoded);
  output->set_ioproxy(&memory);
  if (!output->open(path.string(), spec) || !output->write_image(type, data) || !output->close())
    throw Error("cannot write " + path.string() + ": " + output->geterror());
  write_bytes_atomically(path, std::string_view(reinterpret_cast<const char*>(encoded.data()), encoded.size()));
}

}  // namespace

void write_png(const Image8& image, const std::filesystem::path& path) {
  OIIO::ImageSpec spec(image.width, image.height, 3, OIIO::TypeDesc::UINT8);
  spec.attribute("oiio:ColorSpace", "sRGB");
  write_with_oiio("png", path, spec, OIIO::TypeDesc::UINT8, image.pixels.data());
}

void write_exr(const Image& image, const std::filesystem::path& path) {
  OIIO::ImageSpec spec(image.width, image.height, 3, OIIO::TypeDesc::FLOAT);
  spec.attribute("compression", "zip");
  spec.attribute("oiio:ColorSpace", "Linear");
  // OpenImageIO stamps the header's capDate with the time of writing when the spec has no DateTime; an empty one
  // keeps the file the same bytes for the same image, as the PNGs and the PLY are.
  spec.attribute("DateTime", "");
  write_with_oiio("openexr", path, spec, OIIO::TypeDesc::FLOAT, image.pixels.data());
}

}  // namespace aarad
