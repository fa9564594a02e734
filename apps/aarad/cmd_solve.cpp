// `aarad solve [SCENE]`: progressive-refinement radiosity with adaptive substructuring (refine/solver.h),
// progress on stderr, Ctrl-C to stop after the current shot, and the output files of ../shared/design.md.
// Exit codes (docs/solver.md): 0 converged or stopped at --max-shots, 1 bad input or output (stdout in main.cpp),
// 2 usage, 3 internal error (main.cpp), 130 interrupted by Ctrl-C (143 by SIGTERM, 129 by SIGHUP).
#include "apps/aarad/commands.h"

#include "aarad/core/builtin_scenes.h"
#include "aarad/core/error.h"
#include "aarad/mesh/invariants.h"
#include "aarad/refine/output.h"
#include "aarad/refine/report.h"
#include "aarad/refine/solver.h"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <unistd.h>
#include <vector>

namespace aarad::app {
namespace {

// Ctrl-C (SIGINT), and SIGTERM and SIGHUP alike (docs/solver.md): a batch system or a closed terminal asks a
// solve to stop the same way. During the solve the first stops it after the current shot, and the second ends the
// program at once (the default action), as nothing is being written yet. Once the solve is over, files are being
// written, and a signal must not end the program in the middle of one (its temporary would stay behind): the first
// lets every file be written, the next stops after the file being written. The exit code is 128 + the first
// signal's number: 130 for Ctrl-C, 143 for SIGTERM, 129 for SIGHUP.
constexpr int kStopSignals[] = {SIGINT, SIGTERM, SIGHUP};
std::atomic<int> g_interrupts{0};
std::atomic<int> g_first_signal{0};
std::atomic<int> g_last_signal{0};
std::atomic<unsigned> g_handled_signals{0};  // bit k: kStopSignals[k] gets our handlers (StopSignalGuard)
std::atomic<bool> g_quiet{false};
static_assert(std::atomic<int>::is_always_lock_free && std::atomic<bool>::is_always_lock_free &&
                  std::atomic<unsigned>::is_always_lock_free,
              "the signal handlers need lock-free atomics");

// How the messages name a signal.
const char* signal_label(int signal) {
  switch (signal) {
    case SIGINT: return "Ctrl-C";
    case SIGTERM: return "SIGTERM";
    case SIGHUP: return "SIGHUP";
    default: return "a signal";
  }
}

// Counts the signal; returns how many have come.
int note_signal(int signal) {
  int none = 0;
  g_first_signal.compare_exchange_strong(none, signal);
  g_last_signal.store(signal);
  return g_interrupts.fetch_add(1) + 1;
}

extern "C" void on_signal_while_solving(int signal) {
  const int saved_errno = errno;  // the interrupted code may be about to read it
  note_signal(signal);
  // A second stop signal of any of the three ends the program: each goes back to its default action.
  // (sigaction is async-signal-safe.)
  for (std::size_t k = 0; k < std::size(kStopSignals); ++k) {
    if ((g_handled_signals.load() >> k & 1u) == 0) continue;
    struct sigaction action {};
    action.sa_handler = SIG_DFL;
    sigemptyset(&action.sa_mask);
    sigaction(kStopSignals[k], &action, nullptr);
  }
  errno = saved_errno;
}

// Appends `text` to buffer[at..] within `size` bytes; async-signal-safe (no library call).
std::size_t append(char* buffer, std::size_t size, std::size_t at, const char* text) {
  while (*text != '\0' && at < size) buffer[at++] = *text++;
  return at;
}

extern "C" void on_signal_while_writing(int signal) {
  const int saved_errno = errno;  // a failed write of a file may be about to read it (core/atomic_file.cpp)
  const int interrupts = note_signal(signal);
  if (g_quiet.load()) {
    errno = saved_errno;
    return;
  }
  // write(2) is async-signal-safe, stdio is not.
  const char* label = signal_label(signal);
  char line[160];
  std::size_t n = append(line, sizeof line, 0, "aarad: ");
  n = append(line, sizeof line, n, label);
  if (interrupts == 1) {
    n = append(line, sizeof line, n, ": writing the files to the end; ");
    n = append(line, sizeof line, n, label);
    n = append(line, sizeof line, n, " again to stop after the file being written\n");
  } else {
    n = append(line, sizeof line, n, ": stopping after the file being written\n");
  }
  [[maybe_unused]] const ssize_t written = ::write(STDERR_FILENO, line, n);
  errno = saved_errno;
}

// Handles the stop signals with the handler given last to handle(), and restores the previous handling when it
// ends. A signal the parent set to be ignored stays ignored: a shell runs a background job (`aarad solve ... &`)
// with SIGINT ignored, and a Ctrl-C meant for the script that started it interrupted the solve; `nohup` ignores
// SIGHUP.
class StopSignalGuard {
 public:
  StopSignalGuard() {
    for (std::size_t k = 0; k < std::size(kStopSignals); ++k) {
      sigaction(kStopSignals[k], nullptr, &previous_[k]);
      if (previous_[k].sa_handler != SIG_IGN || (previous_[k].sa_flags & SA_SIGINFO)) handled_ |= 1u << k;
    }
    g_handled_signals.store(handled_);
  }
  ~StopSignalGuard() {
    g_handled_signals.store(0);
    for (std::size_t k = 0; k < std::size(kStopSignals); ++k) sigaction(kStopSignals[k], &previous_[k], nullptr);
  }
  StopSignalGuard(const StopSignalGuard&) = delete;
  StopSignalGuard& operator=(const StopSignalGuard&) = delete;

