// The near-field correction of a shot: the shooting patch as its nearby receivers see it.
//
// A hemicube shoots from a point of the patch (its centroid, or a few Gauss points) and so gives the
// point-to-element factor F(dA_s -> e), where progressive refinement needs the patch-to-element factor
// F(A_s -> e) (Cohen, Chen, Wallace and Greenberg 1988, section 3). The two agree when the element is far from
// the patch compared with the patch's size; near it they do not. An element on a wall, just above a floor patch
// it meets, has half its hemisphere filled by that patch, while the patch's centroid sees the element edge on:
// F(dA_s -> e) tends to 0 at the junction and F(A_s -> e) does not. Every junction comes out dark, and adaptive
// substructuring follows that error instead of the radiosity: in the furnace, whose exact answer is flat, it cut
// the wall junctions down to the deepest level.
//
// The correction takes the receiver's side for the receivers near the patch, as Wallace, Elmquist and Haines
// ("A ray tracing algorithm for progressive radiosity", SIGGRAPH 1989, section 3) do for all receivers: by
// reciprocity F(A_s -> e) = F(A_e -> A_s) A_e / A_s, and for a small element F(A_e -> A_s) is the exact
// point-to-polygon factor from its centroid to the patch (Baum, Rushmeier and Winget 1989, eq. 9). The receiver's
// centroid stands for the receiver better than the patch's centroid stands for the patch when the receiver is the
// smaller of the two, even where they touch. So a receiver e whose centroid lies within `reach` times the patch's
// radius (its farthest corner from its centroid) of the patch's centroid, and whose own radius is at most 3/4 of
// the patch's radius and of its width (the least extent across it: next to a sliver the factor varies over the
// sliver's width), gets
//     G_e = v_e F(dA_e -> A_s) A_e / A_s
// (for a receiver crossing the patch's plane, A_e and the point of dA_e are the area and centroid of its part in
// front of the patch: its own centroid may lie behind the patch, or just in front at the junction), where v_e,
// the fraction of e the back end saw, is its factor over its factor with nothing occluding on the same pixels
// (FormFactorBackend::add_unoccluded; exact when the back end cannot say), clamped to [0, 1], so the back
// end's occlusion is kept and its discretisation error is not (the AA hemicube gives an element at a junction,
// seen edge on through the bottom row of a side face, about half its factor: the cosine kernel, zero at the
// horizon, varies by a factor of two across that row).
//
// A small receiver facing the patch (within 60 degrees) closer to the patch's plane than its own radius sees the
// patch's edge, where one lies across it, as a step from about 1 to about 0: it gets the mean of F(dA_x -> A_s)
// over itself, by ever finer rules from its centroid on until two agree to 1 %.
//
// A near receiver too large for its centroid to stand for it (a box's top just under a lamp, larger than the lamp)
// is shaped from the patch's side instead: G_e = v_e times the mean over the patch of F(dA_p -> e), the exact factor
// from points p of the patch, by 2 x 2 Gauss points in 1, 4, 16 and 64 cells until two rules agree to 1 % (unless
// the back end shot from 8 x 8 points or more, whose factors are as fine and occluded point by point).
//
// Energy. The shot's total stays what the back end sent (a closed scene stays balanced to the bit). The near
// field's total changes (a unit floor patch sends 0.2000 to the unit wall it meets; its centroid, 0.1901), and
// the far receivers, whose factors the centroid gives well one by one, take up the difference all in the same
// proportion: in a closed scene the patch's factors add up to 1, so what the centroid gave the near field too
// little it gave the far field too much. When that would change the far field by more than a quarter (a patch
// that sees mostly its near field), the near receivers are instead scaled to the total the back end gave them,
// and the far ones are left alone; far_refused() says so, and the solver then shoots again from more points over
// the patch (Solver::area_shooters). Receivers added by substructuring in the same shot are scaled like those of
// the whole shot; the solver then scales the pieces of each split receiver so that they share what it had
// received, except where every piece was reshaped here: those keep their own factors, and the shooter keeps the
// difference as unshot flux (refine/solver.cpp). Either way the balance holds through splits.
#pragma once

#include "aarad/core/math.h"
#include "aarad/core/quadrature.h"
#include "aarad/formfactor/backend.h"

#include <tbb/enumerable_thread_specific.h>

#include <cstdint>
#include <span>
#include <vector>

namespace aarad::refine {

// The patch that shoots, and the points the back end shot from.
struct NearFieldShooter {
  std::span<const Vec3> polygon;  // the patch, counter-clockwise seen from its front
  Vec3 centroid{0.0};
  Vec3 normal{0.0, 0.0, 1.0};
  double area = 0.0;
  std::span<const Vec3> points;    // where the back end shot from
  std::span<const double> weights;  // the points' weights, summing to 1
  // Per receiver, what the back end would have given it with nothing occluding (FormFactorBackend::
  // add_unoccluded, weighted over the points like the factors), or empty when the back end does not say: then the
  // exact unoccluded factors from the points stand in for it.
  std::span<const double> unoccluded;
};

class NearFieldCorrection {
 public:
  // Receivers whose centroid is within reach x the patch's radius (its farthest corner from its centroid) of
  // the patch's centroid are corrected; reach <= 0 turns the correction off.
  explicit NearFieldCorrection(double reach) : reach_(reach) {}

  double reach() const { return reach_; }

  // The patches of the receivers, by the view's patch id: each one's centroid and the distance from it to its
  // farthest corner. With them a shot looks only at receivers of patches that reach its near field; without
  // (empty spans), at every receiver.
  void set_patches(std::span<const Vec3> centroids, std::span<const double> radii);

