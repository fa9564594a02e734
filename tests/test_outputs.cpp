// The output files of a solve (design.md): every file exists and reads back (PNG and EXR through OpenImageIO,
// the PLY through OpenMesh), no temporary file is left, and the report has every field of the contract.
// OpenMesh's PropertyT<VectorT<unsigned char, 3>>::push_back trips GCC 12's -Wmaybe-uninitialized when
// instantiated here (a false positive in a system header, reported at the end of the file).
#if defined(__GNUC__) && !defined(__clang__)  // a GCC warning; Clang has no such group
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

#include "aarad/core/builtin_scenes.h"
#include "aarad/core/atomic_file.h"
#include "aarad/core/error.h"
#include "aarad/core/image.h"
#include "aarad/mesh/invariants.h"
#include "aarad/refine/output.h"
#include "aarad/refine/render.h"
#include "aarad/refine/report.h"
#include "aarad/refine/solver.h"
#include "tests/solver_test_scenes.h"

#include <OpenImageIO/imageio.h>
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/PolyMesh_ArrayKernelT.hh>
#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <functional>
#include <map>
#include <fstream>
#include <iterator>
#include <set>
#include <string>
#include <thread>
#include <grp.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

namespace aarad::refine {
namespace {

namespace fs = std::filesystem;

struct ReadImage {
  int width = 0, height = 0, channels = 0;
  std::vector<float> pixels;
};

ReadImage read_image(const fs::path& path) {
  ReadImage image;
  auto input = OIIO::ImageInput::open(path.string());
  if (!input) {
    ADD_FAILURE() << "cannot open " << path << ": " << OIIO::geterror();
    return image;
  }
  const OIIO::ImageSpec& spec = input->spec();
  image.width = spec.width;
  image.height = spec.height;
  image.channels = spec.nchannels;
  image.pixels.resize(static_cast<std::size_t>(spec.width) * spec.height * spec.nchannels);
  EXPECT_TRUE(input->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, image.pixels.data()))
      << input->geterror();
  input->close();
  return image;
}

// Fraction of pixels that are not black.
double lit_fraction(const ReadImage& image) {
  std::size_t lit = 0;
  for (std::size_t i = 0; i + 2 < image.pixels.size(); i += static_cast<std::size_t>(image.channels)) {
    if (image.pixels[i] + image.pixels[i + 1] + image.pixels[i + 2] > 0.0f) ++lit;
  }
  return static_cast<double>(lit) / (static_cast<double>(image.width) * image.height);
}

class OutputsTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    scene_ = std::make_unique<Scene>(make_cornell_box());
    SolverOptions options;
    options.meshing = default_meshing(*scene_);
    options.converge = 0.05;  // a short solve: the files are the subject here
    solver_ = std::make_unique<Solver>(*scene_, options);
    solver_->run();
    // ctest runs every case of this suite as its own process, two at a time: one folder per process.
    directory_ = fs::path(AARAD_BINARY_DIR) / "test-outputs" / ("cornell-" + std::to_string(getpid()));
    fs::remove_all(directory_);
    const OutputResult result = write_solution_files(*solver_, directory_, {.width = 160, .height = 120});
    report_ = make_report(*solver_, mesh::check_invariants(solver_->hierarchy()), {.output = result.seconds});
    write_report(report_, directory_ / "report.json");
  }
  static void TearDownTestSuite() {
    fs::remove_all(directory_);
    solver_.reset();
    scene_.reset();
  }

  static inline std::unique_ptr<Scene> scene_;
  static inline std::unique_ptr<Solver> solver_;
  static inline fs::path directory_;
  static inline nlohmann::json report_;
};

TEST_F(OutputsTest, EveryFileAndNoTemporaryFile) {
  std::set<std::string> names;
  for (const auto& entry : fs::directory_iterator(directory_)) names.insert(entry.path().filename().string());
  EXPECT_EQ(names, (std::set<std::string>{"mesh.ply", "flat.png", "smooth.png", "mesh.png", "radiosity.exr",
                                          "report.json"}));
}

// The same solution gives the same files, byte for byte, whenever they are written: a researcher can diff two
// output folders. OpenImageIO stamps an EXR with the time of writing (the `capDate` header attribute, from the
// spec's DateTime) unless the spec gives one; write_exr gives an empty one. Written a second later, the EXR
// differed in its header.
TEST_F(OutputsTest, FilesWrittenAgainLaterAreTheSameBytes) {
  const fs::path directory = directory_.parent_path() / (directory_.filename().string() + "-again");
  fs::remove_all(directory);
  std::this_thread::sleep_for(std::chrono::milliseconds(1100));  // capDate counts whole seconds
  ASSERT_TRUE(write_solution_files(*solver_, directory, {.width = 160, .height = 120}).complete);
  const auto bytes = [](const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  };
  for (const char* name : {"mesh.ply", "flat.png", "smooth.png", "mesh.png", "radiosity.exr"})
    EXPECT_TRUE(bytes(directory_ / name) == bytes(directory / name)) << name;
  auto input = OIIO::ImageInput::open((directory / "radiosity.exr").string());
  ASSERT_TRUE(input);
  EXPECT_EQ(input->spec().get_string_attribute("DateTime"), "");
  input->close();
  fs::remove_all(directory);
}

