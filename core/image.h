// Images: linear float RGB, the tone map that turns radiosity into display values, and writing through
// OpenImageIO (PNG 8-bit sRGB, OpenEXR float linear). Every file is encoded in memory and written through
// write_bytes_atomically (core/atomic_file.h), so the destination is whole or untouched and a failed write (a full
// disk) throws aarad::Error, which OpenImageIO's PNG writer alone does not report.
//
// Tone map (documented in docs/solver.md): a display value v = exposure * B per channel, clipped to [0, 1],
// then encoded with the sRGB transfer function (IEC 61966-2-1) and rounded to 8 bits. ToneMap::from_percentile
// picks the exposure that maps a given area-weighted percentile of max(r, g, b) to 1.
#pragma once

#include "aarad/core/rgb.h"

#include <array>
#include <cstdint>
#include <filesystem>
#include <span>
#include <vector>

namespace aarad {

// Linear RGB, rows from top to bottom, 3 floats per pixel.
struct Image {
  int width = 0;
  int height = 0;
  std::vector<float> pixels;

  Image() = default;
  Image(int image_width, int image_height)
      : width(image_width), height(image_height),
        pixels(static_cast<std::size_t>(image_width) * static_cast<std::size_t>(image_height) * 3, 0.0f) {}

  float* at(int x, int y) { return pixels.data() + (static_cast<std::size_t>(y) * width + x) * 3; }
  const float* at(int x, int y) const { return pixels.data() + (static_cast<std::size_t>(y) * width + x) * 3; }
};

// 8-bit display RGB (sRGB encoded), rows from top to bottom.
struct Image8 {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> pixels;

  Image8() = default;
  Image8(int image_width, int image_height)
      : width(image_width), height(image_height),
        pixels(static_cast<std::size_t>(image_width) * static_cast<std::size_t>(image_height) * 3, 0) {}

  std::uint8_t* at(int x, int y) { return pixels.data() + (static_cast<std::size_t>(y) * width + x) * 3; }
  const std::uint8_t* at(int x, int y) const {
    return pixels.data() + (static_cast<std::size_t>(y) * width + x) * 3;
  }
};

// The sRGB transfer function for a linear value in [0, 1].
double srgb_encode(double linear);

struct ToneMap {
  double exposure = 1.0;  // display value = exposure * radiosity, before clipping and sRGB encoding

  std::array<std::uint8_t, 3> operator()(const Rgb& radiosity) const;

  // The exposure that maps the area-weighted `percentile` (in (0, 1]) of max(r, g, b) over `values` to 1;
  // weights[i] is the area of values[i]. Exposure 1 when every value is zero.
  static ToneMap from_percentile(std::span<const Rgb> values, std::span<const double> weights,
                                 double percentile = 0.99);
};

Image8 tone_map(const Image& image, const ToneMap& map);

// PNG, 8-bit RGB. Throws aarad::Error naming the path on failure.
void write_png(const Image8& image, const std::filesystem::path& path);
// OpenEXR, 32-bit float linear RGB (zip compression). Throws aarad::Error naming the path on failure.
void write_exr(const Image& image, const std::filesystem::path& path);

}  // namespace aarad
