// Progressive-refinement radiosity (Cohen, Chen, Wallace and Greenberg 1988, section 3) with adaptive
// substructuring (Cohen, Greenberg, Immel and Brock 1986, section 3): the loop of ../shared/references.md.
//
// One shot: the patch s with the largest unshot flux dB_s A_s (summed over the three channels) shoots from its
// centroid; every leaf element e on patch j not in s's plane receives the incident flux dB_s F(s->e) A_s per
// channel, of which rho_j reflects: B_e += rho_j dB_s F A_s / A_e and dB_j += rho_j dB_s F A_s / A_j; the rest
// is absorbed. Then dB_s = 0, or with overrelaxation w (Gortler, Cohen and Slusallek, "Radiosity and relaxation
// methods", IEEE CG&A 1994) s shoots w dB_s and keeps (1 - w) dB_s; with ambient overshooting (Feda and
// Purgathofer, "Accelerating radiosity by overshooting", Eurographics Workshop on Rendering 1992) s also shoots
// rho_s x ambient and keeps minus that.
// Substructuring after the shot: a leaf whose radiosity luminance differs from an edge-neighbour's by more than
// `gradient` times the largest reflected luminance (B - E) is split; its new leaves drop the parent's share of
// this shot (they inherited the parent's B), get their own share from the back end (subset = new leaves, all
// receivers occluding), and the patch's unshot radiosity and the absorbed flux are corrected the same way.
// The new leaves are tested again until nothing splits.
#include "aarad/refine/solver.h"

#include "aarad/core/error.h"
#include "aarad/core/quadrature.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>
#include <string>
#include <tuple>
#include <utility>

namespace aarad::refine {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// The points a shot from the patch with `corners` is made from, with their weights: its centroid for one point per
// side, else samples x samples Gauss points; each lifted by `lift` (compute_form_factors).
void shooting_points(std::span<const Vec3> corners, const Vec3& centroid, const Vec3& lift, int samples,
                     std::vector<Vec3>& points, std::vector<double>& weights) {
  points.clear();
  weights.clear();
  if (samples <= 1) {
    points.push_back(centroid + lift);
    weights.push_back(1.0);
    return;
  }
  for (const AreaSample& sample : polygon_quadrature(corners, samples)) {
    points.push_back(sample.position + lift);
    weights.push_back(sample.weight);
  }
}

// The points per side to try after `samples` when they could not stand for the patch (compute_form_factors); 0
// when there are no more to try.
int more_area_points(int samples) {
  if (samples < 3) return 3;
  if (samples < 5) return 5;
  return 0;
}

// The largest factor cache (SolverOptions::factor_cache_mib), a pebibyte: its size in bytes fits any size_t.
constexpr std::int64_t kLargestFactorCacheMib = std::int64_t{1} << 30;

// How far a shooting point is lifted off its surface (compute_form_factors): 1e-9 of the scene's diagonal, and
// at least 16 units in the last place of the scene's largest coordinate. The centroid and the plane are only known
// to a few of those units, and far from the origin they exceed the first: in a closed cube of side 0.7 at
// (1e7, 3e6, 0) a patch's factors summed to 1 - 2.3e-7, with the lift a rounding error of the point.
double shooter_lift(const Scene& scene) {
  const Vec3 lo = glm::abs(scene.bounds_min()), hi = glm::abs(scene.bounds_max());
  const double largest = std::max({lo.x, lo.y, lo.z, hi.x, hi.y, hi.z});
  return std::max(1e-9 * scene.diagonal(), 16.0 * std::numeric_limits<double>::epsilon() * largest);
}

}  // namespace

mesh::MeshingOptions default_meshing(const Scene& scene) {
  mesh::MeshingOptions options;
  if (scene.meshing) {
    options.patch_size = scene.meshing->patch_size;
    options.element_size = scene.meshing->element_size;
    options.min_area = scene.meshing->min_area;
  }
  return options;
}

Solver::Solver(const Scene& scene, const SolverOptions& options)
    : Solver(scene, options,
             formfactor::make_backend(options.backend, formfactor::BackendOptions{options.resolution})) {}

Solver::Solver(const Scene& scene, const SolverOptions& options,
               std::unique_ptr<formfactor::FormFactorBackend> backend)
    : scene_(scene),
      options_(options),
      // The scene outlives the solver (solver.h): the hierarchy shares it, through a pointer that owns nothing.
      hierarchy_(std::shared_ptr<const Scene>(std::shared_ptr<const Scene>(), &scene), options.meshing),
      backend_(std::move(backend)),
      shooter_lift_(shooter_lift(scene)),
      near_field_(options.near_field),
      factor_cache_(options.factor_cache_mib > 0 && options.factor_cache_mib <= kLargestFactorCacheMib
                        ? static_cast<std::size_t>(options.factor_cache_mib) << 20
                        : 0) {
  // Library callers set SolverOptions fields, `aarad solve` users the options: the messages name both.
  const auto refuse = [](const std::string& field, const std::string& option, const std::string& range, double value) {
    std::ostringstream message;
    message << "solver: SolverOptions::" << field << " (" << option << ") must be " << range << ", got " << value;
    throw Error(message.str());
  };
  if (!backend_) throw Error("solver: no form-factor back end");
  if (!(options_.converge >= 0.0)) refuse("converge", "--converge", ">= 0", options_.converge);
  if (options_.max_shots < 0) refuse("max_shots", "--max-shots", ">= 0", static_cast<double>(options_.max_shots));
  if (!(options_.gradient > 0.0)) refuse("gradient", "--gradient", "> 0", options_.gradient);
  if (!(options_.relaxation >= 1.0 && options_.relaxation < 2.0)) {
    refuse("relaxation", "--relaxation", "in [1, 2)", options_.relaxation);
  }
  if (options_.shooter_samples < 1 || options_.shooter_samples > 64) {
    refuse("shooter_samples", "--shooter-samples", "in [1, 64]", options_.shooter_samples);
  }
  if (!(options_.near_field >= 0.0)) refuse("near_field", "--near-field", ">= 0", options_.near_field);
  if (options_.factor_cache_mib < 0 || options_.factor_cache_mib > kLargestFactorCacheMib) {
    refuse("factor_cache_mib", "--factor-cache", "in [0, 1073741824]", static_cast<double>(options_.factor_cache_mib));
  }
  if (options_.max_elements < 1) {
    refuse("max_elements", "--max-elements", ">= 1", static_cast<double>(options_.max_elements));
  }
  initialise();
}

Solver::~Solver() = default;

const Material& Solver::material(mesh::NodeId node) const {
  return scene_.material_of_surface(hierarchy_.surface(node));
}

void Solver::initialise() {
  // Cohen et al. 1988: B = E and dB = E for emitters, at patches and elements alike.
  const std::size_t nodes = hierarchy_.node_count();
  for (mesh::NodeId node = 0; node < nodes; ++node) {
    hierarchy_.radiosity(node) = material(node).emission;
    hierarchy_.unshot(node) = Rgb{};
  }
  emitted_flux_ = Rgb{};
  patch_table_.clear();
  for (mesh::NodeId patch : hierarchy_.patches()) {
    const Rgb& emission = material(patch).emission;
    hierarchy_.unshot(patch) = emission;
    emitted_flux_ += emission * hierarchy_.area(patch);
    patch_table_.push_back({patch, hierarchy_.area(patch), material(patch).reflectance});
  }
  patch_reflectance_area_ = Rgb{};
  patch_area_ = 0.0;
  for (const PatchEntry& patch : patch_table_) {
    patch_reflectance_area_ += patch.reflectance * patch.area;
    patch_area_ += patch.area;
  }
  absorbed_flux_ = Rgb{};
  shading_.clear();
  const auto positive_zero = [](double e) { return e == 0.0 && !std::signbit(e); };  // B - (-0) is not B when B is -0
  for (std::uint32_t surface = 0; surface < scene_.surfaces.size(); ++surface) {
    const Material& m = scene_.material_of_surface(surface);
    const Rgb& e = m.emission;
    shading_.push_back({m.reflectance, Rgb(1.0) - m.reflectance, e,
                        !(positive_zero(e.r) && positive_zero(e.g) && positive_zero(e.b))});
  }
  received_factor_.assign(nodes, 0.0);
  shot_so_far_.assign(nodes, Rgb{});
  nodes_after_shot_.assign(nodes, 0);
  area_samples_.assign(nodes, 0);
  area_shooters_ = 0;
  // The near-field correction's table of patches, by patch id (the receivers' patch ids are the patches' nodes).
  mesh::NodeId last_patch = 0;
  for (mesh::NodeId patch : hierarchy_.patches()) last_patch = std::max(last_patch, patch);
  std::vector<Vec3> centroids(hierarchy_.patches().empty() ? 0 : last_patch + 1, Vec3(0.0));
  std::vector<double> radii(centroids.size(), -1.0);  // -1: no patch with this id
  for (mesh::NodeId patch : hierarchy_.patches()) {
    centroids[patch] = hierarchy_.centroid(patch);
    radii[patch] = 0.0;
    for (const Vec3& corner : hierarchy_.corners(patch))
      radii[patch] = std::max(radii[patch], glm::length(corner - centroids[patch]));
  }
  near_field_.set_patches(centroids, radii);
}