  // SA_RESTART: a write to a pipe that a signal interrupts goes on instead of failing with EINTR.
  void handle(void (*handler)(int)) {
    for (std::size_t k = 0; k < std::size(kStopSignals); ++k) {
      if ((handled_ >> k & 1u) == 0) continue;
      struct sigaction action {};
      action.sa_handler = handler;
      sigemptyset(&action.sa_mask);
      for (const int other : kStopSignals) sigaddset(&action.sa_mask, other);  // one handler at a time
      action.sa_flags = SA_RESTART;
      sigaction(kStopSignals[k], &action, nullptr);
    }
  }

 private:
  struct sigaction previous_[std::size(kStopSignals)] {};
  unsigned handled_ = 0;  // bit k: kStopSignals[k] was not ignored when the guard began, and gets our handlers
};

// The exit code after a stop signal: 128 + the first one's number.
int signal_exit_code() { return 128 + g_first_signal.load(); }

struct SolveCommandOptions {
  std::string scene = "cornell";
  std::string out;
  bool json = false;
  bool quiet = false;
  int threads = 0;
  int width = 512;
  int height = 512;
  refine::SolverOptions solver;
  // Meshing options given on the command line (otherwise refine::default_meshing for the scene).
  std::optional<double> patch_size, element_size, min_area;
  std::optional<int> max_level;
  bool balance = false;
};

// Progress on stderr: a bar rewritten in place on a terminal, a plain line every few seconds otherwise.
class ProgressPrinter {
 public:
  ProgressPrinter(bool enabled, double converge)
      : enabled_(enabled), terminal_(::isatty(STDERR_FILENO) == 1), converge_(converge) {}

