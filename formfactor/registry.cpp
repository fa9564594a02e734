// The back-end registry (Mitsuba-style: back ends chosen at run time by name) and the shooter's frame.
#include "core/error.h"
#include "formfactor/aa_hemicube.h"
#include "formfactor/analytic.h"
#include "formfactor/backend.h"
#include "formfactor/hemicube.h"

#include <cmath>

namespace aarad::formfactor {

Shooter Shooter::from_normal(const Vec3& centre, const Vec3& normal) {
  Shooter s;
  s.centre = centre;
  s.normal = glm::normalize(normal);
  const Vec3 n = s.normal;
  // The world axis least aligned with the normal (ties go to x, then y), made orthogonal to it.
  const double ax = std::abs(n.x), ay = std::abs(n.y), az = std::abs(n.z);
  const Vec3 axis = ax <= ay && ax <= az ? Vec3(1.0, 0.0, 0.0) : (ay <= az ? Vec3(0.0, 1.0, 0.0) : Vec3(0.0, 0.0, 1.0));
  s.tangent = glm::normalize(axis - glm::dot(axis, n) * n);
  s.bitangent = glm::cross(n, s.tangent);  // tangent x bitangent = normal
  return s;
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
