// Uses the installed library as README.md shows: a Cornell box solve, the public invariant checker, the report
// and the output files. Exits 0 when everything holds, 1 with a message otherwise.
#include "aarad/core/builtin_scenes.h"
#include "aarad/formfactor/backend.h"
#include "aarad/mesh/invariants.h"
#include "aarad/refine/output.h"
#include "aarad/refine/report.h"
#include "aarad/refine/solver.h"

#include <cmath>
#include <cstdio>
#include <filesystem>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: consumer OUTPUT_DIRECTORY\n");
    return 2;
  }
  using namespace aarad;
  const Scene scene = load_scene("cornell");
  refine::SolverOptions options;
  options.meshing = refine::default_meshing(scene);
  options.max_shots = 40;
  refine::Solver solver(scene, options);
  solver.run();
  const auto violations = mesh::check_invariants(solver.hierarchy());
  // The element radiosities as README.md reads them: B by node id at the leaves, which cover the scene's
  // 1.87909e6 mm^2 (aarad inspect cornell) and, in a lit box, have a positive mean.
  const std::vector<Rgb> radiosity = solver.radiosity();
  double area = 0.0, flux = 0.0;
  for (const mesh::NodeId leaf : solver.hierarchy().leaves()) {
    area += solver.hierarchy().area(leaf);
    flux += solver.hierarchy().area(leaf) * radiosity[leaf].r;
  }
  const refine::OutputResult files = refine::write_solution_files(solver, argv[1]);
  const nlohmann::json report = refine::make_report(solver, violations);
  std::printf("%lld shots, %zu elements, unshot %.6f, %zu violations, %zu files, back ends:",
              static_cast<long long>(solver.shots()), solver.hierarchy().leaf_count(), solver.unshot_fraction(),
              violations.size(), files.files.size());
  for (const std::string& name : formfactor::backend_names()) std::printf(" %s", name.c_str());
  std::printf("\n");
  std::printf("total area %.6g, area-weighted mean red radiosity %.6g\n", area, flux / area);
  const bool ok = solver.shots() == 40 && violations.empty() && files.files.size() == 5 &&
                  std::abs(area - 1.87909e6) < 1e2 && flux > 0.0 &&
                  report["elements"].get<std::size_t>() == solver.hierarchy().leaf_count() &&
                  solver.unshot_fraction() > 0.0 && solver.unshot_fraction() < 1.0 &&
                  std::filesystem::exists(std::filesystem::path(argv[1]) / "mesh.ply");
  if (!ok) std::fprintf(stderr, "consumer: the solve through the installed package is not as expected\n");
  return ok ? 0 : 1;
}
