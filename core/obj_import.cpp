// OBJ/MTL import (see obj_import.h for the contract). Structure from tinyobjloader
// (https://github.com/tinyobjloader/tinyobjloader, 2.0.0rc10, double precision); line numbers, exact
// coordinates and material values from a second, line-by-line read of the files. Non-planar faces are
// split by ear clipping (Meisters, "Polygons have ears", Amer. Math. Monthly 82, 1975) on the face's
// projection, with CGAL's exact orientation predicates deciding convexity and containment.
#include "aarad/core/obj_import.h"

#include "aarad/core/error.h"
#include "aarad/core/face_check.h"
#include "aarad/core/polygon.h"
#include "aarad/core/predicates.h"

// The CMake target defines it too; the header must see it in any case (double-precision real_t).
#ifndef TINYOBJLOADER_USE_DOUBLE
#define TINYOBJLOADER_USE_DOUBLE
#endif
#include <tiny_obj_loader.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <string_view>
#include <tuple>
#include <unordered_set>
#include <utility>

namespace aarad {
namespace {

namespace fs = std::filesystem;

// The words of a line: what `std::istringstream(line) >> word` reads in turn, the runs between the blanks it skips
// in the classic locale, found without building a stream per line (a stream per line was about a fifth of
// importing a million-face sphere).
std::vector<std::string> split_tokens(const std::string& line) {
  constexpr std::string_view kBlanks = " \t\n\v\f\r";
  const std::string_view text(line);
  std::vector<std::string> tokens;
  for (std::size_t begin = text.find_first_not_of(kBlanks); begin != std::string_view::npos;) {
    const std::size_t end = text.find_first_of(kBlanks, begin);
    tokens.emplace_back(text.substr(begin, end - begin));
    begin = end == std::string_view::npos ? end : text.find_first_not_of(kBlanks, end);
  }
  return tokens;
}

// The text of an OBJ or MTL file as both readers here see it: without a UTF-8 byte-order mark (Notepad writes
// one, and it would hide the first statement, often the mtllib or newmtl line), with old Mac line ends (CR
// alone) read as line ends, and without a comment after a statement of numbers or file and material names
// ("f 1 2 3 4 # lid": a '#' after a blank), which tinyobjloader would read as part of it. A material's name ends
// there too, where it is defined and where it is used ("newmtl lamp # the light" defines "lamp", as "usemtl lamp #
// the light" uses it; the whole line was the name, which no `usemtl` matched). Group names keep a '#' ("o Chair
// #1"); whole-line comments stay (the "# aarad" lines are
// read from them); every line keeps its number. `fo`, an older spelling of the face statement `f`, is read as `f`
// (tinyobjloader passes over it, and its faces would vanish without a word). A statement whose line ends with a
// backslash goes on on the next line (Wavefront's OBJ specification, appendix B1, "\" line continuation): it is
// joined into one line under the number of its first, and an empty line stands in for each line joined to it, so
// the lines after it keep their numbers. Comment lines are not continued.
std::string clean_text(std::istream& in, const std::string& path) {
  static const std::set<std::string> kCommentAfter{"v",  "vt", "vn", "vp", "f", "l",  "p",  "s",     "mtllib",
                                                   "usemtl", "newmtl", "Kd", "Ka", "Ks", "Ke", "Tf", "Ns", "Ni",
                                                   "d",  "Tr", "illum"};
  std::string text;
  // A file that opens but fails as it is read (/proc/self/mem, a disk error) throws from the stream's buffer; said
  // as a problem of the file, not an internal error.
  try {
    errno = 0;
    text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  } catch (const std::ios_base::failure&) {
    const int reason = errno;
    throw InputError(path, 0, std::string("cannot read the file (") +
                                  (reason != 0 ? std::strerror(reason) : "read error") + ")");
  }
  if (in.bad()) throw InputError(path, 0, "cannot read the file (read error)");
  if (text.starts_with("\xEF\xBB\xBF")) text.erase(0, 3);
  // Every line end is one LF: CR LF, and a CR alone also in a file of LF line ends, as tinyobjloader's reader
  // splits lines; where it split at a CR that the line count did not, the faces' line numbers were lost (a stray CR
  // in a comment made the rest of it a statement for the reader, and every message after it said line 0).
  // A vertical tab or form feed is a blank, as the reader takes it when it splits a statement (the line count
  // split at spaces and tabs only, and told a face of 4 vertices written "f 1\v2 3 4" to split it into faces of at
  // most 255).
  std::size_t kept = 0;
  for (std::size_t k = 0; k < text.size(); ++k) {
    if (text[k] == '\v' || text[k] == '\f') {
      text[kept++] = ' ';
    } else if (text[k] != '\r') {
      text[kept++] = text[k];
    } else {
      text[kept++] = '\n';
      if (k + 1 < text.size() && text[k + 1] == '\n') ++k;
    }
  }
  text.resize(kept);
  // A NUL byte cut the statement it stood in short, without a word: "o wall\0A" and "o wall\0B" named one group
  // 'wall', and "v 1 1\0001" lacked a coordinate. A text file holds none.
  if (const auto nul = text.find('\0'); nul != std::string::npos) {
    const auto line = 1 + std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(nul), '\n');
    throw InputError(path, static_cast<int>(line), "a NUL byte, which a text file does not hold; OBJ and MTL files are "
                                                   "text: is this a binary file, or was the file damaged?");
  }
  // Where the backslash that continues `line` is (the last character but blanks and a CR), or npos.
  const auto continuation = [](const std::string& line) {
    const auto first = line.find_first_not_of(" \t");
    const auto last = line.find_last_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#' || line[last] != '\\') return std::string::npos;
    return last;
  };
  std::string out;
  out.reserve(text.size() + 1);
  std::istringstream lines(text);
  std::string line, next;
  while (std::getline(lines, line)) {
    std::size_t joined = 0;
    for (auto at = continuation(line); at != std::string::npos && std::getline(lines, next); at = continuation(line)) {
      line.replace(at, std::string::npos, " " + next);
      ++joined;
    }
    const auto first = line.find_first_not_of(" \t");
    auto key_end = first == std::string::npos ? first : line.find_first_of(" \t", first);
    if (first != std::string::npos && line.substr(first, key_end - first) == "fo") {
      line.erase(first + 1, 1);
      key_end = key_end == std::string::npos ? key_end : key_end - 1;
    }
    // A material's name starts after the blanks that follow `newmtl`, however many: tinyobjloader took all but the
    // first of them into the name ("newmtl  lamp" defined " lamp"), which no `usemtl` finds, and the material's
    // faces got the default one, emission lost, without a word (read_mtl_text trims the name and found it defined).
    if (first != std::string::npos && key_end != std::string::npos &&
        line.compare(first, key_end - first, "newmtl") == 0) {
      const auto name = line.find_first_not_of(" \t", key_end);
      if (name != std::string::npos) line.replace(key_end, name - key_end, " ");
    }
    if (first != std::string::npos && kCommentAfter.contains(line.substr(first, key_end - first))) {
      for (std::size_t i = first + 1; i < line.size(); ++i) {
        if (line[i] == '#' && (line[i - 1] == ' ' || line[i - 1] == '\t')) {
          line.erase(i);
          break;
        }
      }
    }
    out += line;
    out.append(joined + 1, '\n');
  }
  return out;
}

// tinyobjloader's material reader for cleaned MTL text, found as tinyobjloader finds it: relative to the OBJ's
// folder. A library that cannot be read is skipped (import_obj warns about it by name). So is one that is not a
// regular file: a folder opens, and reading it threw std::ios_base::failure ("basic_filebuf::underflow error
// reading the file: Is a directory"), an internal error.
class CleanMaterialReader final : public tinyobj::MaterialReader {
 public:
  explicit CleanMaterialReader(fs::path folder) : folder_(std::move(folder)) {}
  bool operator()(const std::string& name, std::vector<tinyobj::material_t>* materials,
                  std::map<std::string, int>* material_map, std::string* warnings, std::string* errors) override {
    std::error_code error;
    if (!fs::is_regular_file(folder_ / name, error)) return false;
    std::ifstream in(folder_ / name);
    if (!in) return false;
    std::istringstream text(clean_text(in, (folder_ / name).string()));
    tinyobj::LoadMtl(material_map, materials, &text, warnings, errors);
    return true;
  }