// keep_writing is asked before each file: `aarad solve` stops there after a second Ctrl-C. Answering no before the
// third file leaves the first two, whole, and no temporary file.
TEST_F(OutputsTest, KeepWritingStopsBetweenFiles) {
  const fs::path directory = directory_.parent_path() / (directory_.filename().string() + "-stopped");
  fs::remove_all(directory);
  int asked = 0;
  const OutputResult result = write_solution_files(
      *solver_, directory, {.width = 16, .height = 12, .keep_writing = [&] { return ++asked <= 2; }});
  EXPECT_FALSE(result.complete);
  EXPECT_EQ(asked, 3);
  EXPECT_EQ(result.files, (std::vector<fs::path>{directory / "mesh.ply", directory / "flat.png"}));
  std::set<std::string> names;
  for (const auto& entry : fs::directory_iterator(directory)) names.insert(entry.path().filename().string());
  EXPECT_EQ(names, (std::set<std::string>{"mesh.ply", "flat.png"}));
  EXPECT_EQ(read_image(directory / "flat.png").width, 16);
  // Without an answer, every file.
  EXPECT_TRUE(write_solution_files(*solver_, directory, {.width = 16, .height = 12}).complete);
  fs::remove_all(directory);
}

// Files of an earlier solve in the folder: report.json goes before the first new file is written, and when the
// writing stops early, stopped or failing, the earlier files not written again go too. Before, the folder kept the
// earlier report.json and images next to the new mesh.ply: a set that described two solves.
TEST_F(OutputsTest, WritingThatStopsEarlyLeavesNoFileOfAnEarlierSolve) {
  const fs::path directory = directory_.parent_path() / (directory_.filename().string() + "-earlier");
  const auto names = [&] {
    std::set<std::string> found;
    for (const auto& entry : fs::directory_iterator(directory)) found.insert(entry.path().filename().string());
    return found;
  };
  const auto write_earlier_solve = [&] {
    fs::remove_all(directory);
    fs::create_directories(directory);
    for (const std::string_view name : kSolutionFileNames) std::ofstream(directory / name) << "earlier solve";
  };

  write_earlier_solve();
  int asked = 0;
  EXPECT_FALSE(write_solution_files(*solver_, directory, {.width = 16, .height = 12,
                                                          .keep_writing = [&] { return ++asked <= 2; }})
                   .complete);
  EXPECT_EQ(names(), (std::set<std::string>{"mesh.ply", "flat.png"}));
  EXPECT_EQ(read_image(directory / "flat.png").width, 16);

  // smooth.png cannot be renamed over a directory: the write fails there. The directory stays.
  write_earlier_solve();
  fs::remove(directory / "smooth.png");
  fs::create_directory(directory / "smooth.png");
  EXPECT_THROW(write_solution_files(*solver_, directory, {.width = 16, .height = 12}), Error);
  EXPECT_EQ(names(), (std::set<std::string>{"mesh.ply", "flat.png", "smooth.png"}));
  EXPECT_TRUE(fs::is_directory(directory / "smooth.png"));
  EXPECT_EQ(read_image(directory / "flat.png").width, 16);

  // A whole set replaces the earlier one; only write_report brings report.json back.
  write_earlier_solve();
  EXPECT_TRUE(write_solution_files(*solver_, directory, {.width = 16, .height = 12}).complete);
  EXPECT_EQ(names(), (std::set<std::string>{"mesh.ply", "flat.png", "smooth.png", "mesh.png", "radiosity.exr"}));
  fs::remove_all(directory);
}

TEST_F(OutputsTest, PngsReadBackWithTheRequestedSize) {
  for (const char* name : {"flat.png", "smooth.png", "mesh.png"}) {
    const ReadImage image = read_image(directory_ / name);
    EXPECT_EQ(image.width, 160) << name;
    EXPECT_EQ(image.height, 120) << name;
    EXPECT_EQ(image.channels, 3) << name;
    // The official camera sees the box's inside filling most of the frame.
    EXPECT_GT(lit_fraction(image), 0.5) << name;
  }
}

