// Ctrl-C: the real `aarad solve` run as a child process, sent SIGINT after its first progress line, stops after
// the current shot, writes whole files and an honest report ("interrupted": true, "converged": false), and exits
// with 130 (docs/solver.md). SIGTERM and SIGHUP do the same, with 143 and 129.
// OpenMesh's PropertyT<VectorT<unsigned char, 3>>::push_back trips GCC 12's -Wmaybe-uninitialized when
// instantiated here (a false positive in a system header; see test_outputs.cpp).
#if defined(__GNUC__) && !defined(__clang__)  // a GCC warning; Clang has no such group
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

#include <OpenImageIO/imageio.h>
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/PolyMesh_ArrayKernelT.hh>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>
#include <sys/wait.h>
#include <unistd.h>

namespace {

namespace fs = std::filesystem;

// `aarad solve ARGS` started as a child process whose stderr the test reads through a pipe (a pipe, not a terminal:
// progress comes as lines, the first one after the first shot). With `ignored` the child starts with that signal
// ignored, as a shell starts a background job (SIGINT) or `nohup` a command (SIGHUP).
struct SolveChild {
  pid_t pid = -1;
  FILE* err = nullptr;
};
SolveChild start_solve(std::vector<std::string> args, int ignored = 0) {
  const std::string binary = AARAD_BINARY_DIR "/apps/aarad/aarad";
  EXPECT_TRUE(fs::exists(binary)) << binary;
  args.insert(args.begin(), {binary, "solve"});
  std::vector<char*> argv;
  for (std::string& arg : args) argv.push_back(arg.data());
  argv.push_back(nullptr);
  int stderr_pipe[2];
  if (pipe(stderr_pipe) != 0) return {};
  const pid_t child = fork();
  if (child == 0) {
    dup2(stderr_pipe[1], STDERR_FILENO);
    close(stderr_pipe[0]);
    close(stderr_pipe[1]);
    if (ignored != 0) std::signal(ignored, SIG_IGN);  // kept across exec
    execv(binary.c_str(), argv.data());
    _exit(127);
  }
  close(stderr_pipe[1]);
  return {child, child > 0 ? fdopen(stderr_pipe[0], "r") : nullptr};
}

// A solve sent `signal` after its first progress line: whole files, an honest report, exit 128 + the signal.
void expect_interrupted_by(int signal, const std::string& label) {
  const fs::path out = fs::path(AARAD_BINARY_DIR) / "test-interrupt" / ("cornell-" + std::to_string(signal));
  fs::remove_all(out);
  const auto [child, child_stderr] = start_solve({"cornell", "--converge", "1e-9", "--max-shots", "1000000", "--width",
                                                  "96", "--height", "96", "--out", out.string()});
  ASSERT_GT(child, 0);
  ASSERT_NE(child_stderr, nullptr);
  std::string everything;
  char line[4096];
  bool signalled = false;
  while (std::fgets(line, sizeof line, child_stderr) != nullptr) {
    everything += line;
    if (!signalled && std::string(line).rfind("aarad: shot ", 0) == 0) {
      ASSERT_EQ(kill(child, signal), 0);
      signalled = true;
    }
  }
  std::fclose(child_stderr);
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(signalled) << "no progress line seen; stderr:\n" << everything;
  ASSERT_TRUE(WIFEXITED(status)) << everything;
  EXPECT_EQ(WEXITSTATUS(status), 128 + signal) << everything;
  EXPECT_NE(everything.find("aarad: interrupted by " + label + " after "), std::string::npos) << everything;

  // Whole files, nothing half-written or temporary.
  std::set<std::string> names;
  for (const auto& entry : fs::directory_iterator(out)) names.insert(entry.path().filename().string());
  EXPECT_EQ(names, (std::set<std::string>{"mesh.ply", "flat.png", "smooth.png", "mesh.png", "radiosity.exr",
                                          "report.json"}));
  // Every image reads back whole at the size asked for (--width 96 --height 96), as its header says.
  for (const char* image : {"flat.png", "smooth.png", "mesh.png", "radiosity.exr"}) {
    auto input = OIIO::ImageInput::open((out / image).string());
    ASSERT_TRUE(input) << image << ": " << OIIO::geterror();
    const OIIO::ImageSpec& spec = input->spec();
    EXPECT_EQ(spec.width, 96) << image;
    EXPECT_EQ(spec.height, 96) << image;
    ASSERT_GE(spec.nchannels, 3) << image;
    std::vector<float> pixels(static_cast<std::size_t>(spec.width) * spec.height * spec.nchannels);
    EXPECT_TRUE(input->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, pixels.data()))
        << image << ": " << input->geterror();
    input->close();
  }

