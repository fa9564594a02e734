// The exact point-to-polygon form factor, without occlusion: Lambert's contour formula as given by Baum,
// Rushmeier and Winget, "Improving radiosity solutions through the use of analytically determined form
// factors", SIGGRAPH 1989, eq. 9 (docs/form-factors.md).
#pragma once

#include "aarad/core/math.h"
#include "aarad/formfactor/backend.h"
#include "aarad/formfactor/hemicube_geometry.h"

#include <tbb/enumerable_thread_specific.h>

#include <span>
#include <vector>

namespace aarad::formfactor {

// Form factor from the differential area at `point` with unit normal `normal` to `polygon`:
//     F = (1 / 2 pi) sum_i gamma_i normal . unit(R_{i+1} x R_i),   R_i = v_i - point,
// gamma_i the angle between R_i and R_{i+1}. Signed: positive when the vertices run counter-clockwise seen from
// `point`, the negative of the form factor when they run clockwise (the polygon's back is seen). The polygon must
// lie in front of the point's plane (see clip_to_front).
double polygon_form_factor(const Vec3& point, const Vec3& normal, std::span<const Vec3> polygon);

// Clips a polygon given in the shooter's local coordinates (w = height above the shooter's plane, exactly
// signed; hemicube_geometry.h to_local) to w >= 0 (Sutherland-Hodgman, intersection from the edge's endpoints
// in canonical order, snapped to w = 0). Writes at most plane_clipped_capacity(polygon.size()) vertices to `out`
// (polygon.size() + 1 for a convex polygon); returns the count (0 when nothing is left).
std::size_t clip_to_front(std::span<const Vec3> local_polygon, std::span<Vec3> out);

// The analytic back end: for every receiver of the subset that faces the shooter (back-face culling per
// patch, as the hemicubes do), the exact form factor of its part in front of the shooter's plane. Nothing
// occludes. Parallel over receivers; every out[i] is computed alone, so the numbers do not depend on threads.
class AnalyticBackend final : public FormFactorBackend {
 public:
  std::string_view name() const override { return "analytic"; }
  bool tests_visibility() const override { return false; }
  void compute(const Shooter& shooter, const ReceiverView& receivers, std::span<const std::uint32_t> subset,
               std::span<double> out) override;

 private:
  struct Scratch {
    std::vector<Vec3> local, clipped;
  };
  BackFaceCulling culling_;
  tbb::enumerable_thread_specific<Scratch> scratch_;
};

}  // namespace aarad::formfactor