 private:
  fs::path folder_;
};

std::string trim(const std::string& s) {
  const auto first = s.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return {};
  const auto last = s.find_last_not_of(" \t\r\n");
  return s.substr(first, last - first + 1);
}

// A word of the file as a message shows it: whole up to 64 bytes, else its start (cut between UTF-8 characters) and
// its length (a reviewer's coordinate of ten million digits made a 10 MB error line).
// Control characters are escaped (printable()): a NUL byte in a coordinate cut the message off after it.
std::string shown(const std::string& word) {
  if (word.size() <= 64) return printable(word);
  std::size_t end = 48;
  while (end > 0 && (static_cast<unsigned char>(word[end]) & 0xC0) == 0x80) --end;  // not inside a UTF-8 character
  return printable(word.substr(0, end)) + "... (" + std::to_string(word.size()) + " bytes)";
}

// strtod over a whole token: nullopt when the token is not a number. NaN and infinity parse (and are
// rejected by the callers with a message that says so).
std::optional<double> parse_number(const std::string& token) {
  const char* begin = token.c_str();
  char* end = nullptr;
  errno = 0;
  const double value = std::strtod(begin, &end);
  // The whole token: a NUL byte inside it ("1\0x", a damaged file) ends the C string before the token does.
  if (end == begin || end != begin + token.size()) return std::nullopt;
  return value;
}

// Whether a token of an `f` line has the form v, v/vt, v//vn or v/vt/vn, each a nonzero whole number (the
// range of v is checked later, against the vertices read).
bool vertex_reference(const std::string& token) {
  std::size_t at = 0;
  const auto whole_number = [&](bool optional) {
    const std::size_t start = at;
    if (at < token.size() && (token[at] == '-' || token[at] == '+')) ++at;
    const std::size_t digits = at;
    while (at < token.size() && token[at] >= '0' && token[at] <= '9') ++at;
    if (at == digits) return optional && at == start;
    return token.find_first_not_of("+-0", start) < at;  // not zero
  };
  if (!whole_number(false)) return false;
  for (int part = 0; part < 2 && at < token.size(); ++part) {
    if (token[at] != '/') return false;
    ++at;
    if (!whole_number(part == 0)) return false;  // only the texture index may be empty (v//vn)
  }
  return at == token.size() && token.back() != '/';  // "1/" leaves the texture index out without a normal
}

std::string number_text(double v) {
  std::ostringstream out;
  out.precision(10);
  out << v;
  return out.str();
}

std::string rgb_text(const Rgb& c) { return number_text(c.r) + " " + number_text(c.g) + " " + number_text(c.b); }

// What the line-by-line read of the OBJ file finds.
struct ObjText {
  std::vector<Vec3> positions;   // every `v`, parsed with strtod
  std::vector<int> face_lines;   // line of every `f` with at least three vertex references, in order
  std::vector<std::size_t> face_sizes;  // the number of vertex references on each of those lines
  std::size_t short_faces = 0;   // `f` lines with fewer than three vertex references (skipped with a warning)
  int first_short_line = 0;      // the first of them, and its warning
  std::string first_short_warning;
  std::vector<std::pair<int, std::string>> material_libraries;  // (line, file name) per `mtllib` entry
  std::vector<std::pair<int, std::string>> material_uses;       // (line, name) per `usemtl`
  std::optional<Camera> camera;
  std::optional<MeshingHint> meshing;
};

// The comments' readers say what is wrong with a comment they cannot use in `problem`, for the warning.
std::optional<Camera> parse_camera_comment(const std::vector<std::string>& t, std::string& problem) {
  // # aarad camera: eye X Y Z forward X Y Z up X Y Z vertical_fov RADIANS
  if (t.size() != 14 || t[4] != "forward" || t[8] != "up" || t[12] != "vertical_fov" || t[0] != "eye") {
    problem = "its words are not in the order below";
    return std::nullopt;
  }
  std::array<double, 10> v{};
  const std::array<int, 10> at{1, 2, 3, 5, 6, 7, 9, 10, 11, 13};
  for (std::size_t i = 0; i < at.size(); ++i) {
    const std::string& word = t[static_cast<std::size_t>(at[i])];
    const auto n = parse_number(word);
    if (!n || !std::isfinite(*n)) {
      problem = "'" + shown(word) + "' is not a finite number";
      return std::nullopt;
    }
    v[i] = *n;
  }
  Camera camera;
  camera.eye = Vec3(v[0], v[1], v[2]);
  camera.forward = Vec3(v[3], v[4], v[5]);
  camera.up = Vec3(v[6], v[7], v[8]);
  camera.vertical_fov = v[9];
  const double lf = glm::length(camera.forward), lu = glm::length(camera.up);
  if (!(lf > 0.0 && std::isfinite(lf))) {
    problem = lf == 0.0 ? "forward is the zero vector" : "forward is too long for a double";
    return std::nullopt;
  }
  if (!(lu > 0.0 && std::isfinite(lu))) {
    problem = lu == 0.0 ? "up is the zero vector" : "up is too long for a double";
    return std::nullopt;
  }
  if (!(camera.vertical_fov > 0.0 && camera.vertical_fov < kPi)) {
    problem = "vertical_fov " + shown(t[13]) + " is not between 0 and pi radians";
    return std::nullopt;
  }
  camera.forward /= lf;
  camera.up /= lu;
  camera.up -= glm::dot(camera.up, camera.forward) * camera.forward;
  if (glm::length(camera.up) < 1e-9) {
    problem = "up is parallel to forward";
    return std::nullopt;
  }
  camera.up = glm::normalize(camera.up);
  return camera;
}

std::optional<MeshingHint> parse_meshing_comment(const std::vector<std::string>& t, std::string& problem) {
  // # aarad meshing: patch_size P element_size E min_area A, in any order, each at most once; one left out is 0
  // (the hierarchy's default)
  static constexpr std::array<const char*, 3> kKeys{"patch_size", "element_size", "min_area"};
  if (t.empty()) {
    problem = "it gives no size";
    return std::nullopt;
  }
  std::array<double, 3> v{};
  std::array<bool, 3> seen{};
  for (std::size_t i = 0; i < t.size(); i += 2) {
    const auto k = static_cast<std::size_t>(std::find(kKeys.begin(), kKeys.end(), t[i]) - kKeys.begin());
    if (k == kKeys.size()) {
      problem = "'" + shown(t[i]) + "' is not one of its names";
      return std::nullopt;
    }
    if (seen[k]) {
      problem = t[i] + " is given twice";
      return std::nullopt;
    }
    if (i + 1 == t.size()) {
      problem = t[i] + " has no number after it";
      return std::nullopt;
    }
    const auto n = parse_number(t[i + 1]);
    if (!n || !std::isfinite(*n) || !(*n >= 0.0)) {
      problem = t[i] + " '" + shown(t[i + 1]) + "' is not a finite number >= 0";
      return std::nullopt;
    }
    v[k] = *n;
    seen[k] = true;
  }
  return MeshingHint{v[0], v[1], v[2]};
}

// Statements of the OBJ format (Wavefront's specification, appendix B1) that this importer reads or may pass
// over in silence: texture and normal data, groups, smoothing, free-form geometry, display attributes.
bool obj_statement(const std::string& key) {
  static const std::set<std::string> kKnown{
      "v",     "vt",    "vn",     "vp",     "f",      "fo",       "l",          "p",         "o",
      "g",     "s",     "mg",     "usemtl", "mtllib", "cstype",   "deg",        "bmat",      "step",
      "curv",  "curv2", "surf",   "parm",   "trim",   "hole",     "scrv",       "sp",        "end",
      "con",   "bevel", "lod",    "maplib", "usemap", "c_interp", "d_interp",   "shadow_obj", "trace_obj",
      "ctech", "stech", "call",   "csh"};
  return key.starts_with('#') || kKnown.contains(key);
}

// Names the groups that an `o` or `g` line without a name starts: `unnamed_line_N`, N its line. tinyobjloader
// passed over a bare `o` or `g` (its faces joined the group before) but started a group named after the file
// at one followed by blanks. A warning names the line when faces follow it; exporters end objects with a bare
// `g` (3ds Max), which starts no group since no face follows.
std::string with_unnamed_groups_named(const std::string& text, const std::string& path,
                                      std::vector<std::string>& warnings) {
  std::string out;
  out.reserve(text.size());
  std::istringstream lines(text);
  std::string line;
  int number = 0;
  std::optional<std::pair<int, std::string>> unnamed;  // (line, statement) of the last `o` or `g` if unnamed
  while (std::getline(lines, line)) {
    ++number;
    const std::vector<std::string> t = split_tokens(line);
    if (!t.empty() && (t[0] == "o" || t[0] == "g")) {
      unnamed.reset();
      if (t.size() == 1) {
        line = t[0] + " unnamed_line_" + std::to_string(number);
        unnamed.emplace(number, t[0]);
      }
    } else if (!t.empty() && t[0] == "f" && unnamed) {
      warnings.push_back(InputError::format(path, unnamed->first, "'" + unnamed->second + "' without a name: its "
                                                                  "faces form the group 'unnamed_line_" +
                                                                  std::to_string(unnamed->first) + "'; name it"));
      unnamed.reset();
    }
    out += line;
    out += '\n';
  }
  return out;
}

ObjText read_obj_text(const std::string& path, std::istream& in, std::vector<std::string>& warnings) {
  ObjText text;
  std::string line;
  int number = 0;
  std::map<std::string, std::pair<int, int>> unknown;  // statement -> (first line, lines)
  // Texture coordinates and normals aarad does not use, counted to check the faces' references to them: one out of
  // range is a damaged file (or faces copied from another), said once with its first line.
  long long texture_coordinates = 0, normals = 0;
  int first_bad_reference = 0, bad_references = 0;
  while (std::getline(in, line)) {
    ++number;
    const std::vector<std::string> t = split_tokens(line);
    if (t.empty()) continue;
    const std::string& key = t[0];
    if (!obj_statement(key)) {
      auto& [first, count] = unknown.try_emplace(key, number, 0).first->second;
      ++count;
    }
    if (key == "v") {
      if (t.size() < 4)
        throw InputError(path, number, "a vertex needs three coordinates ('v x y z'); complete or remove this line");
      Vec3 p;
      for (int c = 0; c < 3; ++c) {
        const auto value = parse_number(t[static_cast<std::size_t>(c + 1)]);
        if (!value)
          throw InputError(path, number, "vertex coordinate '" + shown(t[static_cast<std::size_t>(c + 1)]) +
                                             "' is not a number; write a finite decimal number");
        // strtod says ERANGE when a number such as 1e999 is beyond a double's range (it gives infinity), not
        // for "inf" written out.
        if (std::isinf(*value) && errno == ERANGE)
          throw InputError(path, number, "vertex coordinate '" + shown(t[static_cast<std::size_t>(c + 1)]) +
                                             "' is beyond the range of double precision (about 1.8e308); scale the "
                                             "scene down");
        if (!std::isfinite(*value))
          throw InputError(path, number, "vertex coordinate '" + shown(t[static_cast<std::size_t>(c + 1)]) +
                                             "' is not finite (NaN or infinity); replace it with a finite number");
        p[c] = *value;
      }
      text.positions.push_back(p);
    } else if (key == "vt") {
      ++texture_coordinates;
    } else if (key == "vn") {
      ++normals;
    } else if (key == "f") {
      for (std::size_t i = 1; i < t.size(); ++i) {
        if (!vertex_reference(t[i]))
          throw InputError(path, number, "face vertex '" + shown(t[i]) + "' is not a vertex reference; write v, "
                                         "v/vt, v//vn or v/vt/vn with whole numbers other than 0 (indices count from 1, "
                                         "negative ones from the end)");
        // Its vt and vn parts, when given, against the texture coordinates and normals read so far.
        const auto first_slash = t[i].find('/');
        if (first_slash != std::string::npos) {
          const auto second_slash = t[i].find('/', first_slash + 1);
          const std::string vt = t[i].substr(first_slash + 1, second_slash == std::string::npos
                                                                  ? std::string::npos
                                                                  : second_slash - first_slash - 1);
          const std::string vn = second_slash == std::string::npos ? std::string() : t[i].substr(second_slash + 1);
          const auto in_range = [](const std::string& part, long long count) {
            if (part.empty()) return true;
            const long long k = std::strtoll(part.c_str(), nullptr, 10);
            return (k >= 1 && k <= count) || (k <= -1 && -k <= count);
          };
          if (!in_range(vt, texture_coordinates) || !in_range(vn, normals)) {
            if (bad_references++ == 0) first_bad_reference = number;
          }
        }
        // tinyobjloader reads indices as int: a larger one would wrap around to some other vertex.
        errno = 0;
        const long long index = std::strtoll(t[i].c_str(), nullptr, 10);
        if (errno == ERANGE || index > std::numeric_limits<int>::max() || index < -std::numeric_limits<int>::max())
          throw InputError(path, number, "vertex index '" + shown(t[i].substr(0, t[i].find('/'))) +
                                         "' is out of range (the file defines " + std::to_string(text.positions.size()) + " vertices "
                                         "before this line); fix the face's vertex references");
      }
      if (t.size() < 4) {
        warnings.push_back(InputError::format(path, number, "face with fewer than three vertices skipped; give it "
                                                            "at least three vertices or remove it"));
        if (text.short_faces++ == 0) {
          text.first_short_line = number;
          text.first_short_warning = warnings.back();
        }
      } else {
        text.face_lines.push_back(number);
        text.face_sizes.push_back(t.size() - 1);
      }
    } else if (key == "s") {
      // `s N` (a whole number; 0 is off) or `s off`.
      const bool off = t.size() == 2 && t[1] == "off";
      const bool group = t.size() == 2 && t[1].size() <= 9 &&
                         std::all_of(t[1].begin(), t[1].end(), [](char c) { return c >= '0' && c <= '9'; });
      if (!off && !group)
        warnings.push_back(InputError::format(path, number, "smoothing statement '" + shown(trim(line)) + "' not "
                                                            "understood; write 's N' with a whole number N below "
                                                            "1e9, or 's off'"));
    } else if (key == "mtllib") {
      // The specification separates libraries by blanks, but Blender's exporter (2.79; tinyobjloader issue 355)
      // writes a file name with spaces as it is, "mtllib my scene.mtl": when the words are not all files in the
      // OBJ's folder and the rest of the line is one, the line names that file.
      const fs::path folder = fs::path(path).parent_path();
      const auto is_file = [&folder](const std::string& name) {
        std::error_code error;
        return fs::is_regular_file(folder / name, error);
      };
      const std::string rest = trim(line.substr(line.find("mtllib") + 6));
      if (t.size() > 2 && !std::all_of(t.begin() + 1, t.end(), is_file) && is_file(rest)) {
        text.material_libraries.emplace_back(number, rest);
      } else {
        for (std::size_t i = 1; i < t.size(); ++i) text.material_libraries.emplace_back(number, t[i]);
      }
    } else if (key == "usemtl") {
      text.material_uses.emplace_back(number, t.size() > 1 ? t[1] : std::string());
      if (t.size() > 2)
        warnings.push_back(InputError::format(path, number, "material name with a space: OBJ readers take only its "
                                                            "first word, '" + shown(t[1]) + "'; write the name without "
                                                            "spaces here and in the MTL file"));
    } else if (key == "#" && t.size() > 2 && t[1] == "aarad" && t[2] == "camera:") {
      std::string problem;
      text.camera = parse_camera_comment(std::vector<std::string>(t.begin() + 3, t.end()), problem);
      if (!text.camera)
        warnings.push_back(InputError::format(path, number, "camera comment not understood (" + problem + "), "
                                                            "ignored; write '# aarad "
                                                            "camera: eye X Y Z forward X Y Z up X Y Z vertical_fov RADIANS'"));
    } else if (key == "#" && t.size() > 2 && t[1] == "aarad" && t[2] == "meshing:") {
      std::string problem;
      text.meshing = parse_meshing_comment(std::vector<std::string>(t.begin() + 3, t.end()), problem);
      if (text.meshing) text.meshing->source_line = number;
      if (!text.meshing)
        warnings.push_back(InputError::format(path, number, "meshing comment not understood (" + problem + "), "
                                                            "ignored; write '# aarad "
                                                            "meshing: patch_size P element_size E min_area A' (any "
                                                            "of them, in any order) with numbers >= 0 (0 or left "
                                                            "out: from the scene's size)"));
    }
  }
  if (bad_references > 0)
    warnings.push_back(InputError::format(
        path, first_bad_reference,
        "a face refers to a texture coordinate or normal the file has not defined (" +
            std::to_string(bad_references) + (bad_references == 1 ? " reference" : " references") +
            " in all, this line first); aarad uses neither and reads the faces' vertices, but the file looks damaged"));
  // In the order of their first lines, as a reader goes through the file.
  std::vector<std::pair<std::string, std::pair<int, int>>> by_line(unknown.begin(), unknown.end());
  std::sort(by_line.begin(), by_line.end(), [](const auto& a, const auto& b) { return a.second.first < b.second.first; });
  for (const auto& [key, where] : by_line) {
    warnings.push_back(InputError::format(
        path, where.first, "'" + key + "' is not an OBJ statement; " +
                               (where.second == 1 ? std::string("this line is")
                                                  : "this line and " + std::to_string(where.second - 1) + " more are") +
                               " ignored (a typo, or a file that is not OBJ?)"));
  }
  return text;
}

// A material as the MTL text states it, with the lines of its statements.
struct MtlEntry {
  std::string file;
  int line = 0;  // of `newmtl`
  std::optional<Rgb> kd;
  int kd_line = 0;
  std::optional<Rgb> ke;
  int ke_line = 0;
};

Rgb parse_colour(const std::string& path, int line, const std::vector<std::string>& t,
                 std::vector<std::string>& warnings) {
  // "Kd r g b" or "Kd r" (grey), as the MTL format allows.
  std::vector<double> values;
  for (std::size_t i = 1; i < t.size() && values.size() < 3; ++i) {
    const auto v = parse_number(t[i]);
    if (!v) throw InputError(path, line, "'" + t[0] + "' needs one or three numbers, got '" + shown(t[i]) + "'; write e.g. '" + t[0] + " 0.5 0.5 0.5'");
    values.push_back(*v);
  }
  if (values.size() == 3 && t.size() > 4)
    warnings.push_back(InputError::format(path, line, "'" + t[0] + "' takes one or three numbers; the " +
                                                          std::to_string(t.size() - 4) + " after the third ('" + shown(t[4]) +
                                                          "' first) are ignored"));
  if (values.size() == 1) return Rgb(values[0]);
  if (values.size() == 3) return Rgb(values[0], values[1], values[2]);
  throw InputError(path, line, "'" + t[0] + "' needs one or three numbers; write e.g. '" + t[0] + " 0.5 0.5 0.5'");
}

void read_mtl_text(const std::string& path, std::map<std::string, MtlEntry>& entries,
                   std::vector<std::string>& warnings) {
  std::ifstream file(path);
  std::istringstream in(clean_text(file, path));
  std::string line;
  int number = 0;
  MtlEntry* current = nullptr;
  bool defines = false;       // a `newmtl` line seen
  std::size_t statements = 0;  // lines that are not blank or comments
  while (std::getline(in, line)) {
    ++number;
    const std::vector<std::string> t = split_tokens(line);
    if (t.empty() || t[0].starts_with('#')) continue;
    ++statements;
    if (!defines && t[0] != "newmtl" && (t[0] == "Kd" || t[0] == "Ke")) {
      // A colour before the first material belongs to none (a `newmtl` line lost or misspelt).
      warnings.push_back(InputError::format(path, number, "'" + t[0] + "' before the first 'newmtl' belongs to no "
                                                          "material and is ignored; start the material with "
                                                          "'newmtl NAME' above it"));
    }
    if (t[0] == "newmtl") {
      defines = true;
      // The rest of the line, as tinyobjloader names it. `usemtl` takes one word (read_obj_text warns of more), so a
      // name of several words can be defined but never used: said here, where it is defined.
      const std::string name = trim(line.substr(line.find("newmtl") + 6));
      if (split_tokens(name).size() > 1)
        warnings.push_back(InputError::format(path, number, "material name '" + shown(name) + "' has blanks in it; "
                                                            "'usemtl' takes one word, so no face can use this "
                                                            "material. Write its name without blanks"));
      // The first definition of a name wins, as in tinyobjloader's material map.
      const auto [it, inserted] = entries.try_emplace(name);
      current = inserted ? &it->second : nullptr;
      if (current) {
        current->file = path;
        current->line = number;
      } else {
        warnings.push_back(InputError::format(path, number, "material '" + name + "' is defined again (first at " +
                                                                it->second.file + ":" + std::to_string(it->second.line) +
                                                                "); this definition is ignored. Rename one of them"));
      }
    } else if (current && t[0] == "Kd") {
      current->kd = parse_colour(path, number, t, warnings);
      current->kd_line = number;
    } else if (current && t[0] == "Ke") {
      current->ke = parse_colour(path, number, t, warnings);
      current->ke_line = number;
    }
  }
  // Text without one `newmtl` is not a material library (a wrong file named by `mtllib`, or a damaged one): said
  // here, where the cause is, besides the warnings of the materials it was meant to define.
  if (!defines && statements > 0)
    warnings.push_back(InputError::format(path, 0, "defines no material (no 'newmtl' line in " +
                                                       std::to_string(statements) + " statements); is it an MTL "
                                                       "file?"));
}

Material checked_material(const tinyobj::material_t& parsed, const MtlEntry* entry, const std::string& obj_path,
                          std::vector<std::string>& warnings) {
  Material m;
  m.name = printable(parsed.name);
  const std::string file = entry ? entry->file : obj_path;
  if (entry && entry->kd) {
    m.reflectance = *entry->kd;
  } else {
    m.reflectance = Rgb(0.5);
    warnings.push_back(InputError::format(file, entry ? entry->line : 0,
                                          "material '" + m.name + "' has no Kd; using reflectance 0.5 grey. Add 'Kd r g b' "
                                          "with values in [0, 1)"));
  }
  if (entry && entry->ke) m.emission = *entry->ke;
  const int kd_line = entry ? entry->kd_line : 0;
  const int ke_line = entry ? entry->ke_line : 0;
  for (int c = 0; c < 3; ++c) {
    if (!(m.reflectance[c] >= 0.0 && m.reflectance[c] < 1.0))
      throw InputError(file, kd_line,
                       "material '" + m.name + "': Kd " + rgb_text(m.reflectance) +
                           " is outside [0, 1): the solution would not converge. Kd is the reflectance per channel; "
                           "use values from 0 up to below 1 (e.g. 0.8)");
    if (!(m.emission[c] >= 0.0) || !std::isfinite(m.emission[c]))
      throw InputError(file, ke_line,
                       "material '" + m.name + "': Ke " + rgb_text(m.emission) +
                           " must be finite and >= 0 per channel. Ke is the emitted radiosity; use 0 for a surface "
                           "that does not emit");
    if (m.reflectance[c] > 0.0 && m.reflectance[c] < kMinReflectance)
      throw InputError(file, kd_line,
                       "material '" + m.name + "': Kd " + rgb_text(m.reflectance) +
                           " is below 1e-100 in a channel but not 0: doubles lose the digits of what it reflects. "
                           "Use 0 for a channel that reflects nothing");
    if (m.emission[c] > 0.0 && m.emission[c] < kMinEmission)
      throw InputError(file, ke_line,
                       "material '" + m.name + "': Ke " + rgb_text(m.emission) +
                           " is below 1e-100 in a channel but not 0: doubles lose the digits of the light it sends "
                           "round the scene. Radiosity is linear in the emission, so scale Ke up and the results "
                           "back down, or use 0 for a channel that emits nothing");
    if (m.emission[c] > kMaxEmission)
      throw InputError(file, ke_line,
                       "material '" + m.name + "': Ke " + rgb_text(m.emission) +
                           " is too large: the solver's sums of flux would overflow. Use at most 1e100 per channel; "
                           "radiosity is linear in the emission, so scale Ke down and the results back up");
  }
  return m;
}

// Checks one face (check_face, shared with Scene::validate) and returns its vertices (without repeated ones), or
// none when it is skipped. Whether it is planar is decided once the scene's size is known (planar_pieces).
std::vector<Vec3> checked_face(const std::vector<Vec3>& face, const std::string& path, int line,
                               std::vector<std::string>& warnings, double& deviation) {
  FaceCheck check = check_face(face);
  const auto skip = [&](const std::string& what) {
    warnings.push_back(InputError::format(path, line, what));
    return std::vector<Vec3>{};
  };
  switch (check.problem) {
    case FaceProblem::kNone:
      break;
    case FaceProblem::kFewerThanThreeDistinct:
      return skip("face with fewer than three distinct vertices skipped; fix its vertex indices or remove it");
    case FaceProblem::kTooLarge:
      return skip("face too large for double precision (a coordinate beyond 1e50, where the solver's products of "
                  "lengths overflow) skipped; scale the scene down");
    case FaceProblem::kTooSmall:
      return skip("face too small for double precision (its size " + number_text(check.size) + " is below 1e-50, "
                  "where the solver's products of lengths underflow) skipped; scale the scene up");
    case FaceProblem::kCollinear:
      return skip("face of zero area or too thin to resolve skipped: its vertices lie on one line to within 1e-12 of "
                  "its size (" + number_text(check.size) + "); remove it or fix its vertices");
    case FaceProblem::kSelfIntersecting:
      throw InputError(path, line, "face intersects itself (two of its edges cross or touch); list its vertices in "
                                   "order around its boundary, or split it into simple polygons");
    case FaceProblem::kZeroArea:
      return skip("face of zero area skipped: its boundary encloses less than 1e-12 of its size squared; remove it or "
                  "fix its vertices");
  }
  deviation = check.deviation;
  return std::move(check.vertices);
}

// A face is planar when its vertices lie within `weld` of its plane: the distance within which the scene takes
// faces for one plane (Scene::build_surfaces) and the meshing moves points onto their surface's plane, kPlaneDistance
// of the scene's diagonal. A tolerance of the face's own size split faces that only the file's rounding bent: a
// generated room (not in the repository) turned off the axes and written with 6 significant digits had quads 2.2e-6
// off their planes, 1.9e-6 of their size, in a scene 6.4 across; its lamp, cut in two triangles, was meshed along
// their diagonal, and the ceiling 0.01 above it split into 8 763 leaves where the planar lamp left 732 (test
// SceneImport.import_face_bent_by_the_files_rounding_is_kept_whole). A face bent more is split into triangles by ear
// clipping its projection, with a warning.
std::vector<std::vector<Vec3>> planar_pieces(std::vector<Vec3> face, double deviation, double weld,
                                             const std::string& path, int line, std::vector<std::string>& warnings) {
  if (deviation <= weld) return {std::move(face)};
  const FaceCheck check = check_face(face);  // the projection, counter-clockwise about the Newell normal
  std::vector<std::array<std::size_t, 3>> triangles;
  ear_clip(check.flat, triangles);
  std::vector<std::vector<Vec3>> out;
  const std::vector<Vec3>& v = check.vertices;
  for (const auto& t : triangles) {
    std::vector<Vec3> tri{v[t[0]], v[t[1]], v[t[2]]};
    if (2.0 * area(tri) > kZeroAreaFraction * check.size * check.size) out.push_back(std::move(tri));
  }
  warnings.push_back(InputError::format(
      path, line, "face is not planar (a vertex lies " + number_text(check.deviation) + " from its plane, more than " +
                      number_text(kPlaneDistance) + " of the scene's diagonal, " + number_text(weld) +
                      "); split into " + std::to_string(out.size()) +
                      " triangles. Make the face planar or split it yourself to silence this"));
  return out;
}

// Faces laid on one another in one plane (a rug on a floor, a face copied into a second group): both are lit
// there and both count the area, where in the real scene one hides the other. Which one the hemicubes show is not
// named: the surface made first where their depth keys are equal (formfactor/coverage_list.h, "Equal keys"), but
// where the planes differ by a rounding (a turned room), either, pixel by pixel.
void warn_about_overlaps(const Scene& scene, const std::string& path, std::vector<std::string>& warnings) {
  constexpr std::size_t kMostWarnings = 10;
  // n copies of one face overlap in n (n - 1) / 2 pairs: 16 000 of them, a 300 KB file, took 8 GB and a minute to
  // list in full. A million pairs is more than anyone reads, and takes at most some 50 MB.
  constexpr std::size_t kMostPairs = 1'000'000;
  bool complete = true;
  const std::vector<Scene::CoplanarOverlap> overlaps = scene.coplanar_overlaps(kMostPairs, &complete);
  const auto name = [&](std::uint32_t surface) {
    const Surface& s = scene.surfaces[surface];
    return "'" + scene.groups[s.group].name + "' (material '" + scene.materials[s.material].name + "')";
  };
  for (std::size_t k = 0; k < overlaps.size() && k < kMostWarnings; ++k) {
    const Scene::CoplanarOverlap& o = overlaps[k];
    const std::string amount = "an area of " + number_text(o.area);
    const std::string lines = "lines " + std::to_string(o.line_a) + " and " + std::to_string(o.line_b);
    if (o.a == o.b) {
      warnings.push_back(InputError::format(
          path, o.line_a, "faces of " + name(o.a) + " overlap each other over " + amount + " (" + lines +
                              " overlap most): that area is lit and counted twice; remove the overlap"));
    } else {
      warnings.push_back(InputError::format(
          path, o.line_a, name(o.a) + " and " + name(o.b) + " lie on one another in one plane over " + amount +
                              " (" + lines + " overlap most): both are lit there and both count that area, where "
                              "one would hide the other; cut one out of the other, or move one off the plane"));
    }
  }
  std::string more;
  if (overlaps.size() > kMostWarnings)
    more = std::to_string(overlaps.size() - kMostWarnings) + " more pairs of surfaces overlap in one plane";
  if (complete && !more.empty()) warnings.push_back(InputError::format(path, 0, more));
  if (!complete) {
    warnings.push_back(InputError::format(
        path, 0, (more.empty() ? "" : "at least " + more + "; ") +
                     "the search for faces that overlap stopped after a million pairs, so more may overlap, and over "
                     "more area than said"));
  }
}

}  // namespace