Rgb Solver::unshot_flux() const {
  Rgb total{};
  for (mesh::NodeId patch : hierarchy_.patches()) total += hierarchy_.unshot(patch) * hierarchy_.area(patch);
  return total;
}

Solver::PatchScan Solver::scan_patches() const {
  PatchScan scan;
  Rgb unshot{};  // sum |dB| A per channel, summed over channels at the end (as unshot_flux().sum())
  // The ambient term's sums (Cohen et al. 1988, section 3.2); those over rho_i A_i and A_i do not change.
  Rgb unshot_area{};
  const Rgb& reflectance_area = patch_reflectance_area_;
  const double area = patch_area_;
  // The shooter: the largest |dB| A summed over channels (strict: ties go to the lowest id, deterministically).
  double best_flux = 0.0;
  // Through a pointer: hierarchy_.unshot() is an out-of-line call, once per patch per shot.
  const Rgb* unshots = hierarchy_.unshots().data();
  for (const PatchEntry& patch : patch_table_) {
    const Rgb& u = unshots[patch.node];
    const Rgb magnitude(std::abs(u.r), std::abs(u.g), std::abs(u.b));
    unshot += magnitude * patch.area;
    const double flux = magnitude.sum() * patch.area;
    if (flux > best_flux) {
      best_flux = flux;
      scan.shooter = patch.node;
    }
    unshot_area += u * patch.area;
  }
  const double emitted = emitted_flux_.sum();
  scan.unshot_fraction = emitted > 0.0 ? unshot.sum() / emitted : 0.0;
  scan.net_unshot_fraction = emitted > 0.0 ? unshot_area.sum() / emitted : 0.0;
  // R = 1 / (1 - rho_avg), ambient = R sum dB_i A_i / sum A_i.
  if (area > 0.0) {
    for (int c = 0; c < 3; ++c) {
      const double rho_average = reflectance_area[c] / area;
      scan.ambient[c] = rho_average < 1.0 ? unshot_area[c] / area / (1.0 - rho_average) : 0.0;
    }
  }
  // With overshooting a patch shoots (w dB + rho x ambient) A, not dB A, and the shooter is the patch whose shot
  // moves the most flux. Chosen by |dB| A, a patch that had shot with an ambient term the same as today's holds
  // dB = -rho x ambient / w and shoots nothing: it stays the largest, and the solve stalls on it (a closed room with
  // walls of rho 0.9 and a floor lamp of rho 0.5 stopped at 20 000 shots with 180 % unshot, when plain shooting
  // converged in 1 877). When no shot would move anything (every dB zero up to rounding), the choice by |dB| A stays.
  if (options_.overshoot) {
    const double relaxation = options_.relaxation;
    double best_shot = 0.0;
    mesh::NodeId shooter = mesh::kNoNode;
    for (const PatchEntry& patch : patch_table_) {
      const Rgb shot = unshots[patch.node] * relaxation + patch.reflectance * scan.ambient;
      const double flux = (std::abs(shot.r) + std::abs(shot.g) + std::abs(shot.b)) * patch.area;
      if (flux > best_shot) {
        best_shot = flux;
        shooter = patch.node;
      }
    }
    if (shooter != mesh::kNoNode) scan.shooter = shooter;
  }
  return scan;
}

double Solver::unshot_fraction() const { return scan_patches().unshot_fraction; }
// unshot_flux() over the emitted flux: the sums the scan makes, without the scan's choice of a shooter.
double Solver::net_unshot_fraction() const {
  const double emitted = emitted_flux_.sum();
  return emitted > 0.0 ? unshot_flux().sum() / emitted : 0.0;
}

Rgb Solver::ambient() const { return scan_patches().ambient; }

// A patch that sees mostly its near field may see too little of the rest of the scene from its centroid to stand
// for it: a lamp 0.01 above a box's top sees the top over 0.98 of its hemicube and the room through a sliver, where
// the lamp as a whole sends the top 0.39. The near-field correction then refuses to hand the near field's change to
// the far field (NearFieldCorrection::far_refused). Called after a whole shot's near field is shaped, for a patch
// whose points are not chosen yet: returns true when the shot is to be made again from more points (set in
// shot_samples_), until the far field takes up the change or more points change the near field's back-end total by
// at most kAreaPointsChange of the shot (then the fewer stand for the patch as well: a box's top 0.01 under a
// ceiling sees the ceiling from every point). The patch shoots from the points chosen from then on, and this shot
// is made from them too: a patch's shots move flux among the pieces of split leaves, and settle what they owe, by
// the factors of its next shots, which should be the same (share_out_history). A patch whose first shots were not
// refused made them from its centroid; should a later one be, its points change once, and share_out_history
// scales down what it moves where the factors differ.
bool Solver::choose_area_points(mesh::NodeId shooter, AreaPointsTrial& trial) {
  const double near_total = near_field_.near_back_end_total();
  const int more = more_area_points(shot_samples_);
  const auto choose = [&](int samples) {
    area_samples_[shooter] = static_cast<std::uint8_t>(samples);
    if (samples > options_.shooter_samples) ++area_shooters_;
  };
  if (!near_field_.far_refused() || more == 0) {
    if (trial.previous_near >= 0.0) choose(shot_samples_);
    return false;
  }
  if (trial.previous_near >= 0.0 &&
      std::abs(near_total - trial.previous_near) <= kAreaPointsChange * near_field_.shot_total()) {
    choose(trial.previous_samples);
    shot_samples_ = trial.previous_samples;
    return true;
  }
  trial.previous_near = near_total;
  trial.previous_samples = shot_samples_;
  shot_samples_ = more;
  return true;
}

// The back end's factors of `shot` (all receivers when empty) into ff_, averaged over the points with their
// weights; with `kept`, also their factors with nothing occluding into `unoccluded`. Returns whether the back end
// gave those.
bool Solver::back_end_factors(std::span<const Vec3> points, std::span<const double> weights, const Vec3& normal,
                              std::span<const std::uint32_t> shot, bool kept, std::vector<double>& unoccluded) {
  const auto take_unoccluded = [&](std::vector<double>& into) {
    into.assign(ff_.size(), 0.0);
    if (!backend_->add_unoccluded(into)) into.clear();
  };
  if (points.size() == 1) {
    backend_->compute(formfactor::Shooter::from_normal(points[0], normal), cache_.view(), shot, ff_);
    if (kept) take_unoccluded(unoccluded);
    return kept;
  }
  ff_sample_.assign(ff_.size(), 0.0);
  const auto for_each_receiver = [&](auto&& body) {
    if (shot.empty()) {
      for (std::uint32_t i = 0; i < ff_.size(); ++i) body(i);
    } else {
      for (std::uint32_t i : shot) body(i);
    }
  };
  for_each_receiver([&](std::uint32_t i) { ff_[i] = 0.0; });
  if (kept) unoccluded.assign(ff_.size(), 0.0);
  for (std::size_t p = 0; p < points.size(); ++p) {
    backend_->compute(formfactor::Shooter::from_normal(points[p], normal), cache_.view(), shot, ff_sample_);
    for_each_receiver([&](std::uint32_t i) { ff_[i] += weights[p] * ff_sample_[i]; });
    if (kept) {
      take_unoccluded(unoccluded_sample_);
      kept = !unoccluded_sample_.empty();
      for (std::size_t i = 0; kept && i < unoccluded.size(); ++i) unoccluded[i] += weights[p] * unoccluded_sample_[i];
    }
  }
  return kept;
}

