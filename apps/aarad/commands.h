// Sub-command registration. Each add_*_command attaches a CLI11 sub-command whose callback runs the job
// and sets the exit code through set_exit_code(); errors propagate as aarad::Error.
#pragma once

#include <CLI/CLI.hpp>

#include <limits>
#include <string>

namespace aarad {
class Scene;
namespace formfactor {
class FormFactorBackend;
}
}  // namespace aarad

namespace aarad::app {

void add_commands(CLI::App& app);
void add_inspect_command(CLI::App& app);
void add_formfactors_command(CLI::App& app);
void add_solve_command(CLI::App& app);

// A CLI11 check: the option's value is a number in the interval from `low` to `high` (either may be infinite),
// each end included or not. NaN is refused, and the message shows the interval as written in the docs.
enum class End { kOpen, kClosed };
CLI::Validator number_in(double low, End low_end, double high, End high_end);
// A CLI11 transform for integer options: the value is a whole number (decimal digits, optional sign) from `low` to
// `high`, both included; `high` = kNoLimit means no upper bound. "1.5", "1e3" or "12x" are refused with a message
// that says a whole number is wanted, instead of CLI11's "not in range" or "could not convert". Leading zeros are
// decimal ("010" is 10): the value is passed on rewritten without them, which CLI11 would otherwise read as octal.
// Attach it with Option::transform(), not check(): check() hands the validator a copy and drops the rewrite.
inline constexpr long long kNoLimit = std::numeric_limits<long long>::max();
CLI::Validator whole_number_in(long long low, long long high = kNoLimit);

// Prints the scene's warnings on stderr, one line each, control characters shown as \xNN (printable): they are
// problems the user must see, so they go out even with --quiet.
void print_scene_warnings(const Scene& scene);

// Warns on stderr when `backend` ignores visibility and surfaces of `scene` can hide one another: its result
// then has no shadows.
void warn_if_visibility_is_ignored(const Scene& scene, const formfactor::FormFactorBackend& backend);

void set_exit_code(int code);
int exit_code();

// Flushes stdout. Output there is buffered, so a full disk (`> /dev/full`) or a descriptor that cannot be written
// shows only when it is flushed: returns why stdout lost output (the first failure, also one of an earlier call),
// empty when all of it went out. main() calls it after every command and then exits 1 (docs/solver.md), not 0.
std::string flush_stdout();

}  // namespace aarad::app
