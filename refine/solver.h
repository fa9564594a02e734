// Progressive-refinement radiosity with adaptive substructuring.
//
// Shooting: M. F. Cohen, S. E. Chen, J. R. Wallace and D. P. Greenberg, "A progressive refinement approach
// to fast radiosity image generation", SIGGRAPH 1988, section 3. Substructuring (patches shoot, elements
// receive, elements split where radiosity changes fast): M. F. Cohen, D. P. Greenberg, D. S. Immel and
// P. J. Brock, "An efficient radiosity approach for realistic image synthesis", IEEE CG&A 1986.
// The formulas, the options and their defaults are documented in docs/solver.md.
#pragma once

#include "aarad/core/rgb.h"
#include "aarad/core/scene.h"
#include "aarad/formfactor/backend.h"
#include "aarad/mesh/hierarchy.h"
#include "aarad/refine/factor_cache.h"
#include "aarad/refine/near_field.h"
#include "aarad/refine/neighbour_table.h"
#include "aarad/refine/receiver_cache.h"

#include <tbb/task_group.h>

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace aarad::refine {

struct SolverOptions {
  std::string backend = "aa-hemicube";  // form-factor back end, see formfactor::backend_names()
  int resolution = 100;                 // hemicube pixels along the full top face
  double converge = 0.01;               // stop when unshot flux < converge * emitted flux (channel sums)
  std::int64_t max_shots = 100000;      // stop after this many shots
  bool adaptive = true;                 // adaptive substructuring on radiosity gradients
  // Split a leaf when the luminance of its radiosity differs from an edge-neighbour's by more than
  // gradient times the largest reflected radiosity luminance (B - E) of any leaf.
  double gradient = 0.1;
  // Overrelaxation factor w of the shooting step: the shooter sends w dB_s and keeps (1 - w) dB_s (Gortler,
  // Cohen and Slusallek 1994; progressive refinement is Southwell iteration). 1 is the paper's plain
  // progressive refinement; values in (1, 2) overshoot, which converges in fewer shots (docs/solver.md).
  double relaxation = 1.0;
  // Ambient overshooting (Feda and Purgathofer 1992): the shooter also sends rho_s times the ambient term of
  // the unshot radiosity (Cohen et al. 1988; docs/solver.md), an estimate of what it will receive later, and
  // keeps its negative.
  // Off by default (the paper's method); on, the office converges in a third of the shots (docs/solver.md).
  bool overshoot = false;
  // Gauss-Legendre points per direction on the shooting patch: 1 shoots from the centroid (the paper's
  // method); n > 1 averages the back end's point factors over n x n points, approximating the
  // patch-to-element form factor (used to check the loop against closed-form patch-to-patch values).
  int shooter_samples = 1;
  // Near-field correction (refine/near_field.h): receivers within this many patch radii of the shooting patch's
  // centroid, and smaller than it (a radius at most 3/4 of its radius and of its width), take the shape of their
  // share from the patch's exact factor seen from their centroid; 0 turns it off (the paper's method: every factor
  // from the shooting point).
  double near_field = 4.0;
  // Memory, in MiB, for the form factors of each patch's last shot (refine/factor_cache.h): a patch that shoots
  // again takes them, shooting only into the leaves split since, whose pieces share the factor the leaf had. The
  // least recently used patches' factors are given up beyond it; 0 computes every shot afresh (docs/solver.md).
  std::int64_t factor_cache_mib = 2048;
  // The most leaf elements adaptive substructuring may make: a split that would take the leaf count beyond it (with
  // the coarser neighbours `balance` would split first) is refused, as one below min_area is, and the solve goes on
  // with the mesh it has (element_limit_reached()). It bounds memory, about 1 KiB per leaf besides the factor cache
  // (docs/solver.md, "Adaptive substructuring"): at 3 million a solve peaked at 3.6 GiB (4 million needed more than
  // 6 GB of address space). The initial meshing has its own limit (MeshingOptions::max_initial_elements); initial
  // elements beyond this one are kept, and none splits.
  std::int64_t max_elements = 3'000'000;
  // Patch and element sizes, max level, min area, balance. The default is the hierarchy's (zeros: sizes relative
  // to the scene's diagonal), not what `aarad solve` uses for a scene that names its sizes (the built-in Cornell
  // box and office, an OBJ file with "# aarad meshing:"): set it to default_meshing(scene) to solve as the program
  // does (on the Cornell box 1 040 initial elements and 1 154 leaves at the end, against 1 332 and 2 190).
  mesh::MeshingOptions meshing;
};

// The meshing defaults aarad uses for a scene: the sizes its author chose (Scene::meshing: the built-in
// Cornell box and office, and OBJ files with a "# aarad meshing:" comment, such as their copies in
// data/scenes/), otherwise the hierarchy's own defaults (zeros).
mesh::MeshingOptions default_meshing(const Scene& scene);

// run() stops when the net unshot flux, sum dB A with its sign (unshot_flux()), exceeds this many times the emitted
// flux either way, or is not finite. It starts at the emitted flux and is what has been neither absorbed nor lost
// from the scene: emitted - absorbed - escaped. In a closed scene whose form factors from every point add up to at
// most 1 it never passes the emitted flux: plain shooting only lowers it, and over-relaxation and overshooting,
// whose negative dB are flux to be taken back, do not lift it either. (Summed with |dB|, as unshot_fraction() is,
// it can: overshooting leaves each shooter -rho x ambient, about 2 rho / (1 - rho) times what is left in all, 65
// times at rho = 0.97.) It grows without end where factors add up to more than 1, which makes flux out of nothing,
// and with overshooting in an open scene, whose ambient term (a closed scene's) sends out more than comes back.
inline constexpr double kDivergedUnshot = 10.0;

struct Progress {
  std::int64_t shots = 0;
  double unshot_fraction = 1.0;
  std::size_t elements = 0;
  double seconds = 0.0;
};

struct SolverTimes {
  double form_factors = 0.0;  // inside the back end (every shot and every substructuring recomputation)
  double subdivision = 0.0;   // gradient tests, splits, receiver-view rebuilds and the corrections
  double total = 0.0;         // the whole of run(), including the two above
};

class Solver {
 public:
  // `scene` must outlive the solver and its hierarchy, which reads it without a copy. Builds the hierarchy, sets
  // B = E for every node and dB = E for every patch, and creates the back end by name (throws aarad::Error for
  // unknown names or bad options).
  Solver(const Scene& scene, const SolverOptions& options);
  // With a caller-supplied back end (tests, custom back ends).
  Solver(const Scene& scene, const SolverOptions& options, std::unique_ptr<formfactor::FormFactorBackend> backend);
  // The solver keeps a reference to the scene, so a temporary one (Solver(load_scene("cornell"), options)) would
  // dangle as soon as the constructor returns: keep the scene in a variable.
  Solver(Scene&& scene, const SolverOptions& options) = delete;
  Solver(Scene&& scene, const SolverOptions& options, std::unique_ptr<formfactor::FormFactorBackend> backend) = delete;
  ~Solver();
  Solver(const Solver&) = delete;
  Solver& operator=(const Solver&) = delete;

  // One shot from the patch with the largest unshot flux, then substructuring. Returns false (and does
  // nothing) when no patch has unshot flux left. Unlike run() it ignores converge and max_shots, leaves
  // converged(), interrupted() and times().total as they were, and leaves inner nodes' B stale: until pull_up(),
  // check_invariants reports them ("radiosity-mean").
  bool shoot_once();

  // Shoots until converged, max_shots, or `keep_going` returns false (checked after every shot; it also
  // reports progress). Sets converged() / interrupted() and the times. When keep_going or a back end throws, the
  // exception passes on, and the solution so far stays readable and balanced: interrupted() is true, inner nodes
  // are pulled up, the times are counted, and every split leaf's share is either taken back and re-shot or kept.
  void run(const std::function<bool(const Progress&)>& keep_going = {});

  // The patch the last shot came from (run()'s or shoot_once()'s), kNoNode before the first shot.
  mesh::NodeId last_shooter() const { return last_shooter_; }

  bool converged() const { return converged_; }
  bool interrupted() const { return interrupted_; }
  // Whether run() stopped because the net unshot flux grew past kDivergedUnshot times the emitted flux: form factors
  // from a patch that add up to more than 1 (the analytic back end ignores what hides one surface from another)
  // feed back more than they absorb, and the loop never converges.
  bool diverged() const { return diverged_; }
  std::int64_t shots() const { return shots_; }

  // Fluxes per channel (radiosity x area): emitted sum E A; absorbed so far sum (1 - rho) x incident flux;
  // unshot sum over patches dB A. With exact, closed form factors absorbed + unshot == emitted.
  Rgb emitted_flux() const { return emitted_flux_; }
  Rgb absorbed_flux() const { return absorbed_flux_; }
  Rgb unshot_flux() const;
  // What left the scene: emitted - absorbed - unshot. It is the flux shot past every receiver (an open scene,
  // or faces turned away from the light; faces are one-sided) plus the back end's quantisation; in a closed
  // scene it is about 1e-6 of the emitted flux with the hemicubes at N = 100 and zero with exact form factors.
  Rgb escaped_flux() const { return emitted_flux_ - absorbed_flux_ - unshot_flux(); }
  // Unshot flux over emitted flux, both summed over channels (0 when nothing emits). The unshot flux is taken
  // as sum |dB| A over patches and channels: with overrelaxation or overshooting dB can be negative, and that is
  // flux still to be taken back. Without it every dB >= 0 and this is unshot_flux().sum() / emitted.
  double unshot_fraction() const;
  // The net unshot flux over the emitted flux, both summed over channels, dB taken with its sign: what the solve has
  // not absorbed yet (escaped_flux() aside). run() stops as diverged when it passes kDivergedUnshot either way.
  double net_unshot_fraction() const;

  // The display-only ambient term of Cohen et al. 1988 (docs/solver.md) and each leaf's displayed radiosity
  // B + rho * ambient, indexed by NodeId (inner nodes hold their B).
  Rgb ambient() const;
  std::vector<Rgb> displayed_radiosity() const;
  // B per NodeId without the ambient term; inner nodes hold the area-weighted mean of their leaves.
  std::vector<Rgb> radiosity() const;

  const Scene& scene() const { return scene_; }
  const SolverOptions& options() const { return options_; }
  const mesh::Hierarchy& hierarchy() const { return hierarchy_; }
  mesh::Hierarchy& hierarchy() { return hierarchy_; }
  const formfactor::FormFactorBackend& backend() const { return *backend_; }
  const SolverTimes& times() const { return times_; }
  int max_leaf_level() const;
  // Number of leaves split by substructuring so far (balancing splits included).
  std::int64_t splits() const { return splits_; }
  // Whether substructuring refused a split because the leaves would have been more than SolverOptions::max_elements.
  bool element_limit_reached() const { return element_limit_reached_; }
  // Shots that took their patch's factors from its previous shot (SolverOptions::factor_cache_mib), and the
  // memory those factors take now.
  std::int64_t reused_shots() const { return reused_shots_; }
  // Patches that shoot from points over their area since their centroid could not stand for them: the rest of the
  // scene took up too little of what it saw to keep a shot's total once its near field was corrected
  // (NearFieldCorrection::far_refused).
  std::int64_t area_shooters() const { return area_shooters_; }
  std::size_t factor_cache_bytes() const { return factor_cache_.bytes(); }

  // Sets every inner node's B to the area-weighted mean of its children (bottom-up). run() calls it at the
  // end; call it after driving shoot_once() by hand before reading inner nodes.
  void pull_up();

 private:
  void initialise();
  // What the loop asks of the patches between two shots, in a pass over them (in patches() order; a second one with
  // overshooting): the unshot fraction, the shooter (the largest unshot flux sum |dB| A over channels, or with
  // overshooting the largest flux a shot would send, sum |w dB + rho x ambient| A; ties to the lowest id; kNoNode
  // when none is left) and the ambient term.
  struct PatchScan {
    double unshot_fraction = 0.0;      // sum |dB| A / emitted flux (unshot_fraction())
    double net_unshot_fraction = 0.0;  // sum dB A / emitted flux (net_unshot_fraction())
    mesh::NodeId shooter = mesh::kNoNode;
    Rgb ambient{};
  };
  PatchScan scan_patches() const;
  // shoot_once() with the scan of the current state.
  bool shoot(const PatchScan& scan);
  // Fills ff_ for the receivers in `subset` (all when empty), averaging over the shooter's sample points.
  void compute_form_factors(mesh::NodeId shooter, std::span<const std::uint32_t> subset);
  // A whole shot from a patch with a row in factor_cache_: puts the row's back-end factors into ff_ (and its
  // unoccluded ones into unoccluded_ when `unoccluded`), the factors of the leaves split since into
  // received_factor_, and their leaves now into subset_, which it returns.
  std::span<const std::uint32_t> factors_from_row(const FactorRow& row, bool unoccluded);
  // The points per side a shot tried before its current ones (compute_form_factors), and the near field's back-end
  // total from them (-1 before any).
  struct AreaPointsTrial {
    double previous_near;
    int previous_samples;
  };
  bool choose_area_points(mesh::NodeId shooter, AreaPointsTrial& trial);
  bool back_end_factors(std::span<const Vec3> points, std::span<const double> weights, const Vec3& normal,
                        std::span<const std::uint32_t> shot, bool kept, std::vector<double>& unoccluded);
  // Keeps the back end's factors of a whole shot (row_ff_, and unoccluded_ of the near-field candidates), made from
  // `samples` points per side, as the shooter's row; called with the factor cache enabled.
  void keep_row(mesh::NodeId shooter, std::span<const std::uint8_t> candidates, int samples);
  // Whether a row keeps receiver i's unoccluded factor: a near-field candidate that got a factor, with the back end
  // keeping those.
  bool kept_near(std::uint32_t i, std::span<const std::uint8_t> candidates) const;
  // The same after a shot that reused the shooter's row, from that row: only the entries of the leaves split since
  // (split_entries_) change.
  void update_row(mesh::NodeId shooter, std::span<const std::uint8_t> candidates);
  const Material& material(mesh::NodeId node) const;
  void receive(mesh::NodeId leaf, const Rgb& incident, double sign);
  struct Deposit;
  struct SurfaceShading;
  // Adds rho x incident to the leaf's B and its patch's dB (scaled by the inverse areas of d) in the node arrays
  // (hierarchy_.radiosities() and unshots()), and sign x (1 - rho) x incident to `absorbed` (the absorbed flux),
  // rho being the reflectance of the leaf's surface, `shading`. Returns the leaf's new B. Static and inline, so
  // that a shot's loop of deposits keeps its sums in registers.
  static const Rgb& deposit(const Deposit& d, const SurfaceShading& shading, const Rgb& incident, double sign,
                            std::span<Rgb> radiosity, std::span<Rgb> unshot, Rgb& absorbed);
  // The luminance of B - E for a leaf of the surface with `shading` whose B has luminance `luminance`.
  static double reflected_luminance(const Rgb& b, double luminance, const SurfaceShading& shading);
  // The loop of run(): shoots until converged, max_shots, or keep_going returns false. Progress reports the time
  // since `start` plus `total_before`.
  void shooting_loop(const std::function<bool(const Progress&)>& keep_going, std::chrono::steady_clock::time_point start,
                     double total_before);
  // Splits where the shot made radiosity change fast, and re-shoots into the new leaves (see solver.cpp).
  void substructure(mesh::NodeId shooter, const Rgb& shot_flux);
  // Its steps: the leaves whose luminance steps too far from a neighbour's, among those this shot reached, then
  // among the leaves a round of splits made; the splits; the split leaves' share of the shot taken back.
  std::vector<mesh::NodeId> steep_leaves_of_shot();
  std::vector<mesh::NodeId> steep_leaves_among(std::span<const mesh::NodeId> new_leaves);
  std::vector<mesh::NodeId> split_candidates(std::span<const mesh::NodeId> candidates);
  // Whether split(candidate) keeps the leaf count within SolverOptions::max_elements.
  bool split_fits_element_limit(mesh::NodeId candidate);
  // Copies the factors of the receivers the shot reached (touched_, ff_) into received_factor_, by leaf.
  void record_shot_factors();
  void take_back_split_shares(std::span<const mesh::NodeId> split_nodes, mesh::NodeId first_new,
                              std::span<const mesh::NodeId> new_leaves, const Rgb& shot_flux);
  // The node or ancestor of `node` that was a leaf when the hierarchy had `count` nodes (node ids only grow, and a
  // split leaf's pieces come after it).
  mesh::NodeId leaf_among_first(mesh::NodeId node, mesh::NodeId count) const;
  // Per ancestor of `pieces` (receivers, with their ancestors), a slot in share_slot_ holding the pieces' total
  // factor (from ff_) and area in share_total_ and share_area_, summed in the pieces' order, and the ancestor in
  // share_leaf_. The caller puts the ancestors' slots back to kNoSlot.
  void sum_pieces(std::span<const std::uint32_t> pieces, std::span<const mesh::NodeId> ancestors);
  // After the near-field correction: scales the new leaves of every split leaf so that together they get the factor
  // it had received. With keep_reshaped (a shot's own substructuring), the pieces of a leaf that the correction
  // reshaped all keep their own factors instead; returns what those leaves had over their pieces' total, which
  // the caller gives back to the shooter (see solver.cpp).
  double share_out_split_factors(mesh::NodeId first_new, bool keep_reshaped);
  // Moves the shooter's earlier shots (history_flux_) among the pieces of each leaf split since it last shot, by
  // their factors of this shot in ff_ (see solver.cpp). `received`: the flux of this shot when the pieces already
  // hold their share of it (in the shot's own substructuring), which a piece keeps whatever it gives back.
  void share_out_history(std::span<const std::uint32_t> pieces, std::span<const mesh::NodeId> ancestors,
                         const Rgb& received = Rgb{});
  // Makes luminance_ and largest_reflected_ current for the receiver view (and deposits_ with them).
  void update_luminance();
  // Rebuilds deposits_ when the receiver view changed.
  void update_deposits();
  // Sets every receiver's slack_ to -infinity (to be tested) and drift_ to 0.
  void forget_slack();

  const Scene& scene_;
  SolverOptions options_;
  mesh::Hierarchy hierarchy_;
  // Per patch, in patches() order: what scan_patches() reads besides dB (none of it changes).
  struct PatchEntry {
    mesh::NodeId node;
    double area;
    Rgb reflectance;
  };
  std::vector<PatchEntry> patch_table_;
  // The ambient term's sums that do not change, sum rho_i A_i and sum A_i over patch_table_, in its order.
  Rgb patch_reflectance_area_{};
  double patch_area_ = 0.0;
  std::unique_ptr<formfactor::FormFactorBackend> backend_;
  ReceiverCache cache_;
  double shooter_lift_ = 0.0;  // how far a shooting point is lifted off its surface (compute_form_factors)

  std::vector<double> ff_;         // per receiver: form factor of the current shot
  std::vector<double> ff_sample_;  // per receiver: one sample point's factors
  NearFieldCorrection near_field_;
  FactorCache factor_cache_;
  std::int64_t reused_shots_ = 0;
  std::vector<double> unoccluded_;         // per receiver: the back end's factors with nothing occluding
  std::vector<double> unoccluded_sample_;  // the same, for one sample point
  std::vector<double> unoccluded_shot_;    // the same, for the leaves a reused row shoots into
  // Per NodeId: the form factor of the current shot to the node when it received (leaves); the flux it received
  // is the shot's flux times this factor. Only substructuring reads it, and only after a split: the shot's own
  // factors are copied in from ff_ then (record_shot_factors), not by every shot's deposit loop.
  std::vector<double> received_factor_;
  // share_out_split_factors' and share_out_history's work: per piece of the subset its split leaf; per node a split
  // leaf's slot (kNoSlot between calls); per slot the pieces' total factor and area, and the leaf (sum_pieces).
  static constexpr std::uint32_t kNoSlot = 0xffffffffu;
  std::vector<mesh::NodeId> piece_ancestor_;
  std::vector<std::uint32_t> share_slot_;
  std::vector<double> share_total_, share_area_;
  std::vector<mesh::NodeId> share_leaf_;
  // share_out_split_factors(keep_reshaped): per receiver, 1 while the near-field correction reshaped it (0 between
  // calls); per slot, 1 when the pieces keep their own factors.
  std::vector<std::uint8_t> reshaped_flag_, share_own_;
  // share_out_history's state: per patch (by NodeId) the flux it has shot so far and the hierarchy's node count
  // after its last shot; the current shooter's flux before this shot; scratch: the pieces, their ancestors, their
  // changes of B, and per ancestor's slot the part of the changes applied.
  std::vector<Rgb> shot_so_far_;
  std::vector<mesh::NodeId> nodes_after_shot_;
  // Per node, for the patches whose centroid could not stand for them (compute_form_factors), the points per side
  // they shoot from; 0 for the others. The points per side of the current shot, and how many patches shoot from
  // more points than the options ask. More points are tried until the far field takes up the near field's change,
  // or they change the near field's total by at most kAreaPointsChange of the shot.
  static constexpr double kAreaPointsChange = 0.01;
  std::vector<std::uint8_t> area_samples_;
  int shot_samples_ = 1;
  std::int64_t area_shooters_ = 0;
  Rgb history_flux_{};
  std::vector<std::uint32_t> history_pieces_;
  std::vector<mesh::NodeId> history_ancestor_;
  std::vector<Rgb> history_change_;
  std::vector<double> share_scale_;
  std::vector<mesh::NodeId> factor_written_;  // the nodes whose received_factor_ the current shot set
  // Per NodeId: 1 when the hierarchy refused to split the node (deepest level, smallest area, or already split).
  // A leaf's refusal never changes (its level and corners stay), and such leaves come back as split candidates
  // shot after shot: the refusal is asked once instead of recomputing the children's areas every time.
  std::vector<std::uint8_t> refused_;
  // split_fits_element_limit's scratch: the leaves a split with balancing would split first.
  std::vector<mesh::NodeId> forced_;
  // The receivers that got flux from the current shot: the first touched_count_ entries (the vector only grows).
  std::vector<std::uint32_t> touched_;
  std::size_t touched_count_ = 0;
  std::vector<std::uint32_t> subset_;
  std::vector<std::size_t> split_entries_;  // factors_from_row: the row's entries of leaves split since
  std::vector<mesh::NodeId> split_leaves_, leaf_stack_;  // factors_from_row: scratch for leaves_under
  // Per receiver: edge-neighbours (receiver indices).
  NeighbourTable neighbours_;
  // Per receiver, valid for revision deposits_revision_: what a shot needs to deposit flux on it besides its
  // surface's material, with the areas' inverses (times the sign of the deposit when receive() builds one).
  // 24 bytes: the deposit loop reads it for nearly every receiver in every shot, from memory the hemicube's
  // tasks have used in between.
  struct Deposit {
    double inverse_area = 0.0;        // 1 / A_e
    double inverse_patch_area = 0.0;  // 1 / A_j of its patch
    mesh::NodeId leaf = 0;
    mesh::NodeId patch = 0;
  };
  std::vector<Deposit> deposits_;
  // Per surface (the receivers' surfaces() index it): its material's reflectance rho and emission E, and whether
  // E differs from +0 in some channel (when it does not, B - E is B bit for bit, and so is its luminance).
  struct SurfaceShading {
    Rgb reflectance;
    Rgb absorptance;  // 1 - rho
    Rgb emission;
    bool emits = false;
  };
  std::vector<SurfaceShading> shading_;
  std::uint64_t deposits_revision_ = ~std::uint64_t{0};
  const mesh::Hierarchy::Impl* deposits_source_ = nullptr;
  // Per receiver, for substructuring: radiosity luminance, and 1 when it is to be split. The luminances and the
  // largest reflected luminance max (B - E) over all receivers are current for revision luminance_revision_.
  static constexpr std::uint64_t kNoRevision = ~std::uint64_t{0};
  std::vector<double> luminance_;
  double largest_reflected_ = 0.0;
  std::uint64_t luminance_revision_ = kNoRevision;
  const mesh::Hierarchy::Impl* luminance_source_ = nullptr;
  bool luminance_current() const {
    return luminance_revision_ == cache_.revision() && luminance_source_ == &hierarchy_.impl();
  }
  std::vector<std::uint8_t> candidate_flag_;
  // The back end's factors of the current whole shot, for keep_row and update_row, which run on row_task_ while
  // ff_ takes the near-field correction. A reused shot also lists its near-field candidates on row_task_ while it
  // reads its row (and waits for them there).
  std::vector<double> row_ff_;
  // update_row's scratch, on row_task_: leaves_under's, the entries left vacant, the pieces placed after them.
  std::vector<mesh::NodeId> row_leaves_, row_stack_;
  std::vector<std::size_t> row_vacant_;
  std::vector<std::pair<mesh::NodeId, double>> row_extra_;
  std::unique_ptr<tbb::task_group> row_task_ = std::make_unique<tbb::task_group>();
  bool row_pending_ = false;
  // Waits for the row task, if one runs: before anything it reads changes (the leaves, the factor cache).
  void wait_for_row();
  // Per receiver r, for the gradient test of steep_leaves_of_shot: slack_[r] - drift_ is at most how far below the
  // threshold the widest luminance step from r to a neighbour lies. Tested receivers set their slack; drift_ sums the
  // largest luminance rise of each shot since the luminance table was made (which sets every slack to -infinity).
  std::vector<double> slack_;
  double drift_ = 0.0;
  std::uint32_t drift_shots_ = 0;  // shots summed in drift_

  Rgb emitted_flux_{};
  Rgb absorbed_flux_{};
  std::int64_t shots_ = 0;
  mesh::NodeId last_shooter_ = mesh::kNoNode;
  std::int64_t splits_ = 0;
  bool element_limit_reached_ = false;
  bool converged_ = false;
  bool diverged_ = false;
  bool interrupted_ = false;
  SolverTimes times_;
};

}  // namespace aarad::refine
