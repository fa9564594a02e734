// Output files of a solve; see output.h and docs/solver.md for the tone map and what each image shows.
#include "aarad/refine/output.h"

#include "aarad/core/atomic_file.h"
#include "aarad/core/error.h"
#include "aarad/mesh/display.h"
#include "aarad/mesh/export_ply.h"
#include "aarad/refine/render.h"
#include "aarad/refine/report.h"

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <functional>
#include <string>
#include <string_view>
#include <system_error>

#include <sys/stat.h>
#include <unistd.h>

namespace aarad::refine {

ToneMap solution_tone_map(const Solver& solver, std::span<const Rgb> displayed) {
  const mesh::Hierarchy& hierarchy = solver.hierarchy();
  const Scene& scene = solver.scene();
  std::vector<Rgb> values;
  std::vector<double> areas;
  // Emitters clip to white: a lamp of a few percent of the area, often 10-100x brighter than what it lights,
  // would otherwise set the exposure and leave the lit surfaces dark. Only when no surface that does not emit is
  // lit (every surface emits, as in the furnace, or the lamps light nothing) do the emitters set it: a lamp of
  // Ke 0.01 over an unlit floor was drawn at exposure 1, nearly black.
  const auto lit = [](const Rgb& value) { return value.max_component() > 0.0; };
  for (const bool emitters : {false, true}) {
    values.clear();
    areas.clear();
    for (mesh::NodeId leaf : hierarchy.leaves()) {
      if (!emitters && scene.material_of_surface(hierarchy.surface(leaf)).emission.max_component() > 0.0) continue;
      values.push_back(displayed[leaf]);
      areas.push_back(hierarchy.area(leaf));
    }
    if (std::any_of(values.begin(), values.end(), lit)) break;
  }
  // The lit area, when it is at most 1 - kPercentile of the area: then the percentile is an unlit leaf's 0, which
  // left exposure 1 and the images depending on Ke (a small card under a lamp on a black floor was dark at Ke 10
  // and white at Ke 1e4). The percentile is then the lit area's.
  constexpr double kPercentile = 0.99;
  double all = 0.0, lit_area = 0.0;
  for (std::size_t i = 0; i < values.size(); ++i) {
    all += areas[i];
    if (lit(values[i])) lit_area += areas[i];
  }
  if (lit_area > 0.0 && lit_area <= (1.0 - kPercentile) * all) {
    std::size_t kept = 0;
    for (std::size_t i = 0; i < values.size(); ++i) {
      if (!lit(values[i])) continue;
      values[kept] = values[i];
      areas[kept] = areas[i];
      ++kept;
    }
    values.resize(kept);
    areas.resize(kept);
  }
  return ToneMap::from_percentile(values, areas, kPercentile);
}

void check_output_directory(const std::filesystem::path& directory) {
  namespace fs = std::filesystem;
  std::error_code error;
  const fs::path absolute = fs::absolute(directory, error);
  if (error) throw Error("cannot create directory " + directory.string() + ": " + error.message());
  fs::path existing = absolute;
  while (!fs::exists(existing, error)) {
    // A symbolic link that leads nowhere does not exist, yet create_directories cannot make a directory in its
    // place ("File exists").
    if (fs::is_symlink(fs::symlink_status(existing, error))) {
      throw Error("cannot create directory " + directory.string() + ": " + existing.string() +
                  " is a symbolic link to " + fs::read_symlink(existing, error).string() +
                  ", which does not exist; remove the link or create what it points to");
    }
    if (!existing.has_parent_path() || existing == existing.parent_path()) break;
    existing = existing.parent_path();
  }
  if (!fs::is_directory(existing, error))
    throw Error("cannot create directory " + directory.string() + ": " + existing.string() + " is not a directory");
  if (::access(existing.c_str(), W_OK | X_OK) != 0)
    throw Error("cannot write files in " + existing.string() + ": " + std::strerror(errno));
  if (existing != absolute) return;  // the directory is new: nothing in it yet
  // In a sticky folder (mode +t, as /tmp), a file may be replaced or removed only by its owner, the folder's
  // owner or root (rename(2) and unlink(2) give EPERM otherwise): another user's report.json in /tmp/out let the
  // whole solve run and then fail, leaving the new mesh.ply beside the old images.
  struct stat folder {};
  const bool sticky = ::stat(absolute.c_str(), &folder) == 0 && (folder.st_mode & S_ISVTX) != 0 &&
                      folder.st_uid != ::geteuid() && ::geteuid() != 0;
  // Every file is renamed into place: rename(2) cannot replace a directory, and a FIFO or a device is not a file a
  // solve should replace. A regular file, or a symbolic link (replaced, not followed), is fine.
  for (const std::string_view name : kSolutionFileNames) {
    const fs::path path = directory / name;
    const fs::file_status status = fs::symlink_status(path, error);
    if (!fs::exists(status)) continue;
    if (fs::is_regular_file(status) || fs::is_symlink(status)) {
      struct stat file {};
      if (sticky && ::lstat(path.c_str(), &file) == 0 && file.st_uid != ::geteuid())
        throw Error("cannot replace " + path.string() + ": it belongs to another user (uid " +
                    std::to_string(file.st_uid) + ") and " + directory.string() +
                    " is a sticky folder, where only a file's owner may replace it; remove it as its owner or write "
                    "the solution elsewhere");
      continue;
    }
    throw Error("cannot write " + path.string() + ": it exists and is " +
                (fs::is_directory(status) ? "a directory" : "not a regular file") +
                "; move it away or write the solution elsewhere");
  }
}

namespace {

// The five files of write_solution_files, in order, each after asking next_file; result.files lists those written.
void write_files(const Solver& solver, const std::filesystem::path& directory, const OutputOptions& options,
                 const std::function<bool()>& next_file, OutputResult& result) {
  namespace fs = std::filesystem;
  const mesh::Hierarchy& hierarchy = solver.hierarchy();
  const std::vector<Rgb> radiosity = solver.radiosity();
  const std::vector<Rgb> displayed = solver.displayed_radiosity();
  result.tone_map = solution_tone_map(solver, displayed);
  const ToneMap map = result.tone_map;

  // One display mesh of the displayed values for every file. The PLY carries the solution B per face (no ambient
  // term); its vertex colours are the displayed values through the images' tone map, as smooth.png shows them.
  const mesh::DisplayMesh display = mesh::build_display_mesh(hierarchy, displayed);
  const fs::path ply = directory / "mesh.ply";
  mesh::write_ply(hierarchy, radiosity, display, [map](const Rgb& value) { return map(value); }, ply);
  result.files.push_back(ply);

  const Scene& scene = solver.scene();
  const double aspect = static_cast<double>(options.width) / options.height;
  const Camera camera = scene.camera ? *scene.camera : scene.fitted_camera(aspect);
  if (!next_file()) return;

  // The images are rendered scaled by a power of two near the exposure (render.h), so that single precision keeps
  // what the tone map shows: with Ke 1e45 or 1e-300 the values as they are were inf or 0, and flat.png and
  // smooth.png all white or all black while the PLY's colours were graded. Powers of two scale exactly: the PNGs
  // and the EXR are bit for bit what scale 1 gives wherever that was in range.
  const double scale = image_scale(map.exposure);
  const ToneMap scaled_map{map.exposure / scale};
  const Rendering flat = render(display, displayed, camera, options.width, options.height, Shading::kFlat, scale);
  const Image8 flat_display = tone_map(flat.image, scaled_map);
  write_png(flat_display, directory / "flat.png");
  result.files.push_back(directory / "flat.png");

  if (!next_file()) return;
  const Rendering smooth =
      render(display, displayed, camera, options.width, options.height, Shading::kSmooth, scale);
  write_png(tone_map(smooth.image, scaled_map), directory / "smooth.png");
  result.files.push_back(directory / "smooth.png");

  if (!next_file()) return;
  Image8 with_edges = flat_display;
  draw_leaf_edges(with_edges, flat.leaf);
  write_png(with_edges, directory / "mesh.png");
  result.files.push_back(directory / "mesh.png");

  if (!next_file()) return;
  Image linear = flat.image;  // radiosity as it is: inf beyond single precision (aarad warns), 0 below it
  for (float& value : linear.pixels) value = static_cast<float>(static_cast<double>(value) / scale);
  write_exr(linear, directory / "radiosity.exr");
  result.files.push_back(directory / "radiosity.exr");
}

}  // namespace

OutputResult write_solution_files(const Solver& solver, const std::filesystem::path& directory,
                                  const OutputOptions& options) {
  namespace fs = std::filesystem;
  const auto start = std::chrono::steady_clock::now();
  if (options.width < 1 || options.height < 1) throw Error("image size must be at least 1 x 1");
  OutputResult result;
  // Before each file: false when the caller asks to stop, and then the result says how far it got.
  const auto next_file = [&] {
    if (!options.keep_writing || options.keep_writing()) return true;
    result.complete = false;
    return false;
  };
  if (!next_file()) return result;
  std::error_code error;
  fs::create_directories(directory, error);
  if (error) throw Error("cannot create directory " + directory.string() + ": " + error.message());

  // report.json marks a whole set of files: write_report writes it last. An earlier solve's report goes before
  // this solve writes its first file, and when the writing stops early (a failure, or keep_writing), the earlier
  // solve's files that this one did not write again go too: the directory never mixes the files of two solves.
  const auto remove_earlier_files = [&] {
    for (const std::string_view name : kSolutionFileNames) {
      const fs::path path = directory / name;
      if (std::find(result.files.begin(), result.files.end(), path) != result.files.end()) continue;
      std::error_code ignored;
      const fs::file_status status = fs::symlink_status(path, ignored);
      if (fs::is_regular_file(status) || fs::is_symlink(status)) fs::remove(path, ignored);
    }
  };
  fs::remove(directory / "report.json", error);
  if (error) throw Error("cannot remove " + (directory / "report.json").string() + ": " + error.message());
  try {
    write_files(solver, directory, options, next_file, result);
  } catch (...) {
    remove_earlier_files();
    throw;
  }
  if (!result.complete) remove_earlier_files();
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

void write_report(const nlohmann::json& report, const std::filesystem::path& path) {
  write_bytes_atomically(path, json_text(report, 2) + '\n');
}

}  // namespace aarad::refine