Scene import_obj(const std::string& obj_path) {
  std::error_code ec;
  const fs::file_status status = fs::status(obj_path, ec);
  // "box.obj/" names a folder inside a file: not a directory, which is not "no such file".
  if (ec && ec != std::errc::no_such_file_or_directory)
    throw InputError(obj_path, 0, "cannot reach the file (" + ec.message() + "); check the path");
  if (!fs::exists(status))
    throw InputError(obj_path, 0, "no such file; check the path (built-in scenes are named without a path: cornell, "
                                  "office, furnace)");
  if (!fs::is_regular_file(obj_path, ec)) throw InputError(obj_path, 0, "not a regular file; give the path of an OBJ file");
  std::ifstream obj_file(obj_path);
  if (!obj_file)
    throw InputError(obj_path, 0, std::string("cannot read the file (") + std::strerror(errno) + "); check its permissions");
  Scene scene;
  scene.name = obj_path;
  std::vector<std::string>& warnings = scene.warnings;
  // The text is held once, and copies of it (a stream copies its string) only while they are read: for a
  // million-face file each was 42 MB, and four of them stayed until the end of the import.
  std::string cleaned = with_unnamed_groups_named(clean_text(obj_file, obj_path), obj_path, warnings);
  const ObjText text = [&] {
    std::istringstream in(cleaned);
    return read_obj_text(obj_path, in, warnings);
  }();

  // The MTL libraries, read the same way tinyobjloader finds them: relative to the OBJ's folder.
  const fs::path folder = fs::path(obj_path).parent_path();
  std::map<std::string, MtlEntry> mtl_entries;
  std::vector<fs::path> libraries_read;
  std::string library_statements;  // one `mtllib` per library, for tinyobjloader (below)
  for (const auto& [line, file] : text.material_libraries) {
    const fs::path mtl = folder / file;
    if (std::find(libraries_read.begin(), libraries_read.end(), mtl) != libraries_read.end()) continue;
    libraries_read.push_back(mtl);
    // tinyobjloader splits the line at spaces, a backslash keeping the character after it.
    library_statements += "mtllib ";
    for (const char c : file) {
      if (c == ' ' || c == '\\') library_statements += '\\';
      library_statements += c;
    }
    library_statements += '\n';
    errno = 0;
    const bool regular = fs::is_regular_file(mtl, ec);
    const bool readable = regular && std::ifstream(mtl);
    const int reason = errno;
    if (readable) {
      read_mtl_text(mtl.string(), mtl_entries, warnings);
      continue;
    }
    // Said as the OBJ's own errors say it: a folder or an unreadable file is not "not found".
    const std::string problem = regular                ? std::string("cannot be read (") +
                                                             (reason != 0 ? std::strerror(reason) : "unreadable") + ")"
                                : fs::exists(mtl, ec) ? "is not a regular file"
                                                      : "not found";
    warnings.push_back(InputError::format(obj_path, line, "material library '" + mtl.string() + "' " + problem +
                                                              "; using the default material (reflectance 0.5 grey, no "
                                                              "emission). Put the MTL file there or fix the mtllib "
                                                              "line"));
  }
  for (const auto& [line, name] : text.material_uses)
    if (!mtl_entries.contains(name))
      warnings.push_back(InputError::format(obj_path, line, "material '" + name + "' is not defined in any MTL file; "
                                                            "using the default material (reflectance 0.5 grey, no "
                                                            "emission). Define it with newmtl or fix the usemtl line"));

  tinyobj::attrib_t attrib;
  std::vector<tinyobj::shape_t> shapes;
  std::vector<tinyobj::material_t> parsed_materials;
  std::string tiny_warnings, tiny_errors;
  // tinyobjloader looks a `usemtl` name up among the libraries read so far, and of an `mtllib` naming several files
  // reads only the first it can: faces after `usemtl lamp` but before the `mtllib` that defines it, or of a
  // material in a second library on one line, got the default material without a word, since the check above
  // finds the name defined. It gets every library, each on a line of its own, before the first statement, and the
  // file's own `mtllib` lines are left out (the faces are matched to their lines by order, not by tinyobjloader's
  // line numbers). So is every statement aarad does not read (points and lines, `p` and `l`; vertex weights, `vw`;
  // tags, `t`; free-form geometry): tinyobjloader refused a bad one ("p 0", "vw 1 -1 0.5") with a message naming a
  // line shifted by the libraries above, where read_obj_text has warned that it is passed over.
  static const std::set<std::string> kParsed{"v", "vt", "vn", "f", "o", "g", "s", "usemtl"};
  std::string parsed_text = library_statements;
  parsed_text.reserve(library_statements.size() + cleaned.size());
  {
    std::istringstream lines(std::move(cleaned));  // its last use
    std::string line;
    while (std::getline(lines, line)) {
      const std::vector<std::string> t = split_tokens(line);
      if (!t.empty() && kParsed.contains(t[0])) parsed_text += line;
      parsed_text += '\n';
    }
  }
  bool ok = false;
  {
    std::istringstream obj_text(std::move(parsed_text));
    CleanMaterialReader material_reader(folder.empty() ? fs::path(".") : folder);
    ok = tinyobj::LoadObj(&attrib, &shapes, &parsed_materials, &tiny_warnings, &tiny_errors, &obj_text,
                          &material_reader, /*triangulate=*/false);
  }
  if (!ok) throw InputError(obj_path, 0, "cannot parse the OBJ file: " + trim(tiny_errors));

  // Materials, checked against the MTL text (which knows the lines).
  // tinyobjloader also hands back a material without a name for an MTL file with no newmtl line (empty, or not an
  // MTL file at all): it defines nothing, and a face that names no material gets the default one.
  constexpr std::uint32_t kNoMaterial = std::numeric_limits<std::uint32_t>::max();
  // A name defined again is one material, the first definition's (read_mtl_text warns of the others): the others
  // were listed among the scene's materials with the first one's values, though no face can use them.
  std::vector<std::uint32_t> material_index(parsed_materials.size(), kNoMaterial);
  std::map<std::string, std::uint32_t> material_by_name;
  for (std::size_t i = 0; i < parsed_materials.size(); ++i) {
    const auto found = mtl_entries.find(parsed_materials[i].name);
    const MtlEntry* entry = found != mtl_entries.end() ? &found->second : nullptr;
    if (parsed_materials[i].name.empty() && entry == nullptr) continue;
    const auto [named, first] = material_by_name.try_emplace(parsed_materials[i].name);
    if (first) named->second = scene.add_material(checked_material(parsed_materials[i], entry, obj_path, warnings));
    material_index[i] = named->second;
  }
  std::optional<std::uint32_t> default_material;

  // Faces in file order; the k-th face is on the k-th `f` line with three or more vertex references.
  std::size_t face_count = 0;
  for (const auto& shape : shapes) face_count += shape.mesh.num_face_vertices.size();
  const bool lines_known = face_count == text.face_lines.size();
  const std::size_t vertex_count = attrib.vertices.size() / 3;
  const bool positions_known = text.positions.size() == vertex_count;
  const std::string stem = fs::path(obj_path).stem().string();
  // A shape's group: its name, with a control character (an escape sequence) shown as \xNN wherever it is printed,
  // or the file's stem for faces before any `o` or `g`.
  const auto group_name_of = [&stem](const tinyobj::shape_t& shape) {
    const std::string name = printable(trim(shape.name));
    return !name.empty() ? name : stem.empty() ? std::string("default") : stem;
  };
  // tinyobjloader keeps a face's vertex count in an unsigned char (mesh_t::num_face_vertices): a face of 256
  // or more vertices comes back with its count modulo 256, though all its vertex indices are there. The count
  // on the face's line is the true one; without the lines (never seen), such a face cannot be read.
  if (!lines_known)
    for (std::size_t k = 0; k < text.face_sizes.size(); ++k)
      if (text.face_sizes[k] > std::numeric_limits<unsigned char>::max())
        throw InputError(obj_path, text.face_lines[k], "face with " + std::to_string(text.face_sizes[k]) +
                                                           " vertices, more than the 255 the OBJ parser counts; "
                                                           "split it into faces of at most 255 vertices");

  // A face may be written twice (a copy-paste, an exporter's double): its area would count twice, and a lamp's
  // emitted flux too, while the mesh covers it once. Repeats in one group with one material (the same vertex
  // cycle, the same way round; the reverse is the back side of a two-sided panel) are skipped with a warning.
  // The same polygon in another group or material is another object and stays.
  // A kept face is found again by a hash of (its group's number, its material, its vertex cycle from its
  // lexicographically smallest vertex) into `kept`: a std::map keyed by a copy of the group's name and of the
  // coordinates took about 200 bytes per face, and its string and vector comparisons a second per million faces.
  std::map<std::string, std::uint32_t> group_numbers;  // by group name, in order of first use

  // Faces skipped, those of fewer than three vertices (found by the line-by-line read) among them, and the warning
  // of the one on the earliest line (line 0 when the lines are not known), for an error if none is left.
  std::size_t face_number = 0, skipped_faces = text.short_faces;
  std::string first_skip = text.first_short_warning;
  int first_skip_line = text.first_short_line;
  const auto note_skip = [&](int line) {
    if (skipped_faces++ == 0 || (line > 0 && line < first_skip_line)) {
      first_skip = warnings.back();
      first_skip_line = line;
    }
  };
  bool unassigned_faces = false;
  // The faces to add, once the scene's size is known (below).
  struct Kept {
    std::size_t shape;
    std::uint32_t group_number;
    std::uint32_t material;
    std::vector<Vec3> polygon;
    int line;
    std::uint32_t smoothing;
    double deviation;  // of its vertices from its plane (FaceCheck)
  };
  std::vector<Kept> kept;
  const auto first_corner = [](const std::vector<Vec3>& polygon) {
    const auto before = [](const Vec3& a, const Vec3& b) { return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z); };
    return static_cast<std::size_t>(std::min_element(polygon.begin(), polygon.end(), before) - polygon.begin());
  };
  const auto same_face = [&kept, &first_corner](std::size_t i, std::size_t j) {
    const Kept& a = kept[i];
    const Kept& b = kept[j];
    if (a.group_number != b.group_number || a.material != b.material || a.polygon.size() != b.polygon.size())
      return false;
    const std::size_t n = a.polygon.size(), from_a = first_corner(a.polygon), from_b = first_corner(b.polygon);
    for (std::size_t k = 0; k < n; ++k) {
      const Vec3& p = a.polygon[(from_a + k) % n];
      const Vec3& q = b.polygon[(from_b + k) % n];
      if (!(p.x == q.x && p.y == q.y && p.z == q.z)) return false;
    }
    return true;
  };
  const auto face_hash = [&kept, &first_corner](std::size_t i) {
    const Kept& a = kept[i];
    std::uint64_t h = (std::uint64_t{a.group_number} << 32) ^ a.material;
    const auto mix = [&h](std::uint64_t v) { h = (h ^ v) * 0x100000001b3ULL + (h >> 29); };
    const std::size_t n = a.polygon.size(), from = first_corner(a.polygon);
    for (std::size_t k = 0; k < n; ++k) {
      const Vec3& p = a.polygon[(from + k) % n];
      // + 0.0 makes -0.0 the 0.0 it equals.
      for (const double c : {p.x + 0.0, p.y + 0.0, p.z + 0.0}) mix(std::bit_cast<std::uint64_t>(c));
    }
    return static_cast<std::size_t>(h);
  };
  std::unordered_set<std::size_t, decltype(face_hash), decltype(same_face)> kept_faces(0, face_hash, same_face);
  for (std::size_t shape_index = 0; shape_index < shapes.size(); ++shape_index) {
    const auto& shape = shapes[shape_index];
    const std::string group_name = group_name_of(shape);
    const std::uint32_t group_number =
        group_numbers.try_emplace(group_name, static_cast<std::uint32_t>(group_numbers.size())).first->second;
    std::size_t offset = 0;
    for (std::size_t f = 0; f < shape.mesh.num_face_vertices.size(); ++f, ++face_number) {
      const int line = lines_known ? text.face_lines[face_number] : 0;
      const std::size_t parsed_count = shape.mesh.num_face_vertices[f];
      const std::size_t count = lines_known ? text.face_sizes[face_number] : parsed_count;
      if (count % 256 != parsed_count || offset + count > shape.mesh.indices.size())
        throw InputError(obj_path, line, "the OBJ parser read " + std::to_string(parsed_count) + " of this face's " +
                                             std::to_string(count) + " vertices; split it into faces of at most 255 "
                                             "vertices");
      std::vector<Vec3> vertices;
      for (std::size_t k = 0; k < count; ++k) {
        const int index = shape.mesh.indices[offset + k].vertex_index;
        if (index < 0 || static_cast<std::size_t>(index) >= vertex_count)
          throw InputError(obj_path, line, "vertex index out of range (the file defines " + std::to_string(vertex_count) +
                                               " vertices); fix the face's vertex references");
        const auto i = static_cast<std::size_t>(index);
        vertices.push_back(positions_known ? text.positions[i]
                                           : Vec3(attrib.vertices[3 * i], attrib.vertices[3 * i + 1], attrib.vertices[3 * i + 2]));
      }
      offset += count;

      double deviation = 0.0;
      std::vector<Vec3> polygon = checked_face(vertices, obj_path, line, warnings, deviation);
      if (polygon.empty()) {
        note_skip(line);
        continue;
      }
      const int parsed_material = f < shape.mesh.material_ids.size() ? shape.mesh.material_ids[f] : -1;
      const std::uint32_t smoothing = f < shape.mesh.smoothing_group_ids.size() ? shape.mesh.smoothing_group_ids[f] : 0;
      std::uint32_t material;
      if (parsed_material >= 0 && static_cast<std::size_t>(parsed_material) < material_index.size() &&
          material_index[static_cast<std::size_t>(parsed_material)] != kNoMaterial) {
        material = material_index[static_cast<std::size_t>(parsed_material)];
      } else {
        if (!default_material) default_material = scene.add_material(Material{"default", Rgb(0.5), Rgb(0.0)});
        material = *default_material;
        unassigned_faces = true;
      }
      kept.push_back({shape_index, group_number, material, std::move(polygon), line, smoothing, deviation});
      const auto [first, inserted] = kept_faces.insert(kept.size() - 1);
      if (!inserted) {
        kept.pop_back();
        warnings.push_back(InputError::format(obj_path, line, "face repeats the face on line " +
                                                                  std::to_string(kept[*first].line) +
                                                                  " (the same vertices, the same way round, group "
                                                                  "and material); skipped, so its area and light "
                                                                  "count once"));
      }
    }
  }
  // What only the loop above read goes: the repeat check's index and tinyobjloader's copy of the faces.
  kept_faces.clear();
  kept_faces.rehash(0);
  attrib = tinyobj::attrib_t{};
  for (tinyobj::shape_t& shape : shapes) shape.mesh = tinyobj::mesh_t{};
  // A face whose points all lie within kSmallestFace of the scene's diagonal of one another is below what the
  // meshing resolves: it welds vertices closer than kPlaneDistance of the diagonal (rounding errors of the file), so
  // such a face would collapse there, and CGAL's mesher crashed on what was left of it (a face 1 across in a scene
  // 1e6 across). It is skipped with a warning. Leaving it out can only make the scene smaller, and the faces kept
  // larger against it.
  Vec3 low(std::numeric_limits<double>::infinity()), high(-std::numeric_limits<double>::infinity());
  for (const Kept& k : kept)
    for (const Vec3& p : k.polygon) {
      low = glm::min(low, p);
      high = glm::max(high, p);
    }
  const double smallest = kSmallestFace * glm::length(high - low);
  const double weld = kPlaneDistance * glm::length(high - low);  // the meshing's (scene.h)
  std::vector<std::optional<std::uint32_t>> groups(shapes.size());
  const auto add_piece = [&](const Kept& k, std::vector<Vec3> polygon) {
    const double size = box_diagonal(polygon);
    if (size < smallest) {
      warnings.push_back(InputError::format(
          obj_path, k.line, "face too small against the scene (its size " + number_text(size) + " is below " +
                                number_text(kSmallestFace) + " of the scene's diagonal, " +
                                number_text(smallest / kSmallestFace) + ", which the meshing does not resolve) skipped; "
                                "scale it up or give it a scene of its own"));
      note_skip(k.line);
      return;
    }
    // A face narrower everywhere than the meshing's weld distance (kPlaneDistance of the diagonal: a sliver, all
    // its vertices within that of one line) collapses there onto its own edges; a surface of only such faces was
    // refused by the Delaunay path, but a lone triangle went to the grid path, whose patches of a face 7e-11 wide
    // and 1.6 long had no plane to keep their corners on (children 6.7e-8 off their parents' planes) and elements
    // far below min_area. Its area (below kPlaneDistance x its length x the diagonal) is no light to speak of, so it
    // is skipped with a warning, as the faces too small are.
    const double width = width_across(polygon);
    if (width <= weld) {
      warnings.push_back(InputError::format(
          obj_path, k.line, "face too narrow against the scene (its width " + number_text(width) + " is below " +
                                number_text(kPlaneDistance) + " of the scene's diagonal, " + number_text(weld) +
                                ", which the meshing takes for a rounding error) skipped; make it wider or remove it"));
      note_skip(k.line);
      return;
    }
    std::optional<std::uint32_t>& group = groups[k.shape];
    if (!group) group = scene.add_group(group_name_of(shapes[k.shape]));
    scene.add_face(*group, k.material, std::move(polygon), k.line, k.smoothing);
  };
  for (Kept& k : kept) {
    // A face too small is skipped whole, without a word on its planarity.
    if (box_diagonal(k.polygon) < smallest) {
      add_piece(k, std::move(k.polygon));
      continue;
    }
    for (std::vector<Vec3>& piece : planar_pieces(std::move(k.polygon), k.deviation, weld, obj_path, k.line, warnings))
      add_piece(k, std::move(piece));
  }
  std::vector<Kept>().swap(kept);
  if (unassigned_faces && text.material_uses.empty() && text.material_libraries.empty())
    warnings.push_back(InputError::format(obj_path, 0, "faces without a material use the default (reflectance 0.5 "
                                                       "grey, no emission); add an MTL file with mtllib and usemtl"));

  if (scene.faces.empty() && skipped_faces > 0)  // the warnings would be lost with the error: name the first
    throw InputError(obj_path, 0, "no usable faces: all " + std::to_string(skipped_faces) + " faces were skipped; the first: " +
                                      first_skip);
  if (scene.faces.empty())
    throw InputError(obj_path, 0, "no usable faces; the file needs at least one polygon ('f' line)");
  scene.camera = text.camera;
  scene.meshing = text.meshing;
  scene.build_surfaces();
  warn_about_overlaps(scene, obj_path, warnings);
  bool emits = false;
  for (const Face& face : scene.faces) emits |= scene.materials[face.material].emits();
  if (!emits)
    warnings.push_back(InputError::format(obj_path, 0, "no face emits light, so the solution will be black; give a "
                                                       "material a positive Ke"));
  scene.validate();
  return scene;
}

}  // namespace aarad
