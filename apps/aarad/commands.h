// Sub-command registration. Each add_*_command attaches a CLI11 sub-command whose callback runs the job
// and sets the exit code through set_exit_code(); errors propagate as aarad::Error.
#pragma once

namespace CLI { class App; }

namespace aarad::app {

void add_commands(CLI::App& app);
void add_inspect_command(CLI::App& app);
void add_formfactors_command(CLI::App& app);
void add_solve_command(CLI::App& app);

void set_exit_code(int code);
int exit_code();

}  // namespace aarad::app
