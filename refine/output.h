// The files of a solve (docs/solver.md, "aarad solve"): DIR/mesh.ply, flat.png, smooth.png, mesh.png, radiosity.exr and
// report.json, each written under a temporary name and renamed, so each is whole or absent.
#pragma once

#include "aarad/core/image.h"
#include "aarad/refine/solver.h"

#include <nlohmann/json.hpp>

#include <array>
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace aarad::refine {

struct OutputOptions {
  int width = 512;
  int height = 512;
  // Asked before each file (none: write them all). When it returns false, write_solution_files writes no further
  // file and returns with OutputResult::complete false: `aarad solve` stops there after a second Ctrl-C, between
  // two files, so that every file is whole or absent and no temporary stays behind.
  std::function<bool()> keep_writing = nullptr;
};

struct OutputResult {
  ToneMap tone_map;                          // the exposure used for the PNGs and the PLY's vertex colours
  std::vector<std::filesystem::path> files;  // in the order written
  bool complete = true;                      // false when keep_writing stopped it before the last file
  double seconds = 0.0;
};

// The tone map of the images: exposure maps the 99th area-weighted percentile of the leaves' displayed
// max(r, g, b) to 1 (docs/solver.md).
ToneMap solution_tone_map(const Solver& solver, std::span<const Rgb> displayed);

// The files of a solve in `directory`, in the order they are written: write_solution_files, then write_report.
inline constexpr std::array<std::string_view, 6> kSolutionFileNames = {
    "mesh.ply", "flat.png", "smooth.png", "mesh.png", "radiosity.exr", "report.json"};

// Checks, without creating anything, that write_solution_files could create `directory` and write into it: the
// directory, or the nearest ancestor that exists, is a directory this process may write into, no part of the
// path is a symbolic link to nothing, and none of kSolutionFileNames in it is a directory or another file that
// is neither regular nor a symbolic link (a FIFO, a device), nor, in a sticky folder such as /tmp, a file of
// another user that this process may not replace. A solve calls it before it starts, so that it does not end in an
// error about its output. Throws aarad::Error.
void check_output_directory(const std::filesystem::path& directory);

// Writes mesh.ply, flat.png, smooth.png, mesh.png and radiosity.exr into `directory` (created when missing),
// from the scene's camera or, without one, Scene::fitted_camera, in that order, each after asking
// options.keep_writing. Throws aarad::Error naming the file on failure. report.json marks a whole set (write it
// with write_report after this): an earlier solve's report.json in `directory` is removed before the first file is
// written, and when the writing stops early (a failure, or keep_writing), so are the earlier solve's files of
// kSolutionFileNames that were not written again, so that the directory never mixes the files of two solves.
OutputResult write_solution_files(const Solver& solver, const std::filesystem::path& directory,
                                  const OutputOptions& options = {});

// Writes `report` (indented JSON and a newline) to `path` atomically.
void write_report(const nlohmann::json& report, const std::filesystem::path& path);

}  // namespace aarad::refine