TEST_F(OutputsTest, ExrHoldsLinearRadiosity) {
  const ReadImage image = read_image(directory_ / "radiosity.exr");
  ASSERT_EQ(image.width, 160);
  ASSERT_EQ(image.height, 120);
  ASSERT_EQ(image.channels, 3);
  // Every pixel is a displayed element radiosity: the brightest is the light (17, 12, 4) plus its reflection.
  float brightest = 0.0f;
  for (std::size_t i = 0; i < image.pixels.size(); i += 3) brightest = std::max(brightest, image.pixels[i]);
  EXPECT_GE(brightest, 17.0f);
  EXPECT_LT(brightest, 17.0f + 1.0f);
  EXPECT_GT(lit_fraction(image), 0.5);
}

TEST_F(OutputsTest, PlyReadsBackWithOneFacePerLeafAndTheContractProperties) {
  OpenMesh::PolyMesh_ArrayKernelT<> mesh;
  mesh.request_vertex_colors();
  OpenMesh::IO::Options options = OpenMesh::IO::Options::VertexColor;
  ASSERT_TRUE(OpenMesh::IO::read_mesh(mesh, (directory_ / "mesh.ply").string(), options));
  EXPECT_EQ(mesh.n_faces(), solver_->hierarchy().leaf_count());
  EXPECT_TRUE(options.check(OpenMesh::IO::Options::VertexColor));
  // The header names the per-face properties of the contract, binary.
  std::ifstream in(directory_ / "mesh.ply", std::ios::binary);
  std::string header, line;
  while (std::getline(in, line) && line != "end_header") header += line + "\n";
  EXPECT_NE(header.find("format binary"), std::string::npos) << header;
  for (const char* property : {"radiosity_r", "radiosity_g", "radiosity_b", "level", "patch"}) {
    EXPECT_NE(header.find(property), std::string::npos) << property << " missing from\n" << header;
  }
}

// The PLY's faces carry the solution B; its vertex colours are what smooth.png shows: the displayed values (with
// the display-only ambient term, which this short solve makes large) interpolated at the vertices, through the
// images' tone map. They were B's, under the displayed values' exposure, and agreed with neither.
TEST_F(OutputsTest, PlyVertexColoursAreTheDisplayedValuesThroughTheToneMap) {
  const std::vector<Rgb> displayed = solver_->displayed_radiosity();
  const ToneMap map = solution_tone_map(*solver_, displayed);
  const mesh::DisplayMesh display = mesh::build_display_mesh(solver_->hierarchy(), displayed);
  ASSERT_GT(solver_->ambient().max_component() * map.exposure, 0.01);  // a difference the colours show
  // The vertex records as written, in the hierarchy's vertex order, which the display mesh's begins with: three
  // floats and three bytes each (OpenMesh's reader leaves out vertices no face uses).
  std::ifstream in(directory_ / "mesh.ply", std::ios::binary);
  std::string line;
  std::size_t count = 0;
  while (std::getline(in, line) && line != "end_header") {
    if (line.starts_with("element vertex ")) count = std::stoul(line.substr(15));
    ASSERT_FALSE(line.starts_with("property double")) << "the Cornell box's points are floats";
  }
  ASSERT_GT(count, 0u);
  ASSERT_LE(count, display.vertex_values.size());
  std::size_t differing = 0;
  for (std::size_t v = 0; v < count; ++v) {
    in.ignore(3 * sizeof(float));
    std::array<unsigned char, 3> colour{};
    in.read(reinterpret_cast<char*>(colour.data()), 3);
    const auto expected = map(display.vertex_values[v]);
    for (int c = 0; c < 3; ++c) differing += colour[c] != expected[static_cast<std::size_t>(c)];
  }
  ASSERT_TRUE(in.good());
  EXPECT_EQ(differing, 0u);
}

