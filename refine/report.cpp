// The solve report (../shared/design.md, "solve report"); field meanings are documented in docs/solver.md.
#include "aarad/refine/report.h"

namespace aarad::refine {

nlohmann::json rgb_json(const Rgb& colour) { return nlohmann::json::array({colour.r, colour.g, colour.b}); }

nlohmann::json make_report(const Solver& solver, const std::vector<mesh::Violation>& violations,
                           const ReportTimes& times) {
  const Scene& scene = solver.scene();
  const mesh::Hierarchy& hierarchy = solver.hierarchy();
  const SolverOptions& options = solver.options();
  const std::vector<Rgb> radiosity = solver.radiosity();

  // Per group: area, leaf count and area-weighted mean leaf radiosity (without the ambient term).
  std::vector<double> group_area(scene.groups.size(), 0.0);
  std::vector<double> group_leaf_area(scene.groups.size(), 0.0);
  std::vector<std::size_t> group_elements(scene.groups.size(), 0);
  std::vector<Rgb> group_weighted(scene.groups.size());
  for (const Surface& surface : scene.surfaces) group_area[surface.group] += surface.area;
  for (mesh::NodeId leaf : hierarchy.leaves()) {
    const std::uint32_t group = scene.surfaces[hierarchy.surface(leaf)].group;
    const double area = hierarchy.area(leaf);
    group_leaf_area[group] += area;
    group_weighted[group] += radiosity[leaf] * area;
    ++group_elements[group];
  }
  nlohmann::json groups = nlohmann::json::array();
  for (std::size_t g = 0; g < scene.groups.size(); ++g) {
    const Rgb mean = group_leaf_area[g] > 0.0 ? group_weighted[g] / group_leaf_area[g] : Rgb{};
    groups.push_back({{"name", scene.groups[g].name},
                      {"area", group_area[g]},
                      {"elements", group_elements[g]},
                      {"mean_radiosity", rgb_json(mean)}});
  }

  nlohmann::json violation_list = nlohmann::json::array();
  for (const mesh::Violation& v : violations) {
    violation_list.push_back({{"invariant", v.invariant},
                              {"node", v.node == mesh::kNoNode ? nlohmann::json(nullptr) : nlohmann::json(v.node)},
                              {"message", v.message}});
  }

  const SolverTimes& solver_times = solver.times();
  const double total = times.total >= 0.0 ? times.total : solver_times.total + times.output;
  const mesh::MeshingOptions& meshing = hierarchy.options();

  return nlohmann::json{
      {"scene", scene.name},
      {"method", std::string(solver.backend().name())},
      {"resolution", options.resolution},
      {"converged", solver.converged()},
      {"interrupted", solver.interrupted()},
      {"diverged", solver.diverged()},
      {"shots", solver.shots()},
      {"unshot_fraction", solver.unshot_fraction()},
      {"emitted_flux", rgb_json(solver.emitted_flux())},
      {"absorbed_flux", rgb_json(solver.absorbed_flux())},
      {"unshot_flux", rgb_json(solver.unshot_flux())},
      {"escaped_flux", rgb_json(solver.escaped_flux())},
      {"ambient", rgb_json(solver.ambient())},
      {"patches", hierarchy.patches().size()},
      {"elements", hierarchy.leaf_count()},
      {"max_level", solver.max_leaf_level()},
      {"splits", solver.splits()},
      {"element_limit_reached", solver.element_limit_reached()},
      {"reused_shots", solver.reused_shots()},
      {"area_shooters", solver.area_shooters()},
      {"seconds",
       {{"total", total},
        {"form_factors", solver_times.form_factors},
        {"subdivision", solver_times.subdivision},
        {"output", times.output}}},
      {"invariants", {{"violations", violation_list}}},
      {"groups", groups},
      {"options",
       {{"converge", options.converge},
        {"max_shots", options.max_shots},
        {"adaptive", options.adaptive},
        {"gradient", options.gradient},
        {"relaxation", options.relaxation},
        {"overshoot", options.overshoot},
        {"shooter_samples", options.shooter_samples},
        {"near_field", options.near_field},
        {"factor_cache_mib", options.factor_cache_mib},
        {"max_elements", options.max_elements},
        {"patch_size", meshing.patch_size},
        {"element_size", meshing.element_size},
        {"max_level", meshing.max_level},
        {"min_area", meshing.min_area},
        {"balance", meshing.balance}}}};
}

}  // namespace aarad::refine
