// Linear RGB triples for reflectance, emission and radiosity (one value per channel, no gamma).
#pragma once

#include <algorithm>

namespace aarad {

struct Rgb {
  double r = 0.0, g = 0.0, b = 0.0;

  constexpr Rgb() = default;
  constexpr Rgb(double red, double green, double blue) : r(red), g(green), b(blue) {}
  constexpr explicit Rgb(double grey) : r(grey), g(grey), b(grey) {}

  constexpr double operator[](int channel) const { return channel == 0 ? r : channel == 1 ? g : b; }
  constexpr double& operator[](int channel) { return channel == 0 ? r : channel == 1 ? g : b; }

  constexpr Rgb& operator+=(const Rgb& o) { r += o.r; g += o.g; b += o.b; return *this; }
  constexpr Rgb& operator-=(const Rgb& o) { r -= o.r; g -= o.g; b -= o.b; return *this; }
  constexpr Rgb& operator*=(double s) { r *= s; g *= s; b *= s; return *this; }
  constexpr Rgb& operator/=(double s) { r /= s; g /= s; b /= s; return *this; }

  constexpr double sum() const { return r + g + b; }
  constexpr double average() const { return (r + g + b) / 3.0; }
  constexpr double max_component() const { return std::max({r, g, b}); }
  constexpr double min_component() const { return std::min({r, g, b}); }
  // Rec. 709 luminance, used to compare radiosities of different colours with one number.
  constexpr double luminance() const { return 0.2126 * r + 0.7152 * g + 0.0722 * b; }

  friend constexpr bool operator==(const Rgb&, const Rgb&) = default;
};

constexpr Rgb operator+(Rgb a, const Rgb& b) { return a += b; }
constexpr Rgb operator-(Rgb a, const Rgb& b) { return a -= b; }
constexpr Rgb operator*(Rgb a, double s) { return a *= s; }
constexpr Rgb operator*(double s, Rgb a) { return a *= s; }
constexpr Rgb operator/(Rgb a, double s) { return a /= s; }
// Component-wise product: reflectance times incident radiosity.
constexpr Rgb operator*(const Rgb& a, const Rgb& b) { return {a.r * b.r, a.g * b.g, a.b * b.b}; }

}  // namespace aarad