void Solver::compute_form_factors(mesh::NodeId shooter, std::span<const std::uint32_t> subset) {
  const auto start = Clock::now();
  const Vec3 normal = hierarchy_.plane(shooter).normal;
  // The shooting point is lifted off its surface by 1e-9 of the scene's size (far from the origin, by a few
  // rounding errors of its coordinates: shooter_lift). A centroid computed in floating point lies a rounding error
  // in front of or behind its own plane; lifted, its own surface lies strictly behind it, so the polygon
  // containing the point never projects over the whole hemicube.
  const Vec3 lift = normal * shooter_lift_;
  const Vec3 centroid = hierarchy_.centroid(shooter);
  const std::vector<Vec3> corners = hierarchy_.corners(shooter);
  const bool near_field = near_field_.reach() > 0.0;
  // The points per side the shot is made from (a subset's are those of its whole shot): the options', or those
  // chosen for a patch whose centroid could not stand for it.
  if (subset.empty()) shot_samples_ = area_samples_[shooter] != 0 ? area_samples_[shooter] : options_.shooter_samples;
  AreaPointsTrial trial{-1.0, shot_samples_};
  std::vector<Vec3> points;
  std::vector<double> weights;
  const FactorRow* row = nullptr;
  std::span<const std::uint32_t> shot;  // the receivers the back end shoots into (all when empty)
  while (true) {
    shooting_points(corners, centroid, lift, shot_samples_, points, weights);
    NearFieldShooter near{corners, centroid, normal, hierarchy_.area(shooter), points, weights, {}};
    // A whole shot from a patch whose last whole shot is kept, from the same points, shoots only into the leaves
    // split since.
    row = subset.empty() ? factor_cache_.find(shooter, &hierarchy_.impl()) : nullptr;
    if (row != nullptr && row->samples != shot_samples_) row = nullptr;
    // With the near-field correction, the back end keeps the unoccluded factors of the receivers it may correct
    // (back_end_factors takes them, and says when the back end has none). A reused shot lists those candidates on a
    // second thread while this one reads the row (with the row's unoccluded factors, dropped below when the back end
    // keeps none).
    std::span<const std::uint8_t> candidates;
    const auto list_candidates = [&] { candidates = near_field_.candidates(near, cache_.view()); };
    shot = subset;
    if (row != nullptr) {
      if (near_field) row_task_->run(list_candidates);
      try {
        shot = factors_from_row(*row, near_field);
      } catch (...) {
        row_task_->wait();
        throw;
      }
      row_task_->wait();
    } else if (near_field) {
      list_candidates();
    }
    bool kept = near_field && backend_->keep_unoccluded(candidates);
    if (row == nullptr || !shot.empty()) {
      // The unoccluded factors of `shot`: into unoccluded_, or beside the row's there.
      kept = back_end_factors(points, weights, normal, shot, kept, row != nullptr ? unoccluded_shot_ : unoccluded_);
      if (row != nullptr && kept && !unoccluded_shot_.empty()) {
        for (std::uint32_t i : shot) unoccluded_[i] = unoccluded_shot_[i];
      }
      // The pieces of each split leaf share the factor it had (share_out_split_factors).
      if (row != nullptr) share_out_split_factors(static_cast<mesh::NodeId>(row->node_count), false);
    }
    if (!kept) unoccluded_.clear();
    if (near_field) {
      near.unoccluded = unoccluded_;
      near_field_.shape(near, cache_.view(), subset, ff_);
      // The points saw too little of what lies beyond the near field to stand for the patch: the shot is made
      // again from more points (choose_area_points).
      if (subset.empty() && area_samples_[shooter] == 0 && choose_area_points(shooter, trial)) {
        ff_.assign(cache_.size(), 0.0);
        continue;
      }
    }
    if (row != nullptr) ++reused_shots_;
    // The row is kept, or patched where leaves split (a row whose leaves are all still leaves stays as it is), on
    // another thread, from a copy of the back end's factors, while this one applies the near-field correction and
    // makes the deposits; shoot() waits for it before anything the row reads changes.
    const bool keep = subset.empty() && row == nullptr, update = subset.empty() && row != nullptr && !shot.empty();
    if ((keep || update) && factor_cache_.enabled()) {
      row_ff_.assign(ff_.begin(), ff_.end());
      row_pending_ = true;
      row_task_->run([this, shooter, candidates, keep, samples = shot_samples_] {
        if (keep) {
          keep_row(shooter, candidates, samples);
        } else {
          update_row(shooter, candidates);
        }
      });
    }
    if (near_field) near_field_.write(subset, ff_);
    break;
  }
  if (subset.empty() && !(history_flux_ == Rgb{})) {
    // The leaves made since the shooter's last shot (all among those a reused row shoots into), each with the
    // leaf it comes from as the mesh stood then.
    const mesh::NodeId known = nodes_after_shot_[shooter];
    history_pieces_.clear();
    history_ancestor_.clear();
    const auto add = [&](std::uint32_t receiver) {
      const mesh::NodeId leaf = cache_.leaf(receiver);
      if (leaf < known) return;
      history_pieces_.push_back(receiver);
      history_ancestor_.push_back(leaf_among_first(leaf, known));
    };
    if (row != nullptr) {
      for (const std::uint32_t receiver : shot) add(receiver);
    } else {
      for (std::uint32_t receiver = 0; receiver < ff_.size(); ++receiver) add(receiver);
    }
    share_out_history(history_pieces_, history_ancestor_);
  }
  times_.form_factors += seconds_since(start);
}

// The row holds the back end's factors of the leaves that got one from the patch's last whole shot. A leaf that is
// still a leaf gets its factor as it was: the back end would give it the same, as nothing but splits changed the
// receivers, and a split leaf's pieces tile it exactly (in a pixel the AA hemicube's coverage list then holds pieces
// of one plane at one depth where it held the leaf, which shade what lies behind them as the leaf did; the classical
// hemicube gives the pieces the leaf's pixel centres). A leaf split since has its pieces shot again, every receiver
// occluding, and they share its factor in proportion to what they get. Leaves that got nothing get nothing now,
// their pieces too. The near-field correction is then made as for a shot computed afresh.
std::span<const std::uint32_t> Solver::factors_from_row(const FactorRow& row, bool unoccluded) {
  subset_.clear();
  split_entries_.clear();
  for (std::size_t k = 0; k < row.nodes.size(); ++k) {
    const mesh::NodeId node = row.nodes[k];
    const std::uint32_t receiver = cache_.receiver(node);  // kNoReceiver when it is no longer a leaf
    if (receiver != kNoReceiver) {
      ff_[receiver] = row.factors[k];
      continue;
    }
    // share_out_split_factors reads the factor the split leaf had from received_factor_; the next shot clears it.
    received_factor_[node] = row.factors[k];
    factor_written_.push_back(node);
    split_entries_.push_back(k);
    split_leaves_.clear();
    hierarchy_.leaves_under(node, split_leaves_, leaf_stack_);
    for (const mesh::NodeId leaf : split_leaves_) subset_.push_back(cache_.receiver(leaf));
  }
  std::sort(subset_.begin(), subset_.end());
  if (unoccluded) {
    unoccluded_.assign(ff_.size(), 0.0);
    for (std::size_t k = 0; k < row.near_nodes.size(); ++k) {
      const std::uint32_t receiver = cache_.receiver(row.near_nodes[k]);
      if (receiver != kNoReceiver) unoccluded_[receiver] = row.near_unoccluded[k];
    }
  }
  return subset_;
}

