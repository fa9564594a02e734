#include "apps/aarad/commands.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace aarad::app {
namespace {
int g_exit_code = 0;
}

void add_commands(CLI::App& app) {
  add_inspect_command(app);
  add_formfactors_command(app);
  add_solve_command(app);
}

CLI::Validator number_in(double low, End low_end, double high, End high_end) {
  const auto format = [](double value) {
    char text[32];
    std::snprintf(text, sizeof text, "%g", value);
    return std::string(text);
  };
  // As the docs write it: "> 0", ">= 0" for a half line, "[1, 2)" for an interval.
  std::string wanted;
  if (std::isinf(high) && high > 0.0) {
    wanted = (low_end == End::kOpen ? "> " : ">= ") + format(low);
  } else {
    wanted = (low_end == End::kOpen ? "(" : "[") + format(low) + ", " + format(high) +
             (high_end == End::kOpen ? ")" : "]");
  }
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        char* end = nullptr;
        const double value = std::strtod(text.c_str(), &end);
        const bool number = end != text.c_str() && *end == '\0' && !std::isnan(value);
        const bool above = low_end == End::kOpen ? value > low : value >= low;
        const bool below = high_end == End::kOpen ? value < high : value <= high;
        if (number && above && below) return {};
        return "Value " + text + " must be a " + (high_end == End::kOpen && std::isinf(high) ? "finite " : "") +
               "number " + (wanted.front() == '>' ? "" : "in ") + wanted;
      },
      wanted);
}

void set_exit_code(int code) { g_exit_code = code; }
int exit_code() { return g_exit_code; }

}  // namespace aarad::app