  void update(const refine::Progress& p) {
    if (!enabled_) return;
    if (terminal_) {
      if (printed_ && p.seconds - last_ < 0.1) return;
      // Fill: progress towards --converge on a log scale (unshot falls about geometrically).
      double fill = 1.0;
      if (converge_ > 0.0 && converge_ < 1.0 && p.unshot_fraction > 0.0) {
        fill = std::clamp(std::log(p.unshot_fraction) / std::log(converge_), 0.0, 1.0);
      }
      constexpr int kWidth = 24;
      const int filled = static_cast<int>(std::lround(fill * kWidth));
      std::string bar(static_cast<std::size_t>(filled), '#');
      bar.append(static_cast<std::size_t>(kWidth - filled), '.');
      std::fprintf(stderr, "\r[%s] shot %lld  unshot %.3f %%  %zu elements  %.1f s ", bar.c_str(),
                   static_cast<long long>(p.shots), 100.0 * p.unshot_fraction, p.elements, p.seconds);
    } else {
      if (printed_ && p.seconds - last_ < 2.0) return;
      std::fprintf(stderr, "aarad: shot %lld, unshot %.3f %%, %zu elements, %.1f s\n",
                   static_cast<long long>(p.shots), 100.0 * p.unshot_fraction, p.elements, p.seconds);
    }
    std::fflush(stderr);
    printed_ = true;
    last_ = p.seconds;
  }

  void finish() {
    if (enabled_ && terminal_ && printed_) std::fputc('\n', stderr);
  }