bool Solver::kept_near(std::uint32_t i, std::span<const std::uint8_t> candidates) const {
  return row_ff_[i] > 0.0 && !unoccluded_.empty() && i < candidates.size() && candidates[i] != 0;
}

void Solver::keep_row(mesh::NodeId shooter, std::span<const std::uint8_t> candidates, int samples) {
  // Sized exactly, in the memory of the patch's previous row when it had one.
  const auto near = [&](std::uint32_t i) { return kept_near(i, candidates); };
  std::size_t count = 0, near_count = 0;
  for (std::uint32_t i = 0; i < row_ff_.size(); ++i) {
    count += row_ff_[i] > 0.0;
    near_count += near(i);
  }
  FactorRow row = factor_cache_.take(shooter);
  row.node_count = hierarchy_.node_count();
  row.samples = samples;
  const auto size = [](auto& values, std::size_t n) {
    if (values.capacity() < n || values.capacity() > 2 * n) values = {};
    values.reserve(n);
    values.clear();
  };
  size(row.nodes, count);
  size(row.factors, count);
  size(row.near_nodes, near_count);
  size(row.near_unoccluded, near_count);
  for (std::uint32_t i = 0; i < row_ff_.size(); ++i) {
    if (!(row_ff_[i] > 0.0)) continue;
    row.nodes.push_back(cache_.leaf(i));
    row.factors.push_back(row_ff_[i]);
    // The near-field correction reads the unoccluded factors of its candidates that got a factor.
    if (near(i)) {
      row.near_nodes.push_back(cache_.leaf(i));
      row.near_unoccluded.push_back(unoccluded_[i]);
    }
  }
  factor_cache_.store(shooter, &hierarchy_.impl(), std::move(row));
}

// Rewriting the whole row, as keep_row does, cost as much as reading it in factors_from_row. The entries of the
// leaves that stayed are what the shot gave them; each split leaf's entry gives way to its pieces that got a factor
// (the first takes its place, the others fill entries none of whose pieces got one, then go at the end); entries left
// empty are removed by moving the last entry into them. factors_from_row writes each entry to its own leaf, so their
// order does not matter. A row that outgrows its memory gets a quarter more than it needs (the memory budget counts
// capacity, so that headroom is paid for).
// A split leaf's pieces are near-field candidates exactly when it was one (candidates go by patch).
void Solver::update_row(mesh::NodeId shooter, std::span<const std::uint8_t> candidates) {
  FactorRow row = factor_cache_.take(shooter);
  const auto near = [&](std::uint32_t i) { return kept_near(i, candidates); };
  std::vector<std::size_t>& vacant = row_vacant_;
  std::vector<std::pair<mesh::NodeId, double>>& extra = row_extra_;
  vacant.clear();
  extra.clear();
  // Replaces entry k of (nodes, values), a split leaf's, by its pieces for which wanted(i); value(i) is their value.
  const auto replace = [&](std::vector<mesh::NodeId>& nodes, std::vector<double>& values, std::size_t k,
                           auto&& wanted, auto&& value) {
    bool placed = false;
    row_leaves_.clear();
    hierarchy_.leaves_under(nodes[k], row_leaves_, row_stack_);
    for (const mesh::NodeId leaf : row_leaves_) {
      const std::uint32_t i = cache_.receiver(leaf);
      if (!wanted(i)) continue;
      if (!placed) {
        nodes[k] = leaf;
        values[k] = value(i);
        placed = true;
      } else {
        extra.emplace_back(leaf, value(i));
      }
    }
    if (!placed) vacant.push_back(k);
  };
  // Fills the vacant entries with the extra ones, appends what is left of those, or removes the vacant entries left,
  // largest index first (the last entry is then never a vacant one, or is the one removed).
  const auto settle = [&](std::vector<mesh::NodeId>& nodes, std::vector<double>& values) {
    for (; !vacant.empty() && !extra.empty(); vacant.pop_back(), extra.pop_back())
      std::tie(nodes[vacant.back()], values[vacant.back()]) = extra.back();
    if (nodes.capacity() < nodes.size() + extra.size()) {
      // A quarter more than needed: a row grows a little at most of its updates, and each exact fit moved it whole.
      const std::size_t needed = nodes.size() + extra.size();
      nodes.reserve(needed + needed / 4);
      values.reserve(needed + needed / 4);
    }
    for (const auto& [node, value] : extra) {
      nodes.push_back(node);
      values.push_back(value);
    }
    for (auto k = vacant.rbegin(); k != vacant.rend(); ++k) {
      nodes[*k] = nodes.back();
      values[*k] = values.back();
      nodes.pop_back();
      values.pop_back();
    }
    vacant.clear();
    extra.clear();
  };
  for (const std::size_t k : split_entries_)
    replace(row.nodes, row.factors, k, [&](std::uint32_t i) { return row_ff_[i] > 0.0; },
            [&](std::uint32_t i) { return row_ff_[i]; });
  settle(row.nodes, row.factors);
  for (std::size_t k = 0; k < row.near_nodes.size(); ++k) {
    if (cache_.receiver(row.near_nodes[k]) == kNoReceiver)
      replace(row.near_nodes, row.near_unoccluded, k, near, [&](std::uint32_t i) { return unoccluded_[i]; });
  }
  settle(row.near_nodes, row.near_unoccluded);
  row.node_count = hierarchy_.node_count();
  factor_cache_.store(shooter, &hierarchy_.impl(), std::move(row));
}

inline const Rgb& Solver::deposit(const Deposit& d, const SurfaceShading& shading, const Rgb& incident, double sign,
                                  std::span<Rgb> radiosity, std::span<Rgb> unshot, Rgb& absorbed) {
  const Rgb reflected = shading.reflectance * incident;  // flux
  Rgb& b = radiosity[d.leaf];
  b += reflected * d.inverse_area;
  unshot[d.patch] += reflected * d.inverse_patch_area;
  absorbed += shading.absorptance * incident * sign;
  return b;
}

inline double Solver::reflected_luminance(const Rgb& b, double luminance, const SurfaceShading& shading) {
  return shading.emits ? (b - shading.emission).luminance() : luminance;
}

void Solver::receive(mesh::NodeId leaf, const Rgb& incident, double sign) {
  const mesh::NodeId patch = hierarchy_.patch(leaf);
  deposit({sign / hierarchy_.area(leaf), sign / hierarchy_.area(patch), leaf, patch},
          shading_[hierarchy_.surface(leaf)], incident, sign, hierarchy_.radiosities(), hierarchy_.unshots(),
          absorbed_flux_);
}

bool Solver::shoot_once() { return shoot(scan_patches()); }

