#include "apps/aarad/commands.h"

#include "aarad/core/error.h"
#include "aarad/core/scene.h"
#include "aarad/formfactor/backend.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

namespace aarad::app {
namespace {
int g_exit_code = 0;

// CLI11 shows a flag pair such as "--adaptive,!--no-adaptive" as "--adaptive,--no-adaptive{false}" (the value
// the second name stores), which reads like a default of false. The help shows the names as they are typed; the
// description says which is the default.
class HelpFormatter : public CLI::Formatter {
 public:
  std::string make_option_name(const CLI::Option* option, bool is_positional) const override {
    std::string names = CLI::Formatter::make_option_name(option, is_positional);
    for (std::size_t open = names.find('{'); open != std::string::npos; open = names.find('{', open)) {
      const std::size_t close = names.find('}', open);
      if (close == std::string::npos) break;
      names.erase(open, close + 1 - open);
    }
    return names;
  }
};

}  // namespace

void add_commands(CLI::App& app) {
  app.formatter(std::make_shared<HelpFormatter>());  // before the sub-commands, which copy it
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

CLI::Validator whole_number_in(long long low, long long high) {
  const std::string wanted =
      high == kNoLimit ? ">= " + std::to_string(low) : "in [" + std::to_string(low) + ", " + std::to_string(high) + "]";
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        const std::size_t sign = !text.empty() && (text[0] == '-' || text[0] == '+') ? 1 : 0;
        const bool whole = sign < text.size() && text.find_first_not_of("0123456789", sign) == std::string::npos;
        errno = 0;
        const long long value = whole ? std::strtoll(text.c_str(), nullptr, 10) : 0;
        if (whole && errno == ERANGE) {
          return "Value " + text + " is beyond a 64-bit integer: it must be a whole number in [" +
                 std::to_string(low) + ", " + std::to_string(high) + "]";
        }
        if (!whole || errno != 0 || value < low || value > high) {
          return "Value " + text + " must be a whole number " + wanted;
        }
        // CLI11 converts integers with base 0: "010" would be octal 8 and "08" no number at all. The docs promise
        // decimal, so the option receives the value in decimal without leading zeros.
        text = std::to_string(value);
        return {};
      },
      wanted);
}

void print_scene_warnings(const Scene& scene) {
  for (const std::string& warning : scene.warnings)
    std::fprintf(stderr, "aarad: warning: %s\n", printable(warning).c_str());
}

void warn_if_visibility_is_ignored(const Scene& scene, const formfactor::FormFactorBackend& backend) {
  if (backend.tests_visibility()) return;
  const std::optional<Scene::OcclusionWitness> witness = scene.occlusion_witness();
  if (!witness) return;
  const auto group_of = [&](std::uint32_t surface) { return scene.groups[scene.surfaces[surface].group].name; };
  std::fprintf(stderr,
               "aarad: warning: the %s back end ignores visibility, but in %s surfaces may hide one another (a "
               "vertex of group '%s' lies behind the plane of group '%s'), so its result has no shadows; it is exact "
               "only where every surface lies on or in front of every other's plane\n",
               std::string(backend.name()).c_str(), scene.name.c_str(), group_of(witness->behind).c_str(),
               group_of(witness->front).c_str());
}

void set_exit_code(int code) { g_exit_code = code; }
int exit_code() { return g_exit_code; }

std::string flush_stdout() {
  static std::string failure;  // the first, with its reason: a failed flush empties the buffer and the next succeeds
  if (!failure.empty()) return failure;
  errno = 0;
  const bool flushed = std::fflush(stdout) == 0;
  const int reason = errno;
  // std::cout is synchronised with stdio (the default): its text went to stdout's buffer, or failed there.
  if (flushed && !std::ferror(stdout) && !std::cout.bad()) return {};
  // A write that failed when a full buffer went out sets the error flag, but its errno is gone.
  failure = !flushed && reason != 0 ? std::strerror(reason) : "part of the output was lost";
  return failure;
}

}  // namespace aarad::app
