#include "apps/aarad/commands.h"

namespace aarad::app {
namespace {
int g_exit_code = 0;
}

void add_commands(CLI::App& app) {
  add_inspect_command(app);
  add_formfactors_command(app);
  add_solve_command(app);
}

void set_exit_code(int code) { g_exit_code = code; }
int exit_code() { return g_exit_code; }

}  // namespace aarad::app