TEST_F(OutputsTest, ReportHasEveryFieldOfTheContract) {
  std::ifstream in(directory_ / "report.json");
  const nlohmann::json report = nlohmann::json::parse(in);
  EXPECT_EQ(report, report_);
  for (const char* field : {"scene", "method", "resolution", "converged", "interrupted", "shots", "unshot_fraction",
                            "emitted_flux", "absorbed_flux", "patches", "elements", "max_level", "seconds",
                            "invariants", "groups"}) {
    EXPECT_TRUE(report.contains(field)) << field;
  }
  EXPECT_EQ(report["scene"], "cornell");
  EXPECT_EQ(report["method"], "aa-hemicube");
  EXPECT_EQ(report["resolution"], 100);
  EXPECT_EQ(report["converged"], true);
  EXPECT_EQ(report["interrupted"], false);
  EXPECT_EQ(report["shots"], solver_->shots());
  EXPECT_LT(report["unshot_fraction"].get<double>(), 0.05);
  EXPECT_EQ(report["elements"], solver_->hierarchy().leaf_count());
  EXPECT_EQ(report["patches"], solver_->hierarchy().patches().size());
  for (const char* seconds : {"total", "form_factors", "subdivision", "output"}) {
    EXPECT_TRUE(report["seconds"][seconds].is_number()) << seconds;
  }
  EXPECT_TRUE(report["invariants"]["violations"].is_array());
  EXPECT_TRUE(report["invariants"]["violations"].empty());
  for (const char* flux : {"emitted_flux", "absorbed_flux"}) {
    ASSERT_TRUE(report[flux].is_array() && report[flux].size() == 3) << flux;
  }
  // Emitted flux: the light's 130 x 105 mm^2 times (17, 12, 4).
  EXPECT_NEAR(report["emitted_flux"][0].get<double>(), 17.0 * 130.0 * 105.0, 1e-6 * 17.0 * 130.0 * 105.0);
  ASSERT_EQ(report["groups"].size(), scene_->groups.size());
  std::size_t elements = 0;
  for (const auto& group : report["groups"]) {
    for (const char* field : {"name", "area", "elements", "mean_radiosity"}) {
      EXPECT_TRUE(group.contains(field)) << field;
    }
    EXPECT_EQ(group["mean_radiosity"].size(), 3u);
    elements += group["elements"].get<std::size_t>();
  }
  EXPECT_EQ(elements, solver_->hierarchy().leaf_count());
}

// Files larger than the process may write (RLIMIT_FSIZE, as on a full disk: the write fails part way) are not
// left behind, whole or empty: each writer throws an error naming the file, and the directory stays empty.
// OpenImageIO's PNG writer did not report the failed write and left an empty flat.png.
TEST(OutputsFiles, AWriteThatFailsPartWayLeavesNoFileAndSaysSo) {
  const fs::path directory =
      fs::path(AARAD_BINARY_DIR) / "test-outputs" / ("failed-write-" + std::to_string(getpid()));
  fs::remove_all(directory);
  fs::create_directories(directory);
  // Noise, so that the PNG and the EXR cannot compress below the limit.
  Image image(128, 128);
  std::uint32_t state = 12345;
  for (float& v : image.pixels) v = static_cast<float>((state = state * 1664525u + 1013904223u) >> 8) / 16777216.0f;
  const ToneMap map;
  const Image8 image8 = tone_map(image, map);
  const std::string text(100000, 'x');

  struct rlimit previous {};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &previous), 0);
  struct rlimit small = previous;
  small.rlim_cur = 4096;
  const auto ignore = std::signal(SIGXFSZ, SIG_IGN);  // a write beyond the limit fails (EFBIG) instead
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &small), 0);
  const auto message = [](const std::function<void()>& write) -> std::string {
    try {
      write();
    } catch (const Error& e) {
      return e.what();
    }
    return "no error";
  };
  const std::string png = message([&] { write_png(image8, directory / "flat.png"); });
  const std::string exr = message([&] { write_exr(image, directory / "radiosity.exr"); });
  const std::string bytes = message([&] { write_bytes_atomically(directory / "report.json", text); });
  setrlimit(RLIMIT_FSIZE, &previous);
  std::signal(SIGXFSZ, ignore);

  EXPECT_NE(png.find("flat.png"), std::string::npos) << png;
  EXPECT_NE(exr.find("radiosity.exr"), std::string::npos) << exr;
  EXPECT_NE(bytes.find("report.json"), std::string::npos) << bytes;
  EXPECT_TRUE(fs::is_empty(directory)) << fs::directory_iterator(directory)->path();
  fs::remove_all(directory);
}