bool Solver::shoot(const PatchScan& scan) {
  auto start = Clock::now();
  cache_.update(hierarchy_);
  times_.subdivision += seconds_since(start);

  const mesh::NodeId shooter = scan.shooter;
  if (shooter == mesh::kNoNode) return false;
  const double relaxation = options_.relaxation;
  // With overshooting, also what the shooter is expected to receive later: its reflectance times the ambient
  // term of the unshot flux.
  const Rgb overshoot = options_.overshoot ? material(shooter).reflectance * scan.ambient : Rgb{};
  const double area = hierarchy_.area(shooter);
  const Rgb shot_flux = hierarchy_.unshot(shooter) * (relaxation * area) + overshoot * area;
  history_flux_ = shot_so_far_[shooter];

  // received_factor_ holds this shot's factor per node: clear what the previous shot wrote (not all nodes; only
  // shots that split or reused a row whose leaves split wrote any).
  for (mesh::NodeId node : factor_written_) received_factor_[node] = 0.0;
  factor_written_.clear();
  received_factor_.resize(hierarchy_.node_count(), 0.0);
  ff_.assign(cache_.size(), 0.0);
  // Waits for the row task of compute_form_factors when the shot ends, also when something throws.
  struct RowWait {
    Solver& solver;
    ~RowWait() {
      try {  // unwinding from an exception of this thread, which is the one to report
        solver.wait_for_row();
      } catch (...) {
      }
    }
  } row_wait{*this};
  compute_form_factors(shooter, {});

  hierarchy_.unshot(shooter) = hierarchy_.unshot(shooter) * (1.0 - relaxation) - overshoot;
  const std::uint32_t shooter_surface = hierarchy_.surface(shooter);
  touched_count_ = 0;
  const std::span<const std::uint32_t> surfaces = cache_.view().surfaces();  // the leaves' surfaces
  update_deposits();
  // The luminance table of substructuring follows the deposits when it is current and no channel of the shot is
  // negative: then only the receivers of this shot change, and only upwards, so the largest reflected luminance
  // is the larger of the old one and theirs (steep_leaves_of_shot).
  const bool follow = options_.adaptive && luminance_current() && shot_flux.r >= 0.0 && shot_flux.g >= 0.0 &&
                      shot_flux.b >= 0.0;
  if (!follow) luminance_revision_ = kNoRevision;
  const std::span<Rgb> radiosity = hierarchy_.radiosities(), unshot = hierarchy_.unshots();
  // The running sums in locals and the arrays through plain pointers: with deposit() as an out-of-line member call
  // per receiver, each deposit reloaded every member and waited on the previous one's stores. The same additions
  // in the same order.
  const std::size_t count = cache_.size();
  if (touched_.size() < count) touched_.resize(count);  // only grows: no clearing per shot
  std::uint32_t* touched = touched_.data();
  std::size_t reached = 0;
  double* luminance = luminance_.data();
  const double* ff = ff_.data();
  const Deposit* deposits = deposits_.data();
  const SurfaceShading* shading = shading_.data();
  Rgb absorbed = absorbed_flux_;
  double largest = largest_reflected_;
  // The largest rise of a receiver's luminance (steep_leaves_of_shot). A NaN rise may be left out: a NaN luminance
  // makes no step too steep, with or without a test.
  double rise = 0.0;
  for (std::size_t i = 0; i < count; ++i) {
    // A planar surface sends nothing to itself (its own elements included).
    const std::uint32_t surface = surfaces[i];
    if (surface == shooter_surface || !(ff[i] > 0.0)) continue;
    const Deposit& d = deposits[i];  // receive(leaf, incident, 1) without the lookups
    const SurfaceShading& s = shading[surface];
    const Rgb incident = shot_flux * ff[i];
    touched[reached++] = static_cast<std::uint32_t>(i);
    const Rgb& b = deposit(d, s, incident, 1.0, radiosity, unshot, absorbed);
    if (follow) {
      const double l = b.luminance();
      rise = std::max(rise, l - luminance[i]);
      luminance[i] = l;
      largest = std::max(largest, reflected_luminance(b, l, s));
    }
  }
  touched_count_ = reached;
  if (follow) {
    drift_ += rise;
    ++drift_shots_;
  }
  absorbed_flux_ = absorbed;
  largest_reflected_ = largest;
  ++shots_;
  last_shooter_ = shooter;
  // The shot is in every leaf by its own factor, and the earlier shots too (compute_form_factors moved them among
  // the leaves made since the last shot): kept before substructuring, so that an exception there leaves them
  // right for the next shot.
  shot_so_far_[shooter] += shot_flux;
  nodes_after_shot_[shooter] = static_cast<mesh::NodeId>(hierarchy_.node_count());

  if (options_.adaptive) substructure(shooter, shot_flux);
  wait_for_row();
  return true;
}

void Solver::wait_for_row() {
  if (!row_pending_) return;
  row_pending_ = false;
  row_task_->wait();
}

void Solver::update_deposits() {
  if (deposits_revision_ == cache_.revision() && deposits_source_ == &hierarchy_.impl()) return;
  deposits_.resize(cache_.size());
  for (std::size_t i = 0; i < cache_.size(); ++i) {
    const mesh::NodeId leaf = cache_.leaf(i);
    const mesh::NodeId patch = hierarchy_.patch(leaf);
    deposits_[i] = {1.0 / hierarchy_.area(leaf), 1.0 / hierarchy_.area(patch), leaf, patch};
  }
  deposits_revision_ = cache_.revision();
  deposits_source_ = &hierarchy_.impl();
}

namespace {

// The gradient test of adaptive substructuring: two edge-neighbours whose luminances differ by more than the
// threshold (--gradient times the largest reflected luminance) are both split.
bool too_steep(double luminance, double neighbour_luminance, double threshold) {
  return std::abs(luminance - neighbour_luminance) > threshold;
}

}  // namespace

void Solver::update_luminance() {
  update_deposits();
  if (luminance_current()) return;
  luminance_.resize(cache_.size());
  const std::span<const Rgb> radiosity = hierarchy_.radiosities();
  const std::span<const mesh::NodeId> leaves = cache_.leaves();
  const std::span<const std::uint32_t> surfaces = cache_.view().surfaces();
  largest_reflected_ = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, cache_.size(), 4096), 0.0,
      [&](const tbb::blocked_range<std::size_t>& range, double partial) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
          const Rgb& b = radiosity[leaves[i]];
          const double l = b.luminance();
          luminance_[i] = l;
          partial = std::max(partial, reflected_luminance(b, l, shading_[surfaces[i]]));
        }
        return partial;
      },
      [](double a, double b) { return std::max(a, b); });
  forget_slack();
  luminance_revision_ = cache_.revision();
  luminance_source_ = &hierarchy_.impl();
}

void Solver::forget_slack() {
  slack_.assign(cache_.size(), -std::numeric_limits<double>::infinity());
  drift_ = 0.0;
  drift_shots_ = 0;
}

// Only leaves that changed in this shot can newly exceed the threshold: radiosities only grow and the threshold
// grows with the largest one (with overrelaxation or overshooting a shot can be negative, and this is a
// heuristic). The leaves of the current revision are tested through flat tables by receiver (luminance,
// neighbours), in parallel, with the same result whatever the thread count: a maximum, a set of flags (a flag may
// be set by two threads at once, to the same value), and the tested receivers' slack_ (each written by the one task
// that tests it). Candidates come out by node id.
std::vector<mesh::NodeId> Solver::steep_leaves_of_shot() {
  neighbours_.update(hierarchy_, cache_);
  update_luminance();  // a no-op when the shot's deposits kept the table current
  std::vector<mesh::NodeId> candidates;
  const double threshold = options_.gradient * largest_reflected_;
  if (!(threshold > 0.0)) return candidates;
  candidate_flag_.assign((cache_.size() + 7) / 8 * 8, 0);  // whole words of eight flags for the scan below
  // Plain pointers in locals: through the members, every flag store (a byte, which may alias anything) made the
  // loop load the tables' addresses and the threshold again.
  const double* luminance = luminance_.data();
  std::uint8_t* flags = candidate_flag_.data();
  const std::uint32_t* touched = touched_.data();
  const NeighbourTable& neighbours = neighbours_;
  // Most receivers a shot reaches need no test: while the luminance table follows the deposits, luminances and the
  // threshold only rise, and a pair's step |L_r - L_n| grows by at most the larger of the two rises, which is at most
  // the shot's largest rise. So the step from r to any neighbour stays at most threshold - slack_[r] + drift_, where
  // slack_[r] is what r's last test left, threshold - (its widest step) + drift_ then; r is tested again only when
  // slack_[r] - drift_ is not above `margin`. The margin, 1e-9 of threshold + drift_ (a billion times the rounding
  // of the additions and subtractions involved, drift_ summing at most 2^16 shots), keeps the bound safe in floating
  // point: the receivers flagged are the same as when every one was tested. In the office 88 % of the receivers
  // shots reach are not tested.
  if (drift_shots_ > (1u << 16)) forget_slack();
  double* slack = slack_.data();
  const double drift = drift_;
  const double margin = 1e-9 * (threshold + drift) + std::numeric_limits<double>::min();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, touched_count_, 1024),
                    [luminance, flags, touched, threshold, &neighbours, slack, drift,
                     margin](const tbb::blocked_range<std::size_t>& range) {
                      const auto flag = [flags](std::uint32_t r) {
                        std::atomic_ref<std::uint8_t>(flags[r]).store(1, std::memory_order_relaxed);
                      };
                      for (std::size_t t = range.begin(); t != range.end(); ++t) {
                        const std::uint32_t r = touched[t];
                        if (slack[r] - drift > margin) continue;  // false for NaN, and for -infinity
                        const double own = luminance[r];
                        double widest = 0.0;
                        for (const std::uint32_t neighbour : neighbours.of(r)) {
                          const double step = std::abs(own - luminance[neighbour]);
                          widest = std::max(widest, step);
                          if (step > threshold) {  // too_steep
                            flag(r);
                            flag(neighbour);
                          }
                        }
                        slack[r] = (threshold - widest) + drift;
                      }
                    });
  // By node id, as leaves are. Flags are few: eight at a time.
  for (std::size_t word = 0; word < candidate_flag_.size(); word += 8) {
    std::uint64_t eight;
    std::memcpy(&eight, flags + word, sizeof eight);
    if (eight == 0) continue;
    for (std::size_t r = word; r < word + 8; ++r)
      if (flags[r] != 0) candidates.push_back(cache_.leaf(r));
  }
  return candidates;
}