  // An honest report: interrupted, not converged, with the unshot flux it stopped at.
  std::ifstream in(out / "report.json");
  const nlohmann::json report = nlohmann::json::parse(in);

  // The PLY reads back through OpenMesh with its vertex colours and one face per element of the report.
  OpenMesh::PolyMesh_ArrayKernelT<> mesh;
  mesh.request_vertex_colors();
  OpenMesh::IO::Options options = OpenMesh::IO::Options::VertexColor;
  ASSERT_TRUE(OpenMesh::IO::read_mesh(mesh, (out / "mesh.ply").string(), options));
  EXPECT_TRUE(options.check(OpenMesh::IO::Options::VertexColor));
  EXPECT_EQ(mesh.n_faces(), report["elements"].get<std::size_t>());
  EXPECT_GT(mesh.n_vertices(), 0u);
  EXPECT_EQ(report["interrupted"], true);
  EXPECT_EQ(report["converged"], false);
  EXPECT_GE(report["shots"].get<long long>(), 1);
  EXPECT_LT(report["shots"].get<long long>(), 1000000);
  EXPECT_GT(report["unshot_fraction"].get<double>(), 1e-9);
  EXPECT_LE(report["unshot_fraction"].get<double>(), 1.0);
  EXPECT_GT(report["elements"].get<long long>(), 0);
}

TEST(SolverInterrupt, SigintWritesWholeFilesAndAnHonestReport) { expect_interrupted_by(SIGINT, "Ctrl-C"); }

// A batch system stops a job with SIGTERM, a closed terminal with SIGHUP: before, either ended the program at once,
// with nothing written (and a temporary file left when it came while a file was written).
TEST(SolverInterrupt, SigtermAndSighupStopTheSolveAsCtrlCDoes) {
  expect_interrupted_by(SIGTERM, "SIGTERM");
  expect_interrupted_by(SIGHUP, "SIGHUP");
}

// A solve started with `signal` ignored, and sent it three times: it runs its 300 shots and exits 0.
void expect_ignored(int signal) {
  const fs::path out = fs::path(AARAD_BINARY_DIR) / "test-interrupt" / ("ignored-" + std::to_string(signal));
  fs::remove_all(out);
  const auto [child, child_stderr] =
      start_solve({"cornell", "--max-shots", "300", "--width", "16", "--height", "16", "--out", out.string()}, signal);
  ASSERT_GT(child, 0);
  ASSERT_NE(child_stderr, nullptr);
  std::string everything;
  char line[4096];
  int signals = 0;
  while (std::fgets(line, sizeof line, child_stderr) != nullptr) {
    everything += line;
    if (std::string(line).rfind("aarad: shot ", 0) == 0 && signals < 3) {
      ASSERT_EQ(kill(child, signal), 0);
      ++signals;
    }
  }
  std::fclose(child_stderr);
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_GT(signals, 0) << "no progress line seen; stderr:\n" << everything;
  ASSERT_TRUE(WIFEXITED(status)) << everything;
  EXPECT_EQ(WEXITSTATUS(status), 0) << everything;
  std::ifstream in(out / "report.json");
  const nlohmann::json report = nlohmann::json::parse(in);
  EXPECT_EQ(report["interrupted"], false);
  EXPECT_EQ(report["shots"].get<long long>(), 300);
}

// A SIGINT the parent set to be ignored stays ignored: a shell starts a background job (`aarad solve ... &`) so, and
// a Ctrl-C meant for the script that started it stopped the solve (exit 130, "interrupted": true).
TEST(SolverInterrupt, AnIgnoredSigintStaysIgnored) { expect_ignored(SIGINT); }

