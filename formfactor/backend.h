// The form-factor back-end interface: a small virtual class, created by name through a registry
// (Mitsuba-style plugins). Inner loops stay inside each back end; nothing per pixel is virtual.
#pragma once

#include "aarad/core/math.h"
#include "aarad/formfactor/receiver_view.h"

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace aarad::formfactor {

// The shooting point with a right-handed orthonormal frame: tangent x bitangent = normal.
struct Shooter {
  Vec3 centre{0.0};
  Vec3 normal{0.0, 0.0, 1.0};
  Vec3 tangent{1.0, 0.0, 0.0};
  Vec3 bitangent{0.0, 1.0, 0.0};

  // A frame around `normal` (normalized here) with a deterministic tangent. Throws aarad::Error when `normal` is
  // zero or not finite.
  static Shooter from_normal(const Vec3& centre, const Vec3& normal);
};

// What every back end's compute() checks first: a finite centre, a right-handed orthonormal frame (tangent x
// bitangent = normal, within 1e-9; a Shooter written by hand with a normal other than +z needs its tangents too:
// use from_normal), every subset entry a receiver index, and one output value per receiver. Throws aarad::Error
// naming what is wrong.
void check_shot(const Shooter& shooter, const ReceiverView& receivers, std::span<const std::uint32_t> subset,
                std::span<const double> out);

struct BackendOptions {
  int resolution = 100;  // pixels along the full top face of a hemicube
};

class FormFactorBackend {
 public:
  virtual ~FormFactorBackend() = default;

  virtual std::string_view name() const = 0;
  // Whether compute() lets receivers hide one another; a back end that does not is exact only in scenes where
  // nothing can (Scene::occlusion_witness).
  virtual bool tests_visibility() const { return true; }

  // For every receiver i in `subset` (all receivers when `subset` is empty), writes to out[i] the form
  // factor from the differential area at shooter.centre with normal shooter.normal to the part of
  // receiver i that is visible from there. Every receiver occludes, whether in the subset or not.
  // out.size() == receivers.size(); entries outside the subset are left untouched.
  virtual void compute(const Shooter& shooter, const ReceiverView& receivers,
                       std::span<const std::uint32_t> subset, std::span<double> out) = 0;
  // Asks the following compute() calls to keep, for every receiver i with wanted[i] != 0 (i < wanted.size()),
  // what it would have got had nothing occluded, on the same discretisation of the hemisphere (the same pixels
  // and weights), for add_unoccluded. `wanted` must stay valid until the next call; an empty span keeps nothing
  // (the default, which costs nothing). Returns false when the back end cannot.
  virtual bool keep_unoccluded(std::span<const std::uint8_t> wanted) {
    (void)wanted;
    return false;
  }
  // Adds what keep_unoccluded asked the last compute() to keep to out[i] (out.size() == receivers.size()), for the
  // receivers of its subset (others may get nothing or a part: a subset's compute() skips what cannot touch it). The
  // ratio of compute()'s factor to this one is the fraction of the receiver the back end saw, free of the back
  // end's own discretisation error (refine/near_field.h uses it). Returns false, adding nothing, when the back end
  // does not keep it.
  virtual bool add_unoccluded(std::span<double> out) const {
    (void)out;
    return false;
  }
};

// Creates the back end registered as `name` ("aa-hemicube", "hemicube", "analytic"); throws aarad::Error
// naming the known back ends when there is none, or when an option the back end uses is out of range (the
// resolution, [2, 8192], for the hemicubes; the analytic back end ignores it).
std::unique_ptr<FormFactorBackend> make_backend(std::string_view name, const BackendOptions& options = {});
std::vector<std::string> backend_names();

}  // namespace aarad::formfactor