// In a sticky folder (as /tmp) another user's report.json cannot be replaced: rename(2) gives EPERM. The check before
// a solve refused nothing, and a reviewer's solve ran to the end and failed writing, the new mesh.ply left beside the
// old files. Now check_output_directory names the file. The other user is nobody (65534), in a child process that
// gives up root; the file and the folder are root's, in /tmp, which every user may enter. Where the process may not
// become another user (not root, or root of a user namespace without that capability) the test skips.
TEST(OutputsFiles, AnotherUsersFileInAStickyFolderIsRefusedBeforeTheSolve) {
  if (::geteuid() != 0) GTEST_SKIP() << "needs root, to make a file of another user than the one that runs the check";
  const fs::path folder = fs::path("/tmp") / ("aarad-sticky-" + std::to_string(getpid()));
  fs::remove_all(folder);
  fs::create_directories(folder);
  struct RemoveAtEnd {
    fs::path path;
    ~RemoveAtEnd() {
      std::error_code ignored;
      fs::remove_all(path, ignored);
    }
  } remove_at_end{folder};
  fs::permissions(folder, fs::perms::all | fs::perms::sticky_bit);
  std::ofstream(folder / "report.json") << "{}";
  const fs::path message_file = folder / "message.txt";
  constexpr int kCannotBecomeUser = 2;
  // check_output_directory(folder) as `user`: 0 when it passes, 1 when it throws (its message in message_file).
  const auto check_as = [&](uid_t user) {
    const pid_t child = ::fork();
    if (child == 0) {
      int code = kCannotBecomeUser;
      if (::setgroups(0, nullptr) == 0 && ::setgid(user) == 0 && ::setuid(user) == 0) {
        try {
          check_output_directory(folder);
          code = 0;
        } catch (const Error& e) {
          std::ofstream(message_file) << e.what();
          code = 1;
        }
      }
      std::_Exit(code);
    }
    int status = 0;
    ::waitpid(child, &status, 0);
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  };
  const int as_nobody = check_as(65534);
  if (as_nobody == kCannotBecomeUser) GTEST_SKIP() << "this process may not become uid 65534 (a user namespace?)";
  ASSERT_EQ(as_nobody, 1);
  std::ifstream in(message_file);
  const std::string message((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(message.find("cannot replace " + (folder / "report.json").string() + ": it belongs to another user"),
            std::string::npos)
      << message;
  // Without the sticky bit the folder's write permission is enough to replace it, and the owner may anyway.
  fs::remove(message_file);
  fs::permissions(folder, fs::perms::all);
  EXPECT_EQ(check_as(65534), 0);
  fs::permissions(folder, fs::perms::all | fs::perms::sticky_bit);
  EXPECT_EQ(check_as(0), 0);
}
// A floor one unit below the eye, reaching from behind the camera far ahead, seen level: it fills the lower half of
// the image at any field of view. Clipped at the near plane, its triangle reaches screen coordinates far beyond an
// int when the view is narrow (at half a degree, 3e9 pixels to the side); the pixel range is clamped before it is
// converted (the conversion gave INT_MIN, and the floor was not drawn).
TEST(OutputsRender, FloorFromBehindTheCameraFillsTheLowerHalfAtNarrowViews) {
  mesh::DisplayMesh floor;
  floor.positions = {{-1e6, -1, -10}, {0, -1, 1e6}, {1e6, -1, -10}};  // counter-clockwise seen from above
  floor.vertex_values = {Rgb(1.0), Rgb(1.0), Rgb(1.0)};
  floor.triangles = {{0, 1, 2}};
  floor.triangle_leaf = {0};
  const std::vector<Rgb> node_values{Rgb(1.0)};
  for (const double degrees : {40.0, 5.0, 1.0, 0.5}) {
    Camera camera;
    camera.eye = Vec3(0.0);
    camera.forward = Vec3(0, 0, 1);
    camera.up = Vec3(0, 1, 0);
    camera.vertical_fov = degrees * kPi / 180.0;
    const Rendering r = render(floor, node_values, camera, 64, 64, Shading::kFlat);
    for (int y = 0; y < 64; ++y) {
      std::size_t shown = 0;
      for (int x = 0; x < 64; ++x) shown += r.leaf[static_cast<std::size_t>(y) * 64 + x] != mesh::kNoNode;
      // Rows below the horizon (y down, the horizon between rows 31 and 32) show the floor, rows above do not.
      EXPECT_EQ(shown, y >= 32 ? 64u : 0u) << degrees << " degrees, row " << y;
    }
  }
}

TEST(OutputsToneMap, PercentileExposureAndSrgbEncoding) {
  // 99 % of the area at 0.5, 1 % at 10: the 99th percentile is 0.5, so 0.5 maps to 255.
  const std::vector<Rgb> values{Rgb(0.5), Rgb(10.0)};
  const std::vector<double> areas{99.0, 1.0};
  const ToneMap map = ToneMap::from_percentile(values, areas, 0.99);
  EXPECT_DOUBLE_EQ(map.exposure, 2.0);
  EXPECT_EQ(map(Rgb(0.5))[0], 255);
  EXPECT_EQ(map(Rgb(0.0))[0], 0);
  // sRGB (IEC 61966-2-1): linear 0.18 encodes to 0.4614, 118 of 255 (0.09 x exposure 2).
  EXPECT_EQ(map(Rgb(0.09))[0], 118);
}

// The exposure comes from the surfaces that do not emit: the lamp clips to white instead of darkening what it
// lights. Two unit squares (one emits 1, the other reflects what it gets, about 0.12), one element each.
// mesh.png's lines lie on the scene's pixels only: where an element meets the background, on the element's side,
// whichever side of it the background is (a reviewer found the outline painted grey into the background above and
// left of the scene, and inside it below and right).
TEST(OutputsRender, EdgesBetweenAnElementAndTheBackgroundAreDrawnOnTheElement) {
  constexpr mesh::NodeId kNone = mesh::kNoNode;
  // 5 x 3: background in the first and last columns, element 7 between, with 8 in the middle of the lower row.
  const std::vector<mesh::NodeId> leaf{kNone, 7, 7, 7, kNone,  //
                                       kNone, 7, 7, 7, kNone,  //
                                       kNone, 7, 8, 7, kNone};
  Image8 image(5, 3);
  for (int y = 0; y < 3; ++y) {
    for (int x = 0; x < 5; ++x) {
      if (leaf[static_cast<std::size_t>(y) * 5 + x] == kNone) continue;
      for (int c = 0; c < 3; ++c) image.at(x, y)[c] = 200;
    }
  }
  draw_leaf_edges(image, leaf);
  std::string drawn;  // '#' a line, '.' the scene unchanged, ' ' the background unchanged
  for (int y = 0; y < 3; ++y) {
    for (int x = 0; x < 5; ++x) {
      const std::uint8_t value = image.at(x, y)[0];
      drawn += value == 0 ? ' ' : value == 200 ? '.' : '#';
    }
    drawn += '/';
  }
  EXPECT_EQ(drawn, " #.# / ### / ### /");
}

// Radiosity is linear in Ke, which may be as large as 1e100 or as faint as 1e-100 (kMinEmission), and the tone map's
// exposure follows it: the PNGs show the same picture whatever the scale. Rendered into single precision as they
// were, the values were inf or 0, and a reviewer's scene with Ke 1e45 (or 1e-300) gave an all-white (all-black)
// flat.png and smooth.png. Scaled by powers of two here, so that the solves are exact multiples of one another and
// the files must agree byte for byte.
TEST(OutputsToneMap, ImagesDoNotDependOnTheScaleOfTheEmission) {
  const auto bytes = [](const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  };
  const fs::path root = fs::path(AARAD_BINARY_DIR) / "test-outputs" / ("scaled-" + std::to_string(getpid()));
  fs::remove_all(root);
  std::map<int, fs::path> folders;
  for (const int power : {0, 150, -300}) {
    Scene scene = make_cornell_box();
    for (Material& material : scene.materials) material.emission = material.emission * std::ldexp(1.0, power);
    SolverOptions options;
    options.meshing = default_meshing(scene);
    options.converge = 0.2;
    Solver solver(scene, options);
    solver.run();
    folders[power] = root / std::to_string(power);
    ASSERT_TRUE(write_solution_files(solver, folders[power], {.width = 64, .height = 48}).complete);
  }
  for (const char* name : {"flat.png", "smooth.png", "mesh.png"}) {
    EXPECT_GT(lit_fraction(read_image(folders[0] / name)), 0.5) << name;
    EXPECT_TRUE(bytes(folders[0] / name) == bytes(folders[150] / name)) << name;
    EXPECT_TRUE(bytes(folders[0] / name) == bytes(folders[-300] / name)) << name;
  }
  // The EXR holds radiosity as it is: 2^150 times as much is beyond single precision (inf), and the Cornell box's
  // radiosities times 2^-300 are below it (0).
  const ReadImage plain = read_image(folders[0] / "radiosity.exr");
  const ReadImage bright = read_image(folders[150] / "radiosity.exr");
  ASSERT_EQ(plain.pixels.size(), bright.pixels.size());
  for (std::size_t i = 0; i < plain.pixels.size(); ++i) {
    if (plain.pixels[i] > 0.0f) {
      EXPECT_TRUE(std::isinf(bright.pixels[i])) << i;
    }
  }
  EXPECT_EQ(lit_fraction(read_image(folders[-300] / "radiosity.exr")), 0.0);
  fs::remove_all(root);
}

TEST(OutputsToneMap, EmittersDoNotSetTheExposure) {
  SolverOptions options;
  options.backend = "analytic";
  options.adaptive = false;
  options.converge = 1e-12;
  options.meshing.patch_size = 10.0;
  options.meshing.element_size = 10.0;
  Scene scene = test::two_unit_squares();
  {
    Solver solver(scene, options);
    solver.run();
    const std::vector<Rgb> displayed = solver.displayed_radiosity();
    ASSERT_EQ(solver.hierarchy().leaf_count(), 2u);
    mesh::NodeId receiver = solver.hierarchy().leaves()[0];
    if (scene.material_of_surface(solver.hierarchy().surface(receiver)).emission.r > 0.0)
      receiver = solver.hierarchy().leaves()[1];
    // 0.5 F B_1 with the patch-to-patch factor F = C-11(1,1,1) = 0.1998249 (references.md; the near-field
    // correction shapes the other square from points over the shooter).
    EXPECT_NEAR(displayed[receiver].r, 0.1009, 1e-3);
    EXPECT_DOUBLE_EQ(solution_tone_map(solver, displayed).exposure, 1.0 / displayed[receiver].r);
  }
  // When every surface emits, the emitters set it: the brighter square, half the area, is the 99th percentile.
  scene.materials[1].emission = Rgb(2.0);
  Solver solver(scene, options);
  solver.run();
  const std::vector<Rgb> displayed = solver.displayed_radiosity();
  const double brightest = std::max(displayed[solver.hierarchy().leaves()[0]].r,
                                    displayed[solver.hierarchy().leaves()[1]].r);
  EXPECT_GT(brightest, 2.0);
  EXPECT_DOUBLE_EQ(solution_tone_map(solver, displayed).exposure, 1.0 / brightest);
}

// A lamp that lights nothing (facing away from the only other surface) leaves every surface that does not emit
// black: then the lamp sets the exposure and shows white, where exposure 1 drew a lamp of 0.01 nearly black.
TEST(OutputsToneMap, EmittersSetTheExposureWhenNothingElseIsLit) {
  Scene scene;
  scene.name = "lamp facing away";
  const std::uint32_t lamp = scene.add_group("lamp"), floor = scene.add_group("floor");
  const std::uint32_t glowing = scene.add_material({"glow", Rgb(0.0), Rgb(0.01)});
  const std::uint32_t white = scene.add_material({"white", Rgb(0.5), Rgb(0.0)});
  scene.add_face(lamp, glowing, {{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}});  // facing up, away from the floor
  scene.add_face(floor, white, {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}});
  scene.build_surfaces();
  SolverOptions options;
  options.adaptive = false;
  options.meshing.patch_size = 1.0;
  options.meshing.element_size = 1.0;
  Solver solver(scene, options);
  solver.run();
  const std::vector<Rgb> displayed = solver.displayed_radiosity();
  for (const mesh::NodeId leaf : solver.hierarchy().leaves()) {
    if (scene.groups[scene.surfaces[solver.hierarchy().surface(leaf)].group].name == "floor") {
      ASSERT_EQ(displayed[leaf].max_component(), 0.0);
    }
  }
  EXPECT_DOUBLE_EQ(solution_tone_map(solver, displayed).exposure, 1.0 / 0.01);
}

// A small white card under a lamp on a black floor (a reviewer's scene): the card is lit, the floor (Kd 0) is not, and
// the card is less than 1 % of the area that does not emit, so the 99th percentile over all of it is 0. Exposure 1
// then drew the card dark at Ke 10, black at Ke 0.001 and white at Ke 1e4; the percentile is now the lit area's,
// and the exposure follows Ke.
TEST(OutputsToneMap, ALitAreaOfUnderOnePercentSetsTheExposure) {
  for (const double ke : {10.0, 1e-3, 1e4}) {
    Scene scene;
    scene.name = "card on a black floor";
    const std::uint32_t floor = scene.add_group("floor"), card = scene.add_group("card"), lamp = scene.add_group("lamp");
    const std::uint32_t black = scene.add_material({"black", Rgb(0.0), Rgb(0.0)});
    const std::uint32_t white = scene.add_material({"white", Rgb(0.7), Rgb(0.0)});
    const std::uint32_t glow = scene.add_material({"glow", Rgb(0.0), Rgb(ke)});
    scene.add_face(floor, black, {{-5, 0, 5}, {5, 0, 5}, {5, 0, -5}, {-5, 0, -5}});
    scene.add_face(card, white, {{-0.25, 0.01, 0.25}, {0.25, 0.01, 0.25}, {0.25, 0.01, -0.25}, {-0.25, 0.01, -0.25}});
    scene.add_face(lamp, glow, {{-0.1, 1, -0.1}, {0.1, 1, -0.1}, {0.1, 1, 0.1}, {-0.1, 1, 0.1}});  // facing down
    scene.build_surfaces();
    SolverOptions options;
    options.adaptive = false;
    options.meshing.patch_size = 20.0;
    options.meshing.element_size = 20.0;
    Solver solver(scene, options);
    solver.run();
    const std::vector<Rgb> displayed = solver.displayed_radiosity();
    double brightest_card = 0.0;
    for (const mesh::NodeId leaf : solver.hierarchy().leaves()) {
      if (scene.surfaces[solver.hierarchy().surface(leaf)].group == card)
        brightest_card = std::max(brightest_card, displayed[leaf].r);
    }
    ASSERT_GT(brightest_card, 0.0) << ke;
    // The card fills the lit area: exposure x its brightest value is at least 0.99's share of it, and at most 1.
    const double exposure = solution_tone_map(solver, displayed).exposure;
    EXPECT_GT(exposure * brightest_card, 0.5) << ke;
    EXPECT_LE(exposure * brightest_card, 1.0 + 1e-12) << ke;
  }
}

// The report's numbers for the furnace (E = 1, rho = 0.5 everywhere: B = E / (1 - rho) = 2 on every surface): the
// room of 4 x 3 x 5 (area 94), block_a 1 x 0.9 x 1.2 (area 6.36, six faces of its group) and block_b 1 x 0.9 x 0.7
// (area 4.46) emit 104.82; each group's mean radiosity is its leaves' area-weighted mean, within a few per cent of 2
// once the unshot flux is below 1 % of the emitted (the hemicube's factors are not exact). The fields beside the contract's are the solver's, and the times are
// the caller's when given.
TEST(OutputsReport, FurnaceGroupsFluxesAndTimes) {
  const Scene scene = make_furnace();
  SolverOptions options;
  options.resolution = 50;
  options.adaptive = false;  // a quick solve: the report is the subject here
  options.meshing.balance = true;
  Solver solver(scene, options);
  solver.run();
  ASSERT_TRUE(solver.converged());
  const nlohmann::json report =
      make_report(solver, {{"test-invariant", mesh::kNoNode, "no node"}, {"test-invariant", 5, "node 5"}},
                  {.output = 1.5});
  EXPECT_NEAR(report["emitted_flux"][0].get<double>(), 104.82, 1e-9);
  std::map<std::string, double> area;
  for (const auto& group : report["groups"]) {
    area[group["name"].get<std::string>()] += group["area"].get<double>();
    for (int c = 0; c < 3; ++c) {
      EXPECT_NEAR(group["mean_radiosity"][c].get<double>(), 2.0, 0.05) << group["name"];
    }
  }
  EXPECT_NEAR(area.at("block_a"), 6.36, 1e-12);
  EXPECT_NEAR(area.at("block_b"), 4.46, 1e-12);
  double total_area = 0.0;
  for (const auto& [name, a] : area) total_area += a;
  EXPECT_NEAR(total_area, 104.82, 1e-9);

  ASSERT_EQ(report["invariants"]["violations"].size(), 2u);
  EXPECT_TRUE(report["invariants"]["violations"][0]["node"].is_null());
  EXPECT_EQ(report["invariants"]["violations"][1]["node"], 5);

  EXPECT_EQ(report["seconds"]["output"], 1.5);
  EXPECT_EQ(report["seconds"]["total"], solver.times().total + 1.5);
  EXPECT_EQ(make_report(solver, {}, {.total = 0.0, .output = 1.5})["seconds"]["total"], 0.0);
  EXPECT_EQ(make_report(solver, {}, {.total = 7.0})["seconds"]["total"], 7.0);

  // The solver's deepest leaf and its splits, not the options' limit and the shots.
  EXPECT_EQ(report["max_level"], solver.max_leaf_level());
  EXPECT_EQ(report["options"]["max_level"], 8);
  EXPECT_NE(solver.max_leaf_level(), 8);
  EXPECT_EQ(report["splits"], solver.splits());
  EXPECT_NE(solver.splits(), solver.shots());  // no split, many shots
  // Shots that reused their patch's factors: no split, so all but the first of each patch.
  EXPECT_EQ(report["reused_shots"], solver.reused_shots());
  EXPECT_EQ(report["area_shooters"], solver.area_shooters());
  EXPECT_GT(solver.reused_shots(), 0);
  EXPECT_LT(solver.reused_shots(), solver.shots());
  EXPECT_EQ(report["options"]["factor_cache_mib"], 2048);
  EXPECT_EQ(report["ambient"], rgb_json(solver.ambient()));
  EXPECT_EQ(report["unshot_flux"], rgb_json(solver.unshot_flux()));
  EXPECT_NE(rgb_json(solver.ambient()), rgb_json(solver.unshot_flux()));
  EXPECT_EQ(report["options"]["balance"], true);
  EXPECT_EQ(report["options"]["adaptive"], false);
  EXPECT_EQ(report["options"]["gradient"], 0.1);
  EXPECT_EQ(report["options"]["converge"], 0.01);
}

}  // namespace
}  // namespace aarad::refine