// Under `nohup` (SIGHUP ignored), a SIGHUP changes nothing.
TEST(SolverInterrupt, AnIgnoredSighupStaysIgnored) { expect_ignored(SIGHUP); }

// `aarad solve cornell` writing 2048 x 2048 images (about 1.2 s of writing, so that a Ctrl-C sent when mesh.ply
// appears arrives while the images are written, even on a busy machine) into `out`, as a child process
// whose stderr the test reads through a pipe (stdout goes to /dev/null).
struct WritingChild {
  pid_t pid = -1;
  FILE* err = nullptr;
  std::string everything;  // stderr as read so far

  explicit WritingChild(const fs::path& out) {
    const std::string binary = AARAD_BINARY_DIR "/apps/aarad/aarad";
    fs::remove_all(out);
    int stderr_pipe[2];
    if (pipe(stderr_pipe) != 0) return;
    pid = fork();
    if (pid == 0) {
      dup2(stderr_pipe[1], STDERR_FILENO);
      close(stderr_pipe[0]);
      close(stderr_pipe[1]);
      if (std::freopen("/dev/null", "w", stdout) == nullptr) _exit(126);
      execl(binary.c_str(), binary.c_str(), "solve", "cornell", "--max-shots", "3", "--width", "2048", "--height",
            "2048", "--out", out.c_str(), static_cast<char*>(nullptr));
      _exit(127);
    }
    close(stderr_pipe[1]);
    err = fdopen(stderr_pipe[0], "r");
  }

  // Waits until `file` exists (true), or the child has ended or a minute has passed (false).
  bool wait_for(const fs::path& file) const {
    for (int ms = 0; ms < 60000; ++ms) {
      if (fs::exists(file)) return true;
      siginfo_t info{};
      // Ended (left to be waited for by finish()), or an error.
      if (waitid(P_PID, static_cast<id_t>(pid), &info, WEXITED | WNOHANG | WNOWAIT) != 0 || info.si_pid != 0) {
        return false;
      }
      usleep(1000);
    }
    return false;
  }

  // Reads stderr until a line starts with `prefix` (true) or it ends (false).
  bool read_until(const std::string& prefix) {
    char line[4096];
    while (std::fgets(line, sizeof line, err) != nullptr) {
      everything += line;
      if (std::string(line).rfind(prefix, 0) == 0) return true;
    }
    return false;
  }

  // Reads stderr to its end and returns the child's status.
  int finish() {
    read_until("\n");  // no line starts with a newline: to the end
    std::fclose(err);
    int status = 0;
    waitpid(pid, &status, 0);
    return status;
  }
};

std::set<std::string> names_in(const fs::path& directory) {
  std::set<std::string> names;
  for (const auto& entry : fs::directory_iterator(directory)) names.insert(entry.path().filename().string());
  return names;
}

void expect_whole_image(const fs::path& path, int size) {
  auto input = OIIO::ImageInput::open(path.string());
  ASSERT_TRUE(input) << path << ": " << OIIO::geterror();
  const OIIO::ImageSpec& spec = input->spec();
  EXPECT_EQ(spec.width, size) << path;
  EXPECT_EQ(spec.height, size) << path;
  std::vector<float> pixels(static_cast<std::size_t>(spec.width) * spec.height * spec.nchannels);
  EXPECT_TRUE(input->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, pixels.data()))
      << path << ": " << input->geterror();
  input->close();
}