// Leaves made by splits are not in the flat tables yet: they and their neighbours are asked of the hierarchy.
// Sorted by node id, without repeats.
std::vector<mesh::NodeId> Solver::steep_leaves_among(std::span<const mesh::NodeId> new_leaves) {
  update_luminance();  // the view is that of the new leaves (substructure updated the cache)
  std::vector<mesh::NodeId> candidates;
  const double threshold = options_.gradient * largest_reflected_;
  if (!(threshold > 0.0)) return candidates;
  std::vector<mesh::NodeId> around;
  for (mesh::NodeId leaf : new_leaves) {
    const double own = hierarchy_.radiosity(leaf).luminance();
    hierarchy_.edge_neighbours(leaf, around);
    for (mesh::NodeId neighbour : around) {
      if (too_steep(own, hierarchy_.radiosity(neighbour).luminance(), threshold)) {
        candidates.push_back(leaf);
        candidates.push_back(neighbour);
      }
    }
  }
  std::sort(candidates.begin(), candidates.end());
  candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
  return candidates;
}

// Splits the candidates that may be split; returns every node split, balancing's included.
std::vector<mesh::NodeId> Solver::split_candidates(std::span<const mesh::NodeId> candidates) {
  std::vector<mesh::NodeId> split_nodes;
  refused_.resize(hierarchy_.node_count(), 0);
  for (mesh::NodeId candidate : candidates) {
    // Already split by balancing, or at the deepest level or smallest area (asked first: a refused split
    // composes its reason, and such leaves come back as candidates shot after shot).
    if (refused_[candidate] != 0) continue;
    if (!hierarchy_.can_split(candidate)) {
      refused_[candidate] = 1;
      continue;
    }
    // Not recorded in refused_: a split that balancing makes too large may fit once its neighbours are split.
    if (!split_fits_element_limit(candidate)) {
      element_limit_reached_ = true;
      continue;
    }
    const mesh::SplitResult result = hierarchy_.split(candidate);
    if (!result.ok) continue;
    split_nodes.push_back(candidate);
    for (mesh::NodeId other : result.also_split) split_nodes.push_back(other);
  }
  splits_ += static_cast<std::int64_t>(split_nodes.size());
  return split_nodes;
}

// A split makes 3 leaves more for every leaf it splits: the candidate and, with balancing, the leaves it forces to
// split first (Hierarchy::forced_splits). Decided in the order of the splits, on one thread: the same with any
// number of threads.
bool Solver::split_fits_element_limit(mesh::NodeId candidate) {
  const auto limit = static_cast<std::uint64_t>(options_.max_elements);
  const std::uint64_t leaves = hierarchy_.leaf_count();
  const std::uint64_t room = limit > leaves ? limit - leaves : 0;
  if (room < 3) return false;
  // Balancing splits distinct leaves, at most all of them: with 4 x leaves within the limit, no need to count.
  if (!hierarchy_.options().balance || room >= 3 * leaves) return true;
  hierarchy_.forced_splits(candidate, forced_);
  return 3 * (forced_.size() + 1) <= room;
}

// Most shots split nothing (in the office, 215 of the first 3 000), and writing every receiver's factor by node in
// the deposit loop, then clearing it, cost those shots a scattered store and a list entry per receiver.
void Solver::record_shot_factors() {
  factor_written_.reserve(factor_written_.size() + touched_count_);
  for (const std::uint32_t receiver : std::span(touched_.data(), touched_count_)) {
    const mesh::NodeId leaf = cache_.leaf(receiver);
    received_factor_[leaf] = ff_[receiver];
    factor_written_.push_back(leaf);
  }
}

// After a round of splits (nodes from first_new on are new): takes the split leaves' share of this shot back
// from their patches' unshot radiosity and the absorbed flux, and from the B the new leaves inherited.
void Solver::take_back_split_shares(std::span<const mesh::NodeId> split_nodes, mesh::NodeId first_new,
                                    std::span<const mesh::NodeId> new_leaves, const Rgb& shot_flux) {
  received_factor_.resize(hierarchy_.node_count(), 0.0);
  for (mesh::NodeId old_leaf : split_nodes) {
    if (old_leaf >= first_new) continue;
    receive(old_leaf, shot_flux * received_factor_[old_leaf], -1.0);
  }
  // The share is computed as deposit() added it, to the bit: taken back from a piece whose B held nothing else, it
  // leaves exactly 0, and from any other with B >= 0 a B >= 0 (fl(B + s) >= s). Computed as rho x flux / area, it
  // left pieces that got nothing of their own at -8.9e-16 (a unit box's first shot with the classical hemicube:
  // 4 005 of 34 479 leaves below 0).
  for (mesh::NodeId leaf : new_leaves) {
    const mesh::NodeId ancestor = leaf_among_first(leaf, first_new);  // the leaf when the shot was received
    const Rgb inherited_share = material(ancestor).reflectance * (shot_flux * received_factor_[ancestor]) *
                                (1.0 / hierarchy_.area(ancestor));
    hierarchy_.radiosity(leaf) -= inherited_share;
    hierarchy_.unshot(leaf) = Rgb{};
  }
}

// The pieces of a split leaf tile it, yet the factors computed afresh for them need not add up to the leaf's: the
// near-field correction reshapes with the pieces' own centroids; where two surfaces lie on one another in one plane
// (a rug laid on a floor), the pixels along the edges of the one in front hold pieces of both, walked by their
// coverages; and where surfaces meet inside a pixel and one runs on behind the other (the floor under a box standing
// on it, a wall behind stairs or a lamp touching it), the AA hemicube's layer rule (formfactor/coverage_list.h) walks
// the pixel side by side or front to back depending on the coverages of the leaves there, and the leaves that were
// not split keep what they got beside the whole leaf. The flux taken back from a split leaf is therefore given out
// again in full: its pieces are scaled to share the factor it had received (by area where the back end gave none of
// them anything), and the balance holds through splits. Before, only the pieces of reshaped leaves and overlapping
// surfaces were: a rug laid on the floor of a closed room lost 6.2 % of the emitted flux in its lamp's four shots, a
// box standing on the floor made 3.6e-6 out of nothing, stairs against a wall 3.5e-5 (tests
// SolverEnergy.*ThroughSplits).
//
// One case is better served otherwise. In a shot's own substructuring (keep_reshaped), a leaf every piece of which
// that got anything was reshaped by the near-field correction holds the factor from its centroid, while each piece
// holds the factor from its own: where the factor changes fast across the leaf (at the foot of a partition, next to
// the shooter's corner) the leaf's is the worse of the two, and scaled to it the pieces kept its error (1.19 times
// the leaf's mean factor on the partition furnace's foot, multiplied again in each round). Such pieces keep their
// own factors, and what the leaf had over their total is returned: the shooter keeps it as unshot flux and sends it
// with its next shot, by all its factors, as the near-field correction of a whole shot has the far receivers take up
// the near field's change (or the shooter owes it, when the pieces got more). The balance holds as before; the
// pieces get what they would have got had they been split before the shot (test SolverHistory.PiecesOfANearLeaf*).
mesh::NodeId Solver::leaf_among_first(mesh::NodeId node, mesh::NodeId count) const {
  while (node >= count) node = hierarchy_.parent(node);
  return node;
}

