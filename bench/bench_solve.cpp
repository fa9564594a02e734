// The solver benchmark of issue 5, laid out like section 4 of Chandran, Kiran, Phani and Rai: the Cornell box
// and the office solved to 1 % unshot flux with the AA hemicube at N = 100 and the classical hemicube at
// N = 100, 300, 1200 and 2500 (seconds, shots, elements), and each method's furnace accuracy (element RMS
// and worst deviation from the exact B = 2, converged to 1e-4; see docs/solver.md). Two more rows: the AA
// hemicube at N = 100 with the shooting step overrelaxed by 1.2 (`--relaxation`) and with ambient overshooting
// (`--overshoot`; docs/solver.md), and the AA hemicube at N = 100 computing every shot afresh (`--factor-cache 0`:
// every other row reuses a patch's factors when it shoots again, as `aarad solve` does by default).
//
//   bench_solve [--budget SECONDS] [--scenes cornell,office,furnace] [--threads N] [--methods LIST]
//
// LIST is comma-separated BACKEND:N[:RELAXATION[:overshoot][:afresh]] (default: the six rows of docs/benchmarks.md,
// "Solver", the AA hemicube with ambient overshooting and the AA hemicube with every shot afresh).
//
// A run that exceeds the budget is stopped after its current shot and reported with the unshot flux it reached.
// Prints a Markdown table on stdout (docs/benchmarks.md, "Solver").
#include "aarad/core/builtin_scenes.h"
#include "aarad/refine/solver.h"

#include <tbb/global_control.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

namespace {

using namespace aarad;

struct Method {
  std::string backend;
  int resolution;
  double relaxation = 1.0;
  bool overshoot = false;
  bool afresh = false;  // SolverOptions::factor_cache_mib = 0
};

struct Result {
  double seconds = 0.0;
  long long shots = 0;
  std::size_t elements = 0;
  bool finished = false;
  double unshot = 1.0;
  double rms = 0.0;
  double worst = 0.0;
};

Result solve(const Scene& scene, const Method& method, double converge, int shooter_samples, bool adaptive,
             double budget) {
  refine::SolverOptions options;
  options.backend = method.backend;
  options.resolution = method.resolution;
  options.converge = converge;
  options.shooter_samples = shooter_samples;
  options.adaptive = adaptive;
  options.relaxation = method.relaxation;
  options.overshoot = method.overshoot;
  if (method.afresh) options.factor_cache_mib = 0;
  options.meshing = refine::default_meshing(scene);
  refine::Solver solver(scene, options);
  solver.run([&](const refine::Progress& p) { return p.seconds < budget; });
  Result result;
  result.seconds = solver.times().total;
  result.shots = solver.shots();
  result.elements = solver.hierarchy().leaf_count();
  result.finished = !solver.interrupted();
  result.unshot = solver.unshot_fraction();
  double sum_squares = 0.0;
  for (mesh::NodeId leaf : solver.hierarchy().leaves()) {
    const double deviation = (solver.hierarchy().radiosity(leaf).r - 2.0) / 2.0;
    sum_squares += deviation * deviation;
    result.worst = std::max(result.worst, std::abs(deviation));
  }
  result.rms = std::sqrt(sum_squares / static_cast<double>(result.elements));
  return result;
}

std::string cell(const Result& r) {
  char text[160];
  if (r.finished) {
    std::snprintf(text, sizeof text, "%.2f s, %lld shots, %zu el.", r.seconds, r.shots, r.elements);
  } else {
    std::snprintf(text, sizeof text, "> %.0f s (stopped at %.2f %% unshot, %lld shots, %zu el.)", r.seconds,
                  100.0 * r.unshot, r.shots, r.elements);
  }
  return text;
}

// "aa-hemicube:100:1.2,hemicube:300,aa-hemicube:100:1:afresh" -> methods; nullopt when an item does not parse.
std::optional<std::vector<Method>> parse_methods(const std::string& list) {
  std::vector<Method> methods;
  std::size_t start = 0;
  while (start <= list.size()) {
    const std::size_t comma = std::min(list.find(',', start), list.size());
    std::vector<std::string> fields;
    for (std::size_t from = start; from <= comma;) {
      const std::size_t colon = std::min(list.find(':', from), comma);
      fields.push_back(list.substr(from, colon - from));
      from = colon + 1;
    }
    if (fields.size() < 2 || fields[0].empty()) return std::nullopt;
    Method method{fields[0], std::atoi(fields[1].c_str())};
    if (fields.size() > 2) method.relaxation = std::atof(fields[2].c_str());
    for (std::size_t k = 3; k < fields.size(); ++k) {
      if (fields[k] == "overshoot") {
        method.overshoot = true;
      } else if (fields[k] == "afresh") {
        method.afresh = true;
      } else {
        return std::nullopt;
      }
    }
    if (method.resolution < 2 || !(method.relaxation >= 1.0 && method.relaxation < 2.0)) return std::nullopt;
    methods.push_back(method);
    start = comma + 1;
  }
  return methods;
}

}  // namespace