 private:
  bool enabled_;
  bool terminal_;
  double converge_;
  bool printed_ = false;
  double last_ = 0.0;
};

std::string default_out_directory(const Scene& scene) {
  std::string name = std::filesystem::path(scene.name).stem().string();
  if (name.empty()) name = "scene";
  return (std::filesystem::path("out") / name).string();
}

void run_solve(SolveCommandOptions options) {
  const auto start = std::chrono::steady_clock::now();
  std::optional<tbb::global_control> threads;
  if (options.threads > 0) {
    threads.emplace(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(options.threads));
  }

  const Scene scene = load_scene(options.scene);
  // Warnings go to stderr even with --quiet, which silences only the progress and the summary.
  print_scene_warnings(scene);
  refine::SolverOptions solver_options = options.solver;
  solver_options.meshing = refine::default_meshing(scene);
  // A scene's sizes were chosen together: a patch or element size on the command line replaces all three, and
  // what the command line leaves out takes the hierarchy's default (elements half the patch size, min area
  // 1e-7 d^2), as --help says. Otherwise --patch-size 10 on the Cornell box would keep its 70 mm elements and
  // 60 mm^2 min area: patches that are their own only element and can never split.
  if (options.patch_size || options.element_size) {
    solver_options.meshing.patch_size = 0.0;
    solver_options.meshing.element_size = 0.0;
    solver_options.meshing.min_area = 0.0;
  }
  if (options.patch_size) solver_options.meshing.patch_size = *options.patch_size;
  if (options.element_size) solver_options.meshing.element_size = *options.element_size;
  if (options.min_area) solver_options.meshing.min_area = *options.min_area;
  if (options.max_level) solver_options.meshing.max_level = *options.max_level;
  solver_options.meshing.balance = options.balance;
  std::filesystem::path out = options.out.empty() ? default_out_directory(scene) : options.out;
  // Without its trailing separators, so that the notes' "wrote DIR/" does not read "o//" for `--out o/`.
  while (!out.has_filename() && out.has_relative_path()) out = out.parent_path();
  refine::check_output_directory(out);  // now, not after the solve

  // A mesh too large for its sizes: when they are the scene's own, the error says where they were written.
  std::optional<refine::Solver> made;
  try {
    made.emplace(scene, solver_options);
  } catch (const Error& e) {
    const bool from_comment =
        scene.meshing && scene.meshing->source_line > 0 && !options.patch_size && !options.element_size;
    if (!from_comment || !std::string_view(e.what()).starts_with("meshing:")) throw;
    throw Error(std::string(e.what()) + " (the sizes are those of the '# aarad meshing:' comment at " + scene.name +
                ":" + std::to_string(scene.meshing->source_line) + "; --patch-size and --element-size replace them)");
  }
  refine::Solver& solver = *made;
  // Ke x area cannot underflow: Ke is 0 or at least 1e-100 (kMinEmission), and a face at least 1e-50 across with
  // an area of at least 1e-12 of its size squared (core/face_check.h).
  if (!(solver.emitted_flux().sum() > 0.0)) {
    throw Error(scene.name + ": nothing in the scene emits light (no material with Ke above 0), so the solution "
                "would be black" +
                (scene.warnings.empty() ? std::string() : " (see the warnings above)"));
  }
  warn_if_visibility_is_ignored(scene, solver.backend());
  const bool show_progress = !options.quiet;
  if (show_progress) {
    std::fprintf(stderr, "aarad: %s: %zu patches, %zu elements; %s at resolution %d\n", scene.name.c_str(),
                 solver.hierarchy().patches().size(), solver.hierarchy().leaf_count(),
                 std::string(solver.backend().name()).c_str(), solver_options.resolution);
  }

  ProgressPrinter printer(show_progress, solver_options.converge);
  {
    g_interrupts.store(0);
    g_first_signal.store(0);
    g_quiet.store(options.quiet);
    StopSignalGuard signals;
    signals.handle(on_signal_while_solving);
    solver.run([&](const refine::Progress& progress) {
      printer.update(progress);
      return g_interrupts.load() == 0;
    });
    // From here on, files are written: no signal ends the program in the middle of one.
    signals.handle(on_signal_while_writing);
    const auto keep_writing = [] { return g_interrupts.load() < 2; };
    printer.finish();
    if (solver.interrupted() && !options.quiet) {
      const char* label = signal_label(g_first_signal.load());
      std::fprintf(stderr,
                   "aarad: interrupted by %s after %lld shots; writing the solution so far (%s again to stop after "
                   "the file being written)\n",
                   label, static_cast<long long>(solver.shots()), label);
    }

    // Flux shot past every receiver. All of it, with shots made, is nearly always a scene whose emitters face
    // away from everything (faces are one-sided): a warning. A part of it is an open scene: the summary says how much.
    const double shot_flux = (solver.emitted_flux() - solver.unshot_flux()).sum();
    const double escaped = solver.escaped_flux().sum();
    if (shot_flux > 0.0 && escaped >= 0.999 * shot_flux) {
      // "None" only when none did: a lamp lighting a little of an open scene of bright surfaces also gets here.
      const double reached = 1.0 - escaped / shot_flux;
      char amount[32] = "none";
      if (reached > 1e-12) std::snprintf(amount, sizeof amount, "only %.2g %%", 100.0 * reached);
      std::fprintf(stderr,
                   "aarad: warning: %s of the light shot reached a surface: do the emitters face the scene? A face "
                   "emits and receives on its front side only, the side from which its vertices run "
                   "counter-clockwise\n",
                   amount);
    }

    // The books that do not balance, even with --quiet.
    const double emitted = solver.emitted_flux().sum();
    if (escaped < -0.01 * emitted && !options.solver.overshoot && !(options.solver.relaxation > 1.0)) {
      // More absorbed and still unshot than was emitted: form factors from some point add up to more than 1.
      // (Over-relaxation and overshooting take back flux that earlier shots sent out of the scene: with them
      // the escaped flux may be below 0 for a while.)
      std::fprintf(stderr,
                   "aarad: warning: %.1f %% more flux than was emitted is absorbed or still unshot: the form factors "
                   "from some patches add up to more than 1%s\n",
                   -100.0 * escaped / emitted,
                   options.solver.backend == "analytic" ? " (the analytic back end ignores occlusion)" : "");
    }
    const Rgb absorbed = solver.absorbed_flux();
    if (!solver.diverged() && std::min({absorbed.r, absorbed.g, absorbed.b}) < 0.0) {
      // Over-relaxation and overshooting shoot flux that later shots take back; a negative total absorbed means
      // radiosities below zero, which a converged solve does not leave.
      std::fprintf(stderr,
                   "aarad: warning: the absorbed flux is negative (%.3g): some radiosities are below zero, and the "
                   "images clip them to black; %s\n",
                   absorbed.sum(),
                   options.solver.relaxation > 1.0 ? "--relaxation sends back too much here: try a smaller one"
                                                   : "solve to a smaller --converge");
    }

    // Once, even with --quiet: the mesh is coarser than --gradient asks where splits were refused.
    if (solver.element_limit_reached()) {
      std::fprintf(stderr,
                   "aarad: warning: substructuring reached the limit of %lld elements (--max-elements) and split "
                   "no further, so the mesh is coarser than --gradient asks; raise --max-elements (each element "
                   "takes about 1 KiB), --gradient or --min-area, or lower --max-level\n",
                   static_cast<long long>(solver_options.max_elements));
    }

    // radiosity.exr stores single precision: beyond it, a pixel is inf, and below it 0 or coarse (mesh.ply switches
    // to doubles there, and the PNGs are tone-mapped from values scaled into range).
    const std::vector<Rgb> displayed = solver.displayed_radiosity();
    double brightest = 0.0, faintest = std::numeric_limits<double>::infinity();
    for (const mesh::NodeId leaf : solver.hierarchy().leaves()) {
      for (int c = 0; c < 3; ++c) {
        const double value = displayed[leaf][c];
        brightest = std::max(brightest, value);
        if (value > 0.0) faintest = std::min(faintest, value);
      }
    }
    if (brightest > std::numeric_limits<float>::max()) {
      std::fprintf(stderr,
                   "aarad: warning: radiosities up to %.3g exceed single precision (3.4e38): radiosity.exr holds inf "
                   "there; scale the emission (Ke) down, radiosity is linear in it\n",
                   brightest);
    }
    if (faintest < std::numeric_limits<float>::min()) {
      std::fprintf(stderr,
                   "aarad: warning: radiosities down to %.3g are below single precision (1.2e-38): radiosity.exr "
                   "holds 0 or loses digits there; scale the emission (Ke) up, radiosity is linear in it\n",
                   faintest);
    }

    // The hierarchy's invariants, and those of the display reconstruction the images and the PLY are made from.
    std::vector<mesh::Violation> violations = mesh::check_invariants(solver.hierarchy());
    const std::vector<mesh::Violation> display = mesh::check_display(
        solver.hierarchy(), mesh::build_display_mesh(solver.hierarchy(), displayed));
    violations.insert(violations.end(), display.begin(), display.end());
    // The first few on stderr; report.json lists every one.
    constexpr std::size_t kShown = 10;
    for (std::size_t i = 0; i < std::min(violations.size(), kShown); ++i) {
      std::fprintf(stderr, "aarad: warning: invariant %s violated: %s\n", violations[i].invariant.c_str(),
                   violations[i].message.c_str());
    }
    if (violations.size() > kShown) {
      std::fprintf(stderr, "aarad: warning: and %zu more invariant violations, listed in report.json\n",
                   violations.size() - kShown);
    }
    const refine::OutputResult files = refine::write_solution_files(
        solver, out, {.width = options.width, .height = options.height, .keep_writing = keep_writing});
    if (!files.complete || !keep_writing()) {
      // A second Ctrl-C: what was written is whole, the rest (report.json last) is not written.
      if (!options.quiet) {
        std::string written;
        for (const std::filesystem::path& file : files.files) written += " " + file.filename().string();
        std::fprintf(stderr, "aarad: stopped by %s; %s\n", signal_label(g_last_signal.load()),
                     written.empty() ? "no file written"
                                     : ("wrote" + written + " in " + out.string() + "/, not the rest").c_str());
      }
      set_exit_code(signal_exit_code());
      return;
    }
    const double total = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const nlohmann::json report = refine::make_report(solver, violations, {.total = total, .output = files.seconds});
    refine::write_report(report, out / "report.json");

    if (options.json) {
      std::cout << refine::json_text(report) << '\n';
      flush_stdout();  // before the summary on stderr; main() reports a failure
    }
    if (!options.quiet) {
      std::FILE* summary = options.json ? stderr : stdout;
      const char* state = solver.converged()     ? "converged"
                          : solver.interrupted() ? "interrupted"
                          : solver.diverged()    ? "diverged"
                                                 : "stopped at --max-shots";
      std::fprintf(summary, "aarad: %s after %lld shots (unshot %.3f %%), %zu elements, max level %d, %.2f s\n",
                   state, static_cast<long long>(solver.shots()), 100.0 * solver.unshot_fraction(),
                   solver.hierarchy().leaf_count(), solver.max_leaf_level(), total);
      if (escaped > 0.01 * emitted) {
        std::fprintf(summary, "aarad: %.1f %% of the emitted flux left the scene (an open scene, or faces turned away)\n",
                     100.0 * escaped / emitted);
      }
      std::fprintf(summary,
                   "aarad: wrote %s/: mesh.ply flat.png smooth.png mesh.png radiosity.exr report.json\n",
                   out.string().c_str());
    }
  }
  // The report describes the solve ("interrupted" when a signal stopped the shots); a signal while the files were
  // written also gives 128 + its number. A solve that diverged wrote what it had, for a look, and fails.
  if (solver.diverged()) {
    // Why, as far as the options tell: overshooting's ambient term assumes a closed scene; the analytic back end's
    // factors ignore occlusion, so from a patch that sees surfaces behind one another they add up to more than 1.
    // Overshooting is blamed for an open scene only where light does leave it (escaped flux).
    std::vector<std::string> causes;
    if (options.solver.backend == "analytic") {
      causes.push_back("the analytic back end ignores what hides one surface from another, so the form factors from "
                       "some patch add up to more than 1; use --ff aa-hemicube");
    }
    if (options.solver.overshoot && solver.escaped_flux().sum() > 0.01 * solver.emitted_flux().sum()) {
      causes.push_back("overshooting sends rho x the ambient term on top of each shot, and that term assumes a closed "
                       "scene: where light leaves the scene it sends out more than comes back; solve without "
                       "--overshoot");
    }
    if (options.solver.relaxation > 1.0) {
      causes.push_back(std::string("--relaxation sends too much back") +
                       (options.solver.overshoot ? " on top of overshooting's ambient term" : "") +
                       "; try a smaller one");
    }
    if (causes.empty()) {
      causes.push_back(options.solver.overshoot
                           ? "overshooting's ambient term sends out more than comes back; solve without --overshoot"
                           : "the form factors from some patch add up to more than 1");
    }
    std::string why = causes.front();
    for (std::size_t i = 1; i < causes.size(); ++i) why += "; or " + causes[i];
    std::fprintf(stderr,
                 "aarad: error: the solve diverged: after %lld shots the net unshot flux is %.3g times the emitted "
                 "flux; %s\n",
                 static_cast<long long>(solver.shots()), solver.net_unshot_fraction(), why.c_str());
  }
  set_exit_code(g_interrupts.load() > 0 ? signal_exit_code() : solver.diverged() ? 1 : 0);
}

}  // namespace

void add_solve_command(CLI::App& app) {
  auto options = std::make_shared<SolveCommandOptions>();
  constexpr double kInfinity = std::numeric_limits<double>::infinity();
  const CLI::Validator size = number_in(0.0, End::kClosed, kInfinity, End::kOpen);  // 0: from the scene's size
  CLI::App* cmd = app.add_subcommand(
      "solve", "Progressive-refinement radiosity with adaptive substructuring; writes mesh, images and report");
  cmd->add_option("scene", options->scene, "Built-in scene (cornell, office, furnace) or OBJ file")
      ->capture_default_str();
  cmd->add_option("--ff", options->solver.backend, "Form-factor back end: aa-hemicube, hemicube, analytic")
      ->capture_default_str();
  cmd->add_option("--resolution", options->solver.resolution, "Hemicube pixels along the full top face [2, 8192]")
      ->transform(whole_number_in(2, 8192))
      ->capture_default_str();
  cmd->add_option("--converge", options->solver.converge, "Stop when unshot flux < this x emitted flux")
      ->check(number_in(0.0, End::kClosed, 1.0, End::kClosed))
      ->capture_default_str();
  cmd->add_option("--max-shots", options->solver.max_shots, "Stop after this many shots")
      ->transform(whole_number_in(0))
      ->capture_default_str();
  cmd->add_flag("--adaptive,!--no-adaptive", options->solver.adaptive,
                "Adaptive substructuring on radiosity gradients: on by default (--adaptive), off with --no-adaptive");
  cmd->add_option("--gradient", options->solver.gradient,
                  "Split when neighbours' luminance differs by more than this x the largest reflected radiosity")
      ->check(number_in(0.0, End::kOpen, kInfinity, End::kOpen))
      ->capture_default_str();
  cmd->add_option("--relaxation", options->solver.relaxation,
                  "Overrelaxation of the shooting step in [1, 2): shoot W x unshot (1: plain progressive refinement)")
      ->check(number_in(1.0, End::kClosed, 2.0, End::kOpen))
      ->capture_default_str();
  cmd->add_flag("--overshoot", options->solver.overshoot,
                "Ambient overshooting: also shoot rho x the ambient unshot radiosity (fewer shots; default off)");
  cmd->add_option("--max-level", options->max_level, "Deepest element level (patches are level 0; default 8)")
      ->transform(whole_number_in(1, 60));
  cmd->add_option("--min-area", options->min_area,
                  "Smallest element a split may create, scene units^2 (0: 1e-7 x the squared scene diagonal)")
      ->check(size);
  cmd->add_option("--patch-size", options->patch_size, "Longest patch edge, scene units (0: the scene diagonal / 8)")
      ->check(size);
  cmd->add_option("--element-size", options->element_size,
                  "Longest initial element edge, scene units (0: half the patch size)")
      ->check(size);
  cmd->add_flag("--balance", options->balance, "Keep edge-neighbours within one level of each other");
  cmd->add_option("--shooter-samples", options->solver.shooter_samples,
                  "Gauss points per direction on the shooting patch (1: its centroid, as the paper); a patch whose "
                  "point cannot stand for it shoots from 3 or 5 per direction")
      ->transform(whole_number_in(1, 64))
      ->capture_default_str();
  cmd->add_option("--near-field", options->solver.near_field,
                  "Receivers within this many patch radii of the shooting patch get the shape of their share "
                  "from the patch's exact factor: seen from them when smaller than it (3/4 of its radius and of its "
                  "width), else from points over it (0: off, the paper's method)")
      ->check(number_in(0.0, End::kClosed, kInfinity, End::kOpen))
      ->capture_default_str();
  cmd->add_option("--factor-cache", options->solver.factor_cache_mib,
                  "MiB for each patch's last form factors, reused when it shoots again, shooting only into the "
                  "elements split since (0: every shot computed afresh)")
      ->transform(whole_number_in(0, std::int64_t{1} << 30))
      ->capture_default_str();
  cmd->add_option("--max-elements", options->solver.max_elements,
                  "Most leaf elements substructuring may make; beyond it, it splits no further and says so")
      ->transform(whole_number_in(1))
      ->capture_default_str();
  cmd->add_option("--threads", options->threads, "Worker threads (0: all cores) [0, 1024]")
      ->transform(whole_number_in(0, 1024))
      ->capture_default_str();
  cmd->add_option("--out", options->out, "Output directory (default out/<scene name>)")
      ->check(CLI::Validator(
          [](const std::string& value) {
            return value.empty() ? std::string("the directory name is empty; name one, or drop --out for out/<scene>")
                                 : std::string();
          },
          "DIR", "a directory name"));
  cmd->add_option("--width", options->width, "Image width in pixels")
      ->transform(whole_number_in(1, 16384))
      ->capture_default_str();
  cmd->add_option("--height", options->height, "Image height in pixels")
      ->transform(whole_number_in(1, 16384))
      ->capture_default_str();
  cmd->add_flag("--json", options->json, "Print the report as one JSON object on stdout, nothing else there");
  cmd->add_flag("--quiet", options->quiet, "No progress or summary (warnings and errors still go to stderr)");
  cmd->callback([options] { run_solve(*options); });
}

}  // namespace aarad::app