void Solver::sum_pieces(std::span<const std::uint32_t> pieces, std::span<const mesh::NodeId> ancestors) {
  if (share_slot_.size() < hierarchy_.node_count()) share_slot_.resize(hierarchy_.node_count(), kNoSlot);
  share_total_.clear();
  share_area_.clear();
  share_leaf_.clear();
  for (std::size_t k = 0; k < pieces.size(); ++k) {
    std::uint32_t& slot = share_slot_[ancestors[k]];
    if (slot == kNoSlot) {
      slot = static_cast<std::uint32_t>(share_total_.size());
      share_total_.push_back(0.0);
      share_area_.push_back(0.0);
      share_leaf_.push_back(ancestors[k]);
    }
    share_total_[slot] += ff_[pieces[k]];
    share_area_[slot] += hierarchy_.area(cache_.leaf(pieces[k]));
  }
}

double Solver::share_out_split_factors(mesh::NodeId first_new, bool keep_reshaped) {
  if (subset_.empty()) return 0.0;
  // Per piece, the split leaf it comes from: the node that was a leaf when the shot was received.
  piece_ancestor_.resize(subset_.size());
  for (std::size_t k = 0; k < subset_.size(); ++k)
    piece_ancestor_[k] = leaf_among_first(cache_.leaf(subset_[k]), first_new);
  sum_pieces(subset_, piece_ancestor_);
  // The leaves whose pieces that got anything were all reshaped by the near-field correction keep the pieces' own
  // factors; what the leaf had beyond their total is returned.
  double returned = 0.0;
  if (keep_reshaped) {
    const std::span<const std::uint32_t> reshaped = near_field_.last_corrected();
    reshaped_flag_.resize(ff_.size(), 0);
    for (const std::uint32_t receiver : reshaped) reshaped_flag_[receiver] = 1;
    share_own_.assign(share_total_.size(), 1);
    for (std::size_t k = 0; k < subset_.size(); ++k) {
      if (ff_[subset_[k]] > 0.0 && reshaped_flag_[subset_[k]] == 0) share_own_[share_slot_[piece_ancestor_[k]]] = 0;
    }
    for (const std::uint32_t receiver : reshaped) reshaped_flag_[receiver] = 0;
    for (std::uint32_t slot = 0; slot < share_total_.size(); ++slot) {
      if (share_own_[slot] == 0 || !(share_total_[slot] > 0.0)) {
        share_own_[slot] = 0;  // scaled, or shared by area, below
        continue;
      }
      returned += received_factor_[share_leaf_[slot]] - share_total_[slot];
    }
  }
  for (std::size_t k = 0; k < subset_.size(); ++k) {
    const std::uint32_t receiver = subset_[k];
    const mesh::NodeId ancestor = piece_ancestor_[k];
    const std::uint32_t slot = share_slot_[ancestor];
    if (keep_reshaped && share_own_[slot] != 0) continue;
    if (share_total_[slot] > 0.0) {
      ff_[receiver] *= received_factor_[ancestor] / share_total_[slot];
    } else if (share_area_[slot] > 0.0) {
      // The back end gave none of the pieces anything, though the leaf received: a wall whose plane runs through
      // the shooting point, standing on the shooting patch, is seen edge on, a rounding's sliver for the leaf and
      // nothing for its pieces, while the correction gave the leaf what the part of the patch in front of it
      // sends. The pieces share it by area; left out, it was lost from a closed room (1.3e-3 of the emitted flux
      // in one shot).
      ff_[receiver] = received_factor_[ancestor] * hierarchy_.area(cache_.leaf(receiver)) / share_area_[slot];
    }
  }
  for (const mesh::NodeId ancestor : piece_ancestor_) share_slot_[ancestor] = kNoSlot;
  return returned;
}

// A leaf's pieces inherit its B (mesh/hierarchy.h, Split), so they hold every shot made before the split in the
// leaf's even density, where their own factors from those shooters differ: along a wall's foot, a leaf split late
// keeps the share of the far walls and the ceiling that its upper part saw, and then gets its own, larger share of
// the floor patches beside it as they shoot. In the partition furnace that left the foot's leaves up to 15 % over
// B = 2 (docs/hierarchy.md, "Contact lines"). Each shooter's flux shot so far is kept (shot_so_far_), and the mesh's
// node count after its last shot (nodes_after_shot_): in its next shot (`pieces`: the leaves made since, each with
// the leaf it comes from, `ancestors`), and in each round of its own substructuring (the new leaves, with the
// leaves they were split from), the pieces of one leaf move its earlier shots among them by their own factors of
// this shot: piece p gets rho x (flux so far) x (F_p - F A_p / A) / A_p, F and A being the pieces' total factor and
// area. The changes of one leaf's pieces add up to no flux, so no patch's dB, no absorbed flux and no energy
// balance changes; only how B is spread over the leaf. Split before the shots, the pieces would have got the same
// (test SolverHistory.*). Shooters that never shoot again after a split leave their share inherited. A piece
// gives back at most what it has over its emission and, in the shot's own substructuring, over its share of this
// shot, which it must keep whole for a later round to take back should it split again (counted in, a piece gave
// some of it away, its pieces then lost the whole of it, and under a lamp of emission 10 a plate a thousandth below
// it and the ceiling round it had leaves down to -0.031: test
// SolverHistory.APieceSplitAgainInItsShotKeepsWhatItTakesBack). Where this shot's factors are not those of the
// earlier shots (the near-field correction's scale changes a little with the receivers), a leaf's changes are
// scaled down together.
void Solver::share_out_history(std::span<const std::uint32_t> pieces, std::span<const mesh::NodeId> ancestors,
                               const Rgb& received) {
  if (pieces.empty()) return;
  sum_pieces(pieces, ancestors);
  // Per piece the change of its B; per slot the part of the changes that leaves every piece's B at least its
  // emission.
  history_change_.assign(pieces.size(), Rgb{});
  share_scale_.assign(share_total_.size(), 1.0);
  const auto lowest_part = [](double available, double change, double part) {
    return change < 0.0 ? std::min(part, std::max(0.0, available) / -change) : part;
  };
  for (std::size_t k = 0; k < pieces.size(); ++k) {
    const mesh::NodeId piece = cache_.leaf(pieces[k]);
    const std::uint32_t slot = share_slot_[ancestors[k]];
    if (ancestors[k] == piece || !(share_area_[slot] > 0.0)) continue;
    const double area = hierarchy_.area(piece);
    const double change = ff_[pieces[k]] - share_total_[slot] * (area / share_area_[slot]);
    const Rgb delta = material(piece).reflectance * (history_flux_ * (change / area));
    history_change_[k] = delta;
    // What the piece has of the earlier shots: its B but for its emission and its share of this shot, which a
    // later round of this substructuring may take back in full (take_back_split_shares) when it splits.
    const Rgb available = hierarchy_.radiosity(piece) - material(piece).emission -
                          material(piece).reflectance * (received * std::max(0.0, ff_[pieces[k]])) * (1.0 / area);
    double& part = share_scale_[slot];
    part = lowest_part(available.r, delta.r, part);
    part = lowest_part(available.g, delta.g, part);
    part = lowest_part(available.b, delta.b, part);
  }
  // A piece that sets its leaf's scale ends on its emission (and its share of this shot), a rounding either side
  // of it: the scale is its available B over its change, and their product rounds. Below its emission it is set to
  // it (a unit room's piece ended at -1.1e-16, from B 0.949 and a change of -1.435 x 0.661).
  //
  // A current luminance table is kept current here, where forgetting it made the next gradient test recompute every
  // receiver's luminance and test every receiver the shot reached (the office's substructuring took 5.4 of its
  // 50.3 s, 3.3 of 48.3 s now: docs/benchmarks.md, "The office at c5d43ab and now").
  // The pieces' luminances change either way, so each pair's step grows by at most twice the widest change, which
  // drift_ takes in as it takes a shot's rise (steep_leaves_of_shot); the largest reflected luminance is kept unless
  // a piece that held it fell, and then the table is recomputed.
  const bool follow = luminance_current();
  double largest = largest_reflected_, widest = 0.0;
  bool fell = false, changed = false;
  for (std::size_t k = 0; k < pieces.size(); ++k) {
    if (history_change_[k] == Rgb{}) continue;
    const mesh::NodeId piece = cache_.leaf(pieces[k]);
    const double scale = share_scale_[share_slot_[ancestors[k]]];
    Rgb& b = hierarchy_.radiosity(piece);
    const SurfaceShading& shading = shading_[hierarchy_.surface(piece)];
    const double reflected_before = follow ? reflected_luminance(b, luminance_[pieces[k]], shading) : 0.0;
    b += history_change_[k] * scale;
    if (scale < 1.0) {
      const Rgb& e = shading.emission;
      b = Rgb{std::max(b.r, e.r), std::max(b.g, e.g), std::max(b.b, e.b)};
    }
    changed = true;
    if (!follow) continue;
    const double l = b.luminance(), reflected = reflected_luminance(b, l, shading);
    widest = std::max(widest, std::abs(l - luminance_[pieces[k]]));
    fell = fell || (reflected_before == largest_reflected_ && reflected < reflected_before);
    luminance_[pieces[k]] = l;
    largest = std::max(largest, reflected);
  }
  for (const mesh::NodeId ancestor : ancestors) share_slot_[ancestor] = kNoSlot;
  if (!changed) return;
  if (!follow || fell || !(widest < std::numeric_limits<double>::infinity())) {
    luminance_revision_ = kNoRevision;
    return;
  }
  largest_reflected_ = largest;
  drift_ += 2.0 * widest;
  ++drift_shots_;
}

