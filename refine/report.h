// The solve report (docs/solver.md, "The report") as JSON: {"scene", "method", "resolution", "converged",
// "interrupted", "shots", "unshot_fraction", "emitted_flux", "absorbed_flux", "patches", "elements",
// "max_level", "seconds": {"total", "form_factors", "subdivision", "output"}, "invariants": {"violations"},
// "groups": [{"name", "area", "elements", "mean_radiosity"}]}, colours as [r, g, b]. Extra fields (the options
// used, unshot_flux, escaped_flux, ambient, splits, element_limit_reached, diverged, reused_shots) are additions;
// the contract's fields keep their names and meaning.
#pragma once

#include "aarad/mesh/invariants.h"
#include "aarad/refine/solver.h"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace aarad::refine {

struct ReportTimes {
  double total = -1.0;   // wall time of the whole command; < 0 uses the solver's run() time plus output
  double output = 0.0;   // writing the files
};

nlohmann::json rgb_json(const Rgb& colour);

// The text of a JSON report, `indent` as nlohmann::json::dump. Names come from the user's files and need not be
// UTF-8 (a Latin-1 "K\xfcche"): invalid bytes become U+FFFD instead of an exception after the work is done.
template <class Json>
std::string json_text(const Json& report, int indent = -1) {
  return report.dump(indent, ' ', false, Json::error_handler_t::replace);
}

// `violations` is the result of mesh::check_invariants on the solver's hierarchy after the solve.
nlohmann::json make_report(const Solver& solver, const std::vector<mesh::Violation>& violations,
                           const ReportTimes& times = {});

}  // namespace aarad::refine