  // The receivers a shot from `shooter` may correct (its polygon and centroid are read): a flag per receiver,
  // for FormFactorBackend::keep_unoccluded, so that the back end keeps their unoccluded factors and no others.
  // Valid until the next call.
  std::span<const std::uint8_t> candidates(const NearFieldShooter& shooter, const formfactor::ReceiverView& receivers);

  // Rewrites ff[i] for the near receivers among `subset` (all receivers when it is empty: a whole shot, which
  // sets the scale that later subsets of the same shot use). ff holds the back end's factors from the shooter.
  void apply(const NearFieldShooter& shooter, const formfactor::ReceiverView& receivers,
             std::span<const std::uint32_t> subset, std::span<double> ff);
  // apply() in two steps: shape() finds the near receivers and their new factors, and for a whole shot the scales,
  // reading ff only; write() then rewrites ff with them. Between the two, far_refused() tells whether the shot's
  // point could stand for the patch.
  void shape(const NearFieldShooter& shooter, const formfactor::ReceiverView& receivers,
             std::span<const std::uint32_t> subset, std::span<const double> ff);
  void write(std::span<const std::uint32_t> subset, std::span<double> ff);
  // Whether the last whole shot's far receivers could not take up its near field's change (more than kFarChange,
  // near_field.cpp): the near field then keeps the back end's total, and the points shot from saw too little of the
  // rest of the scene to stand for the patch.
  bool far_refused() const { return far_refused_; }
  // The last whole shot's total of the back end's factors, and their total over its near receivers.
  double shot_total() const { return shot_total_; }
  double near_back_end_total() const { return near_back_end_; }

  // Receivers the last apply() corrected.
  std::span<const std::uint32_t> last_corrected() const { return near_; }
  // The factors of the last whole shot: the near receivers' (1 unless the far field could not take up their
  // change) and the far receivers' (1 when there was no near receiver).
  double near_scale() const { return scale_; }
  double far_scale() const { return far_scale_; }

 private:
  double reach_;
  double scale_ = 1.0;
  double far_scale_ = 1.0;
  bool far_refused_ = false;
  double near_back_end_ = 0.0, shot_total_ = 0.0;
  std::vector<Vec3> patch_centroid_;
  std::vector<double> patch_radius_;
  // Flags the patches that may hold a near receiver of a shot from `shooter` (all, without a table of patches);
  // returns the shooter's radius.
  double mark_near_patches(const NearFieldShooter& shooter);
  bool near_patch(std::uint32_t patch) const {
    return patch_centroid_.empty() || (patch < near_patch_.size() && near_patch_[patch] != 0);
  }

  std::vector<std::uint8_t> near_patch_;  // per patch id: 1 when it may hold near receivers (this shot)
  // The shooter near_patch_ was marked for (its centroid and radius; radius -1 when none): a shot marks the patches
  // once for candidates() and every apply() of its whole shot and its subsets.
  Vec3 marked_centroid_{0.0};
  double marked_radius_ = -1.0;
  std::vector<std::uint8_t> candidate_;   // per receiver: candidates()
  // The receivers candidates() flagged, in order, for the view of revision listed_revision_ with listed_size_
  // receivers and the shooter marked then (listed_revision_ is 0 when a later marking made them stale): apply() to
  // a whole shot of that view looks at these instead of at every receiver.
  std::vector<std::uint32_t> listed_;
  std::uint64_t listed_revision_ = 0;
  std::size_t listed_size_ = 0;
  // The view's receivers grouped by patch id (the receivers of patch p: by_patch_[patch_start_[p] ..
  // patch_start_[p + 1]), in receiver order), for the view of revision indexed_revision_ and indexed_size_
  // receivers; made again when the view changed.
  void index_patches(const formfactor::ReceiverView& receivers);
  std::vector<std::uint32_t> patch_start_, by_patch_;
  std::uint64_t indexed_revision_ = 0;
  std::size_t indexed_size_ = 0;
  std::vector<std::uint32_t> near_patches_;
  std::vector<std::uint32_t> near_;
  std::vector<std::uint8_t> near_flag_;  // per receiver: 1 while it is in near_ (all 0 between calls)
  std::vector<double> shaped_;  // per near receiver: G
  // One thread's room for shaping receivers: polygons in a frame, clipped, and the part in front of the patch; the
  // rule over a receiver.
  struct Scratch {
    std::vector<Vec3> local, clipped, front;
    std::vector<AreaSample> receiver_points;
  };
  tbb::enumerable_thread_specific<Scratch> scratch_;
  // Per receiver looked at by shape(), in its order: what shaping found (shape_receiver).
  struct Shaped {
    enum : std::uint8_t { kLeft, kShaped, kFromPatch } state = kLeft;
    double value = 0.0;  // G; for kFromPatch the fraction seen, which the patch's average multiplies
  };
  std::vector<Shaped> found_;
  Shaped shape_receiver(const NearFieldShooter& shooter, const formfactor::ReceiverView& receivers, std::uint32_t i,
                        std::span<const double> ff, double near_squared, double size, Scratch& scratch) const;
  // The factor with nothing occluding from the patch to `polygon`, averaged over the patch by ever finer rules
  // (patch_points_, made before).
  double patch_average(const NearFieldShooter& shooter, std::span<const Vec3> polygon, Scratch& scratch) const;
  // The factor with nothing occluding from `part` of a receiver (its centroid and unit normal given) to the patch,
  // averaged over the part by ever finer rules from its centroid on, which stop when two agree.
  static double receiver_average(const NearFieldShooter& shooter, std::span<const Vec3> part, const Vec3& centroid,
                                 const Vec3& normal, Scratch& scratch);
  // The rules over the shooting patch, by level: made in one go when a large receiver needs them, then read by the
  // threads that shape.
  std::vector<std::vector<AreaSample>> patch_points_;
};

}  // namespace aarad::refine