// A Ctrl-C once the solve is over (the solve stopped at --max-shots, mesh.ply is written, the images are being
// rendered and written): every file is written whole, the report describes the solve, and the exit code is 130.
// Before, the Ctrl-C was ignored: exit 0.
TEST(SolverInterrupt, SigintWhileWritingLetsEveryFileBeWrittenAndExits130) {
  const fs::path out = fs::path(AARAD_BINARY_DIR) / "test-interrupt" / ("writing-" + std::to_string(getpid()));
  WritingChild child(out);
  ASSERT_GT(child.pid, 0);
  ASSERT_NE(child.err, nullptr);
  ASSERT_TRUE(child.wait_for(out / "mesh.ply")) << "mesh.ply never appeared";
  ASSERT_EQ(kill(child.pid, SIGINT), 0);
  const int status = child.finish();
  ASSERT_TRUE(WIFEXITED(status)) << child.everything;
  EXPECT_EQ(WEXITSTATUS(status), 130) << child.everything;
  EXPECT_NE(child.everything.find("aarad: Ctrl-C: writing the files to the end"), std::string::npos)
      << child.everything;
  EXPECT_EQ(names_in(out), (std::set<std::string>{"mesh.ply", "flat.png", "smooth.png", "mesh.png", "radiosity.exr",
                                                  "report.json"}));
  for (const char* image : {"flat.png", "smooth.png", "mesh.png", "radiosity.exr"}) {
    expect_whole_image(out / image, 2048);
  }
  std::ifstream in(out / "report.json");
  const nlohmann::json report = nlohmann::json::parse(in);
  EXPECT_EQ(report["interrupted"], false);  // the solve ran its 3 shots
  EXPECT_EQ(report["shots"], 3);
  fs::remove_all(out);
}

// `first` while the files are written, then `second` once the first was handled (two pending signals of one kind
// would be one): the writing stops after the file being written, no temporary file stays behind, what was written
// is whole, report.json (written last) is not, and the exit code is 128 + the first signal's number. The messages
// name the signals (`first_label`, `second_label`).
void expect_stopped_while_writing(int first, const std::string& first_label, int second,
                                  const std::string& second_label) {
  const std::string folder = "stopped-" + std::to_string(first) + "-" + std::to_string(getpid());
  const fs::path out = fs::path(AARAD_BINARY_DIR) / "test-interrupt" / folder;
  WritingChild child(out);
  ASSERT_GT(child.pid, 0);
  ASSERT_NE(child.err, nullptr);
  ASSERT_TRUE(child.wait_for(out / "mesh.ply")) << "mesh.ply never appeared";
  ASSERT_EQ(kill(child.pid, first), 0);
  if (child.read_until("aarad: " + first_label + ":")) {
    ASSERT_EQ(kill(child.pid, second), 0);
  }
  const int status = child.finish();
  ASSERT_TRUE(WIFEXITED(status)) << child.everything;
  EXPECT_EQ(WEXITSTATUS(status), 128 + first) << child.everything;
  EXPECT_NE(child.everything.find("aarad: " + first_label + ": writing the files to the end; " + first_label +
                                  " again to stop after the file being written"),
            std::string::npos)
      << child.everything;
  EXPECT_NE(child.everything.find("aarad: " + second_label + ": stopping after the file being written"),
            std::string::npos)
      << child.everything;
  EXPECT_NE(child.everything.find("aarad: stopped by " + second_label + "; wrote mesh.ply"), std::string::npos)
      << child.everything;
  const std::set<std::string> names = names_in(out);
  for (const std::string& name : names) EXPECT_NE(name[0], '.') << "a temporary file: " << name;
  EXPECT_EQ(names.count("report.json"), 0u);
  EXPECT_EQ(names.count("mesh.ply"), 1u);
  for (const char* image : {"flat.png", "smooth.png", "mesh.png", "radiosity.exr"}) {
    if (names.count(image) != 0) expect_whole_image(out / image, 2048);
  }
  fs::remove_all(out);
}

// A second Ctrl-C while the files are written stops after the file being written (before, it killed the program in
// the middle of a file and left `.flat.tmpPID-K.png`); the exit code is 130.
TEST(SolverInterrupt, ASecondSigintWhileWritingStopsAfterTheFileBeingWrittenAndLeavesNoTemporary) {
  expect_stopped_while_writing(SIGINT, "Ctrl-C", SIGINT, "Ctrl-C");
}

// SIGTERM while the files are written, then Ctrl-C: the first lets the writing go on, the second stops it; the exit
// code is the first signal's, 143.
TEST(SolverInterrupt, SigtermWhileWritingThenCtrlCStopsAfterTheFileBeingWritten) {
  expect_stopped_while_writing(SIGTERM, "SIGTERM", SIGINT, "Ctrl-C");
}

}  // namespace
