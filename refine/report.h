// The solve report of ../shared/design.md as JSON: {"scene", "method", "resolution", "converged",
// "interrupted", "shots", "unshot_fraction", "emitted_flux", "absorbed_flux", "patches", "elements",
// "max_level", "seconds": {"total", "form_factors", "subdivision", "output"}, "invariants": {"violations"},
// "groups": [{"name", "area", "elements", "mean_radiosity"}]}, colours as [r, g, b]. Extra fields (the options
// used, unshot_flux, ambient, splits) are additions; the contract's fields keep their names and meaning.
#pragma once

#include "mesh/invariants.h"
#include "refine/solver.h"

#include <nlohmann/json.hpp>

#include <vector>

namespace aarad::refine {

struct ReportTimes {
  double total = -1.0;   // wall time of the whole command; < 0 uses the solver's run() time plus output
  double output = 0.0;   // writing the files
};

nlohmann::json rgb_json(const Rgb& colour);

// `violations` is the result of mesh::check_invariants on the solver's hierarchy after the solve.
nlohmann::json make_report(const Solver& solver, const std::vector<mesh::Violation>& violations,
                           const ReportTimes& times = {});

}  // namespace aarad::refine
