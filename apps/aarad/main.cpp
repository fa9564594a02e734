// aarad: the command-line program. Each sub-command lives in its own cmd_*.cpp and registers itself here.
#include "apps/aarad/commands.h"

#include "aarad/core/error.h"

#include <CLI/CLI.hpp>

#include <csignal>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <new>
#include <regex>
#include <string>
#include <system_error>

namespace {

// Parses the command line and runs the command; returns the exit code of docs/solver.md.
int run(int argc, char** argv) {
  CLI::App app{"aarad: progressive-refinement radiosity with anti-aliased hemicubes"};
  // Usage errors read like every other error, and say where the options are listed. Set before the commands are
  // added: each takes its parent's.
  app.failure_message([argc, argv](const CLI::App* parsed, const CLI::Error& e) {
    std::string what = e.what();
    // CLI11's words for an option given twice ("--resolution: At Most 1 required but received 2").
    static const std::regex kGivenTwice(R"(^(\S+): At Most 1 required but received (\d+)$)");
    std::smatch given;
    if (std::regex_match(what, given, kGivenTwice))
      what = given[1].str() + " is given " + given[2].str() + " times; give it once";
    std::string help = "aarad --help";
    std::string command_name = "COMMAND";
    for (const CLI::App* command : parsed->get_subcommands()) {
      help = "aarad " + command->get_name() + " --help";
      command_name = command->get_name();
    }
    // A scene file whose name starts with '-' reads as an option ("scene is required" was all CLI11 said).
    for (int i = 2; i < argc; ++i) {
      const std::string arg = argv[i];
      if (arg == "--") break;
      std::error_code error;
      if (arg.size() < 2 || arg[0] != '-' || !std::filesystem::is_regular_file(arg, error)) continue;
      what += "; '" + arg + "' is a file, but a name starting with '-' reads as an option: give it after '--' "
              "(aarad " + command_name + " -- " + arg + ")";
      break;
    }
    return "aarad: error: " + what + " (" + help + " lists the options)\n";
  });
  app.require_subcommand(1);
  app.set_version_flag("--version", "aarad 0.1.0");
  aarad::app::add_commands(app);
  // CLI11 would only say that a subcommand is required: name the unknown one, or the option given before any
  // command, and the known commands.
  if (argc > 1) {
    const std::string first = argv[1];
    std::string known;
    bool found = first == "-h" || first == "--help" || first == "--version";
    for (const CLI::App* command : app.get_subcommands([](const CLI::App*) { return true; })) {
      found = found || command->check_name(first);
      known += (known.empty() ? "" : ", ") + command->get_name();
    }
    if (!found) {
      if (first.starts_with("-")) {
        std::fprintf(stderr,
                     "aarad: error: unknown option '%s' before the command; options follow the command, which is "
                     "one of %s (aarad --help)\n",
                     first.c_str(), known.c_str());
      } else {
        std::fprintf(stderr, "aarad: error: unknown command '%s'; the commands are %s (aarad --help)\n",
                     first.c_str(), known.c_str());
      }
      return 2;
    }
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version exit 0; every usage error exits 2, whatever CLI11's own code for it.
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;
  } catch (const aarad::Error& e) {
    std::fprintf(stderr, "aarad: error: %s\n", aarad::printable(e.what()).c_str());
    return 1;
  } catch (const std::bad_alloc&) {
    // Out of memory is an internal error too (exit code 3), said in words.
    std::fprintf(stderr,
                 "aarad: internal error: out of memory (std::bad_alloc); fewer elements (a larger --element-size, "
                 "--min-area or a lower --max-level), smaller images (--width, --height) or a lower hemicube "
                 "--resolution need less\n");
    return 3;
  } catch (const std::exception& e) {
    // Anything else (a bug) is an internal error: exit code 3 (docs/solver.md).
    std::fprintf(stderr, "aarad: internal error: %s\n", e.what());
    return 3;
  }
  return aarad::app::exit_code();
}

}  // namespace

int main(int argc, char** argv) {
  const int code = run(argc, argv);
  // Output on stdout (a report, --help) that did not get out is an error (exit 1), also after a stop signal (130
  // for Ctrl-C, 143 for SIGTERM, 129 for SIGHUP); an error's own exit code stays.
  const std::string lost = aarad::app::flush_stdout();
  if (!lost.empty()) {
    std::fprintf(stderr, "aarad: error: cannot write to standard output: %s\n", lost.c_str());
    if (code == 0 || code == 128 + SIGINT || code == 128 + SIGTERM || code == 128 + SIGHUP) return 1;
  }
  return code;
}