int main(int argc, char** argv) {
  double budget = 600.0;
  std::string scenes = "cornell,office,furnace";
  int threads = 0;
  std::vector<Method> methods{{"aa-hemicube", 100},         {"aa-hemicube", 100, 1.2}, {"aa-hemicube", 100, 1.0, true},
                              {"aa-hemicube", 100, 1.0, false, true},
                              {"hemicube", 100},            {"hemicube", 300},         {"hemicube", 1200},
                              {"hemicube", 2500}};
  bool usage = false;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--budget") == 0 && i + 1 < argc) {
      budget = std::atof(argv[++i]);
    } else if (std::strcmp(argv[i], "--scenes") == 0 && i + 1 < argc) {
      scenes = argv[++i];
    } else if (std::strcmp(argv[i], "--threads") == 0 && i + 1 < argc) {
      threads = std::atoi(argv[++i]);
    } else if (std::strcmp(argv[i], "--methods") == 0 && i + 1 < argc) {
      const auto parsed = parse_methods(argv[++i]);
      usage = !parsed;
      if (parsed) methods = *parsed;
    } else {
      usage = true;
    }
  }
  if (usage) {
    std::fprintf(stderr,
                 "usage: %s [--budget SECONDS] [--scenes cornell,office,furnace] [--threads N]\n"
                 "          [--methods BACKEND:N[:RELAXATION[:overshoot][:afresh]],...]\n",
                 argv[0]);
    return 2;
  }
  std::optional<tbb::global_control> control;
  if (threads > 0) control.emplace(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
  const auto wants = [&](const char* name) { return scenes.find(name) != std::string::npos; };

  std::printf("| method | resolution | relaxation | overshoot | factors | Cornell box (to 1 %%) | office (to 1 %%) "
              "| furnace RMS / worst (to 1e-4) |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  std::fflush(stdout);
  const Scene cornell = make_cornell_box();
  const Scene office = make_office();
  const Scene furnace = make_furnace();
  for (const Method& method : methods) {
    std::string cornell_cell = "-", office_cell = "-", furnace_cell = "-";
    if (wants("cornell")) cornell_cell = cell(solve(cornell, method, 0.01, 1, true, budget));
    if (wants("office")) office_cell = cell(solve(office, method, 0.01, 1, true, budget));
    if (wants("furnace")) {
      // As the furnace test: no substructuring, 2 x 2 Gauss points per shooting patch.
      const Result r = solve(furnace, method, 1e-4, 2, false, budget);
      char text[160];
      std::snprintf(text, sizeof text, "%.3f %% / %.3f %% (%.1f s%s)", 100.0 * r.rms, 100.0 * r.worst, r.seconds,
                    r.finished ? "" : ", stopped");
      furnace_cell = text;
    }
    std::printf("| %s | %d | %g | %s | %s | %s | %s | %s |\n", method.backend.c_str(), method.resolution,
                method.relaxation, method.overshoot ? "ambient" : "-", method.afresh ? "afresh" : "reused",
                cornell_cell.c_str(), office_cell.c_str(), furnace_cell.c_str());
    std::fflush(stdout);
  }
  return 0;
}
