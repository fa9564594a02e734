// Ctrl-C: the real `aarad solve` run as a child process, sent SIGINT after its first progress line, stops after
// the current shot, writes whole files and an honest report ("interrupted": true, "converged": false), and exits
// with 130 (docs/solver.md).
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

TEST(SolverInterrupt, SigintWritesWholeFilesAndAnHonestReport) {
  const std::string binary = AARAD_BINARY_DIR "/apps/aarad/aarad";
  ASSERT_TRUE(fs::exists(binary)) << binary;
  const fs::path out = fs::path(AARAD_BINARY_DIR) / "test-interrupt" / "cornell";
  fs::remove_all(out);

  int stderr_pipe[2];
  ASSERT_EQ(pipe(stderr_pipe), 0);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    dup2(stderr_pipe[1], STDERR_FILENO);
    close(stderr_pipe[0]);
    close(stderr_pipe[1]);
    // stderr is a pipe, not a terminal: progress comes as lines, the first one after the first shot.
    execl(binary.c_str(), binary.c_str(), "solve", "cornell", "--converge", "1e-9", "--max-shots", "1000000",
          "--width", "96", "--height", "96", "--out", out.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  close(stderr_pipe[1]);
  FILE* child_stderr = fdopen(stderr_pipe[0], "r");
  ASSERT_NE(child_stderr, nullptr);
  std::string everything;
  char line[4096];
  bool signalled = false;
  while (std::fgets(line, sizeof line, child_stderr) != nullptr) {
    everything += line;
    if (!signalled && std::string(line).rfind("aarad: shot ", 0) == 0) {
      ASSERT_EQ(kill(child, SIGINT), 0);
      signalled = true;
    }
  }
  std::fclose(child_stderr);
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(signalled) << "no progress line seen; stderr:\n" << everything;
  ASSERT_TRUE(WIFEXITED(status)) << everything;
  EXPECT_EQ(WEXITSTATUS(status), 130) << everything;
  EXPECT_NE(everything.find("interrupted"), std::string::npos) << everything;

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

}  // namespace