void Solver::substructure(mesh::NodeId shooter, const Rgb& shot_flux) {
  auto start = Clock::now();
  const std::uint32_t shooter_surface = hierarchy_.surface(shooter);
  std::vector<mesh::NodeId> candidates = steep_leaves_of_shot();
  bool first_round = true;
  while (!candidates.empty()) {
    const auto first_new = static_cast<mesh::NodeId>(hierarchy_.node_count());
    wait_for_row();  // splitting changes the leaves the row names
    const std::vector<mesh::NodeId> split_nodes = split_candidates(candidates);
    if (split_nodes.empty()) break;
    // The shot's factors by leaf, while ff_ and the cache still hold the shot's receivers.
    if (first_round) record_shot_factors();
    first_round = false;
    std::vector<mesh::NodeId> new_leaves;
    for (mesh::NodeId node = first_new; node < hierarchy_.node_count(); ++node) {
      if (hierarchy_.is_leaf(node)) new_leaves.push_back(node);
    }

    // This shot again, into the new leaves only, every other receiver still occluding. The form factors come
    // before anything is taken back: should the back end throw, the new leaves keep the share they inherited and
    // the balance holds.
    cache_.update(hierarchy_);
    subset_.clear();
    for (mesh::NodeId leaf : new_leaves) {
      if (hierarchy_.surface(leaf) != shooter_surface) subset_.push_back(cache_.receiver(leaf));
    }
    times_.subdivision += seconds_since(start);
    double returned = 0.0;
    if (!subset_.empty()) {
      ff_.assign(cache_.size(), 0.0);
      compute_form_factors(shooter, subset_);
      returned = share_out_split_factors(first_new, true);
    }
    start = Clock::now();
    take_back_split_shares(split_nodes, first_new, new_leaves, shot_flux);
    for (mesh::NodeId leaf : new_leaves) {
      const std::uint32_t receiver = cache_.receiver(leaf);
      if (hierarchy_.surface(leaf) == shooter_surface || !(ff_[receiver] > 0.0)) continue;
      received_factor_[leaf] = ff_[receiver];
      factor_written_.push_back(leaf);
      receive(leaf, shot_flux * ff_[receiver], 1.0);
    }
    if (returned != 0.0) hierarchy_.unshot(shooter) += shot_flux * (returned / hierarchy_.area(shooter));
    // The new leaves' share of the shooter's earlier shots, once their B holds this shot's own share and not the
    // one they inherited (a piece gives back at most what it has over its emission and that share).
    if (!subset_.empty() && !(history_flux_ == Rgb{})) share_out_history(subset_, piece_ancestor_, shot_flux);
    // Every leaf now holds the shooter's shots by its own factors: after an exception in a later round, its next
    // shot moves the earlier shots only among the leaves made since.
    nodes_after_shot_[shooter] = static_cast<mesh::NodeId>(hierarchy_.node_count());
    candidates = steep_leaves_among(new_leaves);
  }
  times_.subdivision += seconds_since(start);
}

void Solver::run(const std::function<bool(const Progress&)>& keep_going) {
  const auto start = Clock::now();
  const double total_before = times_.total;
  converged_ = false;
  interrupted_ = false;
  diverged_ = false;
  // Whatever stops the loop, an exception too (from keep_going or a back end), leaves a solution to read: inner
  // nodes pulled up and the time counted. A solve stopped by an exception counts as interrupted.
  const auto finish = [&] {
    pull_up();
    times_.total = total_before + seconds_since(start);
  };
  try {
    shooting_loop(keep_going, start, total_before);
  } catch (...) {
    interrupted_ = true;
    finish();
    throw;
  }
  finish();
}

void Solver::shooting_loop(const std::function<bool(const Progress&)>& keep_going, Clock::time_point start,
                           double total_before) {
  PatchScan scan = scan_patches();
  while (true) {
    if (scan.unshot_fraction < options_.converge) {
      converged_ = true;
      break;
    }
    if (shots_ >= options_.max_shots) break;
    if (!std::isfinite(scan.net_unshot_fraction) || std::abs(scan.net_unshot_fraction) > kDivergedUnshot) {
      diverged_ = true;
      break;
    }
    if (!shoot(scan)) {
      converged_ = true;  // nothing left to shoot
      break;
    }
    scan = scan_patches();
    if (keep_going) {
      const Progress progress{shots_, scan.unshot_fraction, hierarchy_.leaf_count(),
                              total_before + seconds_since(start)};
      if (!keep_going(progress)) {
        converged_ = scan.unshot_fraction < options_.converge;
        interrupted_ = !converged_;
        break;
      }
    }
  }
}

std::vector<Rgb> Solver::radiosity() const {
  std::vector<Rgb> values(hierarchy_.node_count());
  for (mesh::NodeId node = 0; node < values.size(); ++node) values[node] = hierarchy_.radiosity(node);
  hierarchy_.average_inner_nodes(values);
  return values;
}

void Solver::pull_up() { hierarchy_.update_inner_radiosity(); }

std::vector<Rgb> Solver::displayed_radiosity() const {
  std::vector<Rgb> values = radiosity();
  const Rgb ambient_term = ambient();
  for (mesh::NodeId node = 0; node < values.size(); ++node) {
    if (hierarchy_.is_leaf(node)) values[node] += material(node).reflectance * ambient_term;
  }
  return values;
}

int Solver::max_leaf_level() const {
  int level = 0;
  for (mesh::NodeId leaf : hierarchy_.leaves()) level = std::max(level, hierarchy_.level(leaf));
  return level;
}

}  // namespace aarad::refine
