// The back-end registry (Mitsuba-style: back ends chosen at run time by name) and the shooter's frame.
#include "aarad/core/error.h"
#include "aarad/formfactor/aa_hemicube.h"
#include "aarad/formfactor/analytic.h"
#include "aarad/formfactor/backend.h"
#include "aarad/formfactor/hemicube.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace aarad::formfactor {

Shooter Shooter::from_normal(const Vec3& centre, const Vec3& normal) {
  // Scaled by a power of two near its largest component first, so that a normal of 1e200 or 1e-200 (whose length
  // overflows or underflows) keeps its direction.
  const double largest = std::max({std::abs(normal.x), std::abs(normal.y), std::abs(normal.z)});
  if (!(largest > 0.0) || !std::isfinite(largest)) {
    char text[160];
    std::snprintf(text, sizeof text, "(%.17g, %.17g, %.17g)", normal.x, normal.y, normal.z);
    throw Error(std::string("Shooter::from_normal: the normal ") + text + " has no direction; give a finite, "
                "non-zero normal");
  }
  Shooter s;
  s.centre = centre;
  const int e = -std::ilogb(largest);  // scalbn per component: 2^e overflows for a subnormal normal
  s.normal = glm::normalize(Vec3(std::scalbn(normal.x, e), std::scalbn(normal.y, e), std::scalbn(normal.z, e)));
  const Vec3 n = s.normal;
  // The world axis least aligned with the normal (ties go to x, then y), made orthogonal to it.
  const double ax = std::abs(n.x), ay = std::abs(n.y), az = std::abs(n.z);
  const Vec3 axis = ax <= ay && ax <= az ? Vec3(1.0, 0.0, 0.0) : (ay <= az ? Vec3(0.0, 1.0, 0.0) : Vec3(0.0, 0.0, 1.0));
  s.tangent = glm::normalize(axis - glm::dot(axis, n) * n);
  s.bitangent = glm::cross(n, s.tangent);  // tangent x bitangent = normal
  return s;
}

void check_shot(const Shooter& shooter, const ReceiverView& receivers, std::span<const std::uint32_t> subset,
                std::span<const double> out) {
  if (out.size() != receivers.size())
    throw Error("form factors: " + std::to_string(out.size()) + " output values for " +
                std::to_string(receivers.size()) + " receivers; pass one per receiver");
  for (std::size_t k = 0; k < subset.size(); ++k) {
    if (subset[k] >= receivers.size())
      throw Error("form factors: subset entry " + std::to_string(k) + " is receiver " + std::to_string(subset[k]) +
                  ", but there are " + std::to_string(receivers.size()) + " receivers; pass receiver indices below " +
                  std::to_string(receivers.size()));
  }
  const Vec3& c = shooter.centre;
  if (!std::isfinite(c.x) || !std::isfinite(c.y) || !std::isfinite(c.z))
    throw Error("form factors: the shooter's centre is not finite");
  const auto unit = [](const Vec3& v) { return std::abs(glm::dot(v, v) - 1.0) <= 1e-9; };
  const Vec3 product = glm::cross(shooter.tangent, shooter.bitangent);
  if (!unit(shooter.normal) || !unit(shooter.tangent) || !unit(shooter.bitangent) ||
      std::abs(glm::dot(shooter.tangent, shooter.bitangent)) > 1e-9 || !(glm::length(product - shooter.normal) <= 1e-9))
    throw Error("form factors: the shooter's tangent, bitangent and normal are not a right-handed orthonormal frame "
                "(tangent x bitangent = normal); make the shooter with Shooter::from_normal");
}

std::vector<std::string> backend_names() { return {"aa-hemicube", "hemicube", "analytic"}; }

std::unique_ptr<FormFactorBackend> make_backend(std::string_view name, const BackendOptions& options) {
  if (name == "aa-hemicube" || name == "hemicube") {
    check_resolution(options.resolution);
    if (name == "hemicube") return std::make_unique<HemicubeBackend>(options.resolution);
    return std::make_unique<AaHemicubeBackend>(options.resolution);
  }
  if (name == "analytic") return std::make_unique<AnalyticBackend>();
  std::string known;
  for (const std::string& n : backend_names()) known += (known.empty() ? "" : ", ") + n;
  throw Error("unknown form-factor back end '" + std::string(name) + "'; known back ends: " + known);
}

}  // namespace aarad::formfactor
