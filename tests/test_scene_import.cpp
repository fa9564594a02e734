// Tests of the OBJ/MTL importer (core/obj_import.h) and the scene model (core/scene.h): every bad input of
// issue 2 part 3 gives its error or warning, naming the file and line; groups and physical surfaces follow
// the scene contract of shared/design.md; data/scenes/cornell.obj imports to the built-in Cornell box.
#include "aarad/core/builtin_scenes.h"
#include "aarad/core/error.h"
#include "aarad/core/face_check.h"
#include "aarad/core/obj_export.h"
#include "aarad/core/obj_import.h"
#include "aarad/core/polygon.h"
#include "aarad/core/scene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <tuple>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <unistd.h>

namespace aarad {
namespace {

namespace fs = std::filesystem;

// A fresh folder per test under the system's temporary folder, removed afterwards.
class SceneImport : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("aarad_scene_import_" + std::to_string(::getpid()) + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string write(const std::string& name, const std::string& text) const {
    const fs::path path = dir_ / name;
    std::ofstream(path) << text;
    return path.string();
  }

  // Imports `# aarad KIND: WORDS` above one triangle: a comment that cannot be used, whose warning must name line 1
  // and say `why`. Returns the scene.
  Scene import_refused_comment(const std::string& kind, const std::string& words, const std::string& why) const {
    const Scene scene = import_obj(write(kind + ".obj", "# aarad " + kind + ": " + words + "\n"
                                                        "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n"));
    const std::string expected = kind + ".obj:1: " + kind + " comment not understood " + why + ", ignored";
    const auto said = std::find_if(scene.warnings.begin(), scene.warnings.end(),
                                   [&](const std::string& w) { return w.find(expected) != std::string::npos; });
    EXPECT_NE(said, scene.warnings.end()) << words << ": " << (scene.warnings.empty() ? "" : scene.warnings.front());
    return scene;
  }

  // The InputError that importing `path` throws (fails the test when there is none).
  static InputError import_error(const std::string& path) {
    try {
      import_obj(path);
    } catch (const InputError& e) {
      return e;
    }
    ADD_FAILURE() << "no InputError for " << path;
    return InputError(path, 0, "none");
  }

  static bool has_warning(const Scene& scene, const std::string& needle) {
    for (const std::string& w : scene.warnings)
      if (w.find(needle) != std::string::npos) return true;
    return false;
  }

  fs::path dir_;
};

// A unit square in z = 0 facing +z and a light above it, with a material library.
const char* kSquareMtl =
    "newmtl grey\n"
    "Kd 0.5 0.5 0.5\n"
    "newmtl lamp\n"
    "Kd 0.2 0.2 0.2\n"
    "Ke 4 4 4\n";

// ---- Files ---------------------------------------------------------------------------------------------

// write_obj and import_obj round trip: materials whose names are one after blanks become underscores ("red paint",
// "red_paint"), or are the same, are written under distinct names and each reads back as itself (the second
// used to be read as the first, lamp and all).
TEST_F(SceneImport, import_of_an_export_keeps_materials_whose_names_collide) {
  Scene scene;
  scene.name = "collide";
  const auto paint = scene.add_material({"red paint", Rgb(0.7, 0.1, 0.1), Rgb(0.0)});
  const auto lamp = scene.add_material({"red_paint", Rgb(0.1, 0.1, 0.7), Rgb(1.0)});
  const auto twin = scene.add_material({"red paint", Rgb(0.3, 0.3, 0.3), Rgb(0.0)});
  const auto floor = scene.add_group("floor");
  scene.add_face(floor, paint, {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}});
  scene.add_face(scene.add_group("light"), lamp, {{0, 0, 1}, {0, 1, 1}, {1, 1, 1}, {1, 0, 1}});
  scene.add_face(scene.add_group("wall"), twin, {{0, 0, 0}, {0, 1, 0}, {0, 1, 1}, {0, 0, 1}});
  scene.build_surfaces();
  scene.validate();
  const std::string path = (dir_ / "collide.obj").string();
  write_obj(scene, path);
  const Scene back = import_obj(path);
  EXPECT_TRUE(back.warnings.empty()) << back.warnings.front();
  ASSERT_EQ(back.faces.size(), scene.faces.size());
  for (std::size_t f = 0; f < scene.faces.size(); ++f) {
    const Material& written = scene.materials[scene.faces[f].material];
    const Material& read = back.materials[back.faces[f].material];
    EXPECT_EQ(read.reflectance, written.reflectance) << "face " << f << " (" << read.name << ")";
    EXPECT_EQ(read.emission, written.emission) << "face " << f << " (" << read.name << ")";
  }
}

TEST_F(SceneImport, import_missing_obj_is_error_naming_file) {
  const std::string path = (dir_ / "nowhere.obj").string();
  const InputError e = import_error(path);
  EXPECT_EQ(e.file(), path);
  EXPECT_EQ(e.line(), 0);
  EXPECT_NE(std::string(e.what()).find(path), std::string::npos);
  EXPECT_NE(e.message().find("no such file"), std::string::npos);
  // A path through a file ("box.obj/") is not a directory, which "no such file" did not say.
  const std::string through = write("box.obj", "v 0 0 0\n") + "/";
  const InputError not_folder = import_error(through);
  EXPECT_NE(not_folder.message().find("cannot reach the file (Not a directory)"), std::string::npos)
      << not_folder.message();
}

TEST_F(SceneImport, import_unreadable_obj_is_error_naming_file) {
  // A folder where a file is expected cannot be read as an OBJ.
  fs::create_directories(dir_ / "folder.obj");
  const InputError e = import_error((dir_ / "folder.obj").string());
  EXPECT_EQ(e.file(), (dir_ / "folder.obj").string());
  EXPECT_NE(e.message().find("not a regular file"), std::string::npos);
}

TEST_F(SceneImport, import_missing_mtl_warns_and_uses_default_material) {
  const std::string obj = write("a.obj",
                                "mtllib missing.mtl\n"
                                "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                "usemtl grey\n"
                                "f 1 2 3 4\n");
  const Scene scene = import_obj(obj);
  ASSERT_EQ(scene.faces.size(), 1u);
  const Material& m = scene.materials[scene.faces[0].material];
  EXPECT_EQ(m.reflectance, Rgb(0.5));
  EXPECT_EQ(m.emission, Rgb(0.0));
  EXPECT_TRUE(has_warning(scene, obj + ":1: material library"));
  EXPECT_TRUE(has_warning(scene, "missing.mtl"));
  EXPECT_TRUE(has_warning(scene, obj + ":6: material 'grey' is not defined"));
  EXPECT_TRUE(has_warning(scene, "no face emits light"));
}

// A material library that is there but cannot be read says so: it was "not found" too, and a folder named as one
// was an internal error ("basic_filebuf::underflow error reading the file: Is a directory", exit code 3).
TEST_F(SceneImport, import_mtl_that_is_a_folder_or_unreadable_warns_with_what_is_wrong) {
  fs::create_directories(dir_ / "folder.mtl");
  write("locked.mtl", kSquareMtl);
  fs::permissions(dir_ / "locked.mtl", fs::perms::none);
  const std::string obj = write("a.obj",
                                "mtllib folder.mtl\nmtllib locked.mtl\n"
                                "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                "f 1 2 3 4\n");
  const Scene scene = import_obj(obj);
  EXPECT_TRUE(has_warning(scene, obj + ":1: material library '" + (dir_ / "folder.mtl").string() +
                                     "' is not a regular file; using the default material"));
  if (::geteuid() != 0) {  // root reads it anyway
    EXPECT_TRUE(has_warning(scene, obj + ":2: material library '" + (dir_ / "locked.mtl").string() +
                                       "' cannot be read (Permission denied); using the default material"));
  }
  EXPECT_FALSE(has_warning(scene, "not found"));
}

// A material is found whatever the order of `usemtl` and the `mtllib` that defines it, and in every library an
// `mtllib` line names. Both got the default material (no emission) without a warning: the importer's check found
// the name defined, but tinyobjloader looked it up only among the libraries read so far, and of a line naming
// several read only the first.
TEST_F(SceneImport, import_materials_are_found_in_every_library_whatever_the_order) {
  write("walls.mtl", "newmtl grey\nKd 0.5 0.5 0.5\n");
  write("lamps.mtl", "newmtl lamp\nKd 0.2 0.2 0.2\nKe 4 4 4\n");
  const std::string quads = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 2\nv 0 1 2\nv 1 1 2\nv 1 0 2\n";
  for (const std::string& obj :
       {write("later.obj", quads + "g light\nusemtl lamp\nf 5 6 7 8\nmtllib lamps.mtl walls.mtl\n"
                                   "g floor\nusemtl grey\nf 1 2 3 4\n"),
        write("second.obj", "mtllib walls.mtl lamps.mtl\n" + quads + "g floor\nusemtl grey\nf 1 2 3 4\n"
                                                                      "g light\nusemtl lamp\nf 5 6 7 8\n")}) {
    const Scene scene = import_obj(obj);
    EXPECT_TRUE(scene.warnings.empty()) << obj << ": " << scene.warnings.front();
    const Surface& light = scene.surfaces[scene.groups[*scene.find_group("light")].surfaces[0]];
    EXPECT_EQ(scene.materials[light.material].name, "lamp") << obj;
    EXPECT_EQ(scene.materials[light.material].emission, Rgb(4.0)) << obj;
    const Surface& floor = scene.surfaces[scene.groups[*scene.find_group("floor")].surfaces[0]];
    EXPECT_EQ(scene.materials[floor.material].name, "grey") << obj;
  }
}

// Blender (2.79's exporter, and others: tinyobjloader issue 355) names a library whose file name has spaces without
// escaping them, "mtllib my scene.mtl" for my scene.obj. Its words name no file, and the library was not read: the
// lamp got the default material, nothing emitted, and `aarad solve` refused the scene. The line names the one file
// its rest names, when that file is there and its words are not all files; a line of several libraries stays one.
TEST_F(SceneImport, import_library_name_with_spaces_as_blender_writes_it) {
  write("my scene.mtl", "newmtl lamp\nKd 0.2 0.2 0.2\nKe 4 4 4\n");
  const std::string quad = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\ng light\nusemtl lamp\nf 1 2 3 4\n";
  const Scene scene = import_obj(write("my scene.obj", "mtllib my scene.mtl\n" + quad));
  EXPECT_TRUE(scene.warnings.empty()) << scene.warnings.front();
  ASSERT_EQ(scene.surfaces.size(), 1u);
  EXPECT_EQ(scene.materials[scene.surfaces[0].material].emission, Rgb(4.0));
  // Two libraries whose names have no spaces are still two, and a name with spaces that is not there is not found.
  write("my.mtl", "newmtl grey\nKd 0.5 0.5 0.5\n");
  write("scene.mtl", "newmtl lamp\nKd 0.2 0.2 0.2\nKe 2 2 2\n");
  const Scene two = import_obj(write("two.obj", "mtllib my.mtl scene.mtl\n" + quad));
  EXPECT_TRUE(two.warnings.empty()) << two.warnings.front();
  EXPECT_EQ(two.materials[two.surfaces[0].material].emission, Rgb(2.0));
  const Scene missing = import_obj(write("missing.obj", "mtllib other scene.mtl\n" + quad));
  EXPECT_TRUE(has_warning(missing, "material library '" + (dir_ / "other").string() + "' not found"));
}

TEST_F(SceneImport, import_obj_without_materials_uses_default_with_warning) {
  const std::string obj = write("plain.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n");
  const Scene scene = import_obj(obj);
  ASSERT_EQ(scene.materials.size(), 1u);
  EXPECT_EQ(scene.materials[0].reflectance, Rgb(0.5));
  EXPECT_TRUE(has_warning(scene, "faces without a material use the default"));
}

TEST_F(SceneImport, import_material_without_kd_warns_and_uses_grey) {
  write("m.mtl", "newmtl bare\nKe 1 1 1\n");
  const std::string obj = write("m.obj", "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nusemtl bare\nf 1 2 3\n");
  const Scene scene = import_obj(obj);
  EXPECT_EQ(scene.materials[scene.faces[0].material].reflectance, Rgb(0.5));
  EXPECT_EQ(scene.materials[scene.faces[0].material].emission, Rgb(1.0));
  EXPECT_TRUE(has_warning(scene, "m.mtl:1: material 'bare' has no Kd"));
}

// A name after more than one blank ("newmtl  lamp", "newmtl \tlamp") is the name without them. tinyobjloader kept
// all blanks but one in it: `usemtl lamp` found no such material, and the lamp's face got the default one, its Ke
// lost and the scene black, with only "material ' lamp' has no Kd" said.
TEST_F(SceneImport, import_material_names_after_several_blanks_are_found) {
  write("m.mtl", "newmtl  grey\nKd 0.5 0.5 0.5\nnewmtl \tlamp\nKd 0.2 0.2 0.2\nKe 4 4 4\n");
  const std::string obj = write("m.obj", "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\n"
                                         "usemtl grey\nf 1 2 3\nusemtl lamp\nf 4 6 5\n");
  const Scene scene = import_obj(obj);
  EXPECT_TRUE(scene.warnings.empty()) << scene.warnings.front();
  ASSERT_EQ(scene.faces.size(), 2u);
  EXPECT_EQ(scene.materials[scene.faces[0].material].name, "grey");
  EXPECT_EQ(scene.materials[scene.faces[1].material].name, "lamp");
  EXPECT_EQ(scene.materials[scene.faces[1].material].reflectance, Rgb(0.2));
  EXPECT_EQ(scene.materials[scene.faces[1].material].emission, Rgb(4.0));
}

// A comment after `newmtl` ends the name, as it ends it after `usemtl`: "newmtl lamp   # the ceiling light" defined a
// material named by the whole line, the faces of "usemtl lamp" got the default material and the lamp's emission was
// lost, under a warning that 'lamp' was not defined. A name of several words is defined but can never be used:
// said where it is defined.
TEST_F(SceneImport, import_material_name_ends_at_a_comment_and_a_name_of_words_warns) {
  write("m.mtl", "newmtl grey # walls\nKd 0.5 0.5 0.5\nnewmtl lamp   # the ceiling light\nKd 0.2 0.2 0.2\n"
                 "Ke 4 4 4\nnewmtl red paint\nKd 0.7 0.1 0.1\n");
  const Scene scene = import_obj(write("m.obj", "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 0 1\nv 1 0 1\n"
                                                "v 1 1 1\nusemtl grey\nf 1 2 3\nusemtl lamp # on\nf 4 6 5\n"));
  ASSERT_EQ(scene.faces.size(), 2u);
  EXPECT_EQ(scene.materials[scene.faces[0].material].name, "grey");
  EXPECT_EQ(scene.materials[scene.faces[1].material].name, "lamp");
  EXPECT_EQ(scene.materials[scene.faces[1].material].emission, Rgb(4.0));
  ASSERT_EQ(scene.warnings.size(), 1u) << scene.warnings.front();
  EXPECT_NE(scene.warnings[0].find("m.mtl:6: material name 'red paint' has blanks in it"), std::string::npos)
      << scene.warnings[0];
}

// A colour before the first `newmtl` belongs to no material, and a file without a `newmtl` is no material library:
// both were passed over in silence (a misspelt "newmt lamp", an `mtllib` naming the wrong file).
TEST_F(SceneImport, import_warns_of_colours_before_any_material_and_of_a_library_that_defines_none) {
  write("first.mtl", "# materials\nKd 0.2 0.2 0.2\nnewmtl grey\nKd 0.5 0.5 0.5\n");
  write("junk.mtl", "x 1 2\n\x01\x02\x03\nnot a material\n");
  const Scene scene = import_obj(write("m.obj", "mtllib first.mtl junk.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\n"
                                                "usemtl grey\nf 1 2 3\n"));
  EXPECT_TRUE(has_warning(scene, "first.mtl:2: 'Kd' before the first 'newmtl' belongs to no material"));
  EXPECT_TRUE(has_warning(scene, "junk.mtl: defines no material (no 'newmtl' line in 3 statements)"));
  EXPECT_EQ(scene.materials[scene.faces[0].material].reflectance, Rgb(0.5));
}

// ---- Errors with lines ---------------------------------------------------------------------------------

TEST_F(SceneImport, import_nan_coordinate_is_error_with_line) {
  const std::string obj = write("nan.obj", "# a comment\nv 0 0 0\nv 1 nan 0\nv 1 1 0\nf 1 2 3\n");
  const InputError e = import_error(obj);
  EXPECT_EQ(e.file(), obj);
  EXPECT_EQ(e.line(), 3);
  EXPECT_NE(e.message().find("not finite"), std::string::npos);
  EXPECT_NE(std::string(e.what()).find(obj + ":3:"), std::string::npos);
}

TEST_F(SceneImport, import_infinite_coordinate_is_error_with_line) {
  EXPECT_EQ(import_error(write("inf.obj", "v 0 0 0\nv 1 0 0\nv 1 1 -inf\nf 1 2 3\n")).line(), 3);
  EXPECT_NE(import_error(write("inf.obj", "v 0 0 0\nv 1 0 0\nv 1 1 -inf\nf 1 2 3\n")).message().find(
                "vertex coordinate '-inf' is not finite (NaN or infinity)"),
            std::string::npos);
  // Too large for a double: strtod gives infinity, but the file has no infinity in it (the message said "not
  // finite (NaN or infinity)").
  const InputError big = import_error(write("big.obj", "v 0 0 0\nv 1e999 0 0\nv 1 1 0\nf 1 2 3\n"));
  EXPECT_EQ(big.line(), 2);
  EXPECT_EQ(big.message(), "vertex coordinate '1e999' is beyond the range of double precision (about 1.8e308); scale "
                           "the scene down");
  // A word too long to show whole is cut, with its length (ten million digits made a 10 MB message).
  const std::string digits(100000, '9');
  const InputError longer = import_error(write("long.obj", "v 0 0 0\nv 1 0 " + digits + "x\nv 1 1 0\nf 1 2 3\n"));
  EXPECT_EQ(longer.line(), 2);
  EXPECT_EQ(longer.message(), "vertex coordinate '" + digits.substr(0, 48) + "... (100001 bytes)' is not a "
                              "number; write a finite decimal number");
  // Cut between UTF-8 characters, never inside one: 47 ASCII bytes, then two-byte characters (e with an acute
  // accent), so that byte 48 is the second byte of one.
  std::string accents(47, 'x');
  for (int k = 0; k < 20; ++k) accents += "\xC3\xA9";
  const InputError accented = import_error(write("accents.obj", "v 0 0 0\nv 1 0 " + accents + "\nv 1 1 0\nf 1 2 3\n"));
  EXPECT_NE(accented.message().find("'" + accents.substr(0, 47) + "... (87 bytes)'"), std::string::npos)
      << accented.message();
}

// A NUL byte inside a number (a damaged file) ended the C string there: "1\0garbage" was read as 1. A text file
// holds none, so the byte is the error, with its line.
TEST_F(SceneImport, import_coordinate_with_a_nul_byte_is_error_with_line) {
  const char text[] = "v 0 0 0\nv 1\0garbage 0 0\nv 1 1 0\nf 1 2 3\n";
  const InputError e = import_error(write("nul.obj", std::string(text, sizeof text - 1)));
  EXPECT_EQ(e.line(), 2);
  EXPECT_NE(std::string(e.what()).find(":2: a NUL byte, which a text file does not hold"), std::string::npos)
      << e.what();
}

// A control character in a group's or a material's name (an escape sequence) is kept as \xNN text: printed raw,
// it acted on the terminal `aarad inspect` wrote to.
TEST_F(SceneImport, import_control_characters_of_names_are_escaped) {
  write("c.mtl", "newmtl l\x1B[2Jamp\nKd 0.2 0.2 0.2\nKe 4 4 4\n");
  const Scene scene = import_obj(write("c.obj", "mtllib c.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\n"
                                                "o a\x1B[2J\x07" "b\nusemtl l\x1B[2Jamp\nf 1 2 3\n"));
  ASSERT_EQ(scene.groups.size(), 1u);
  EXPECT_EQ(scene.groups[0].name, "a\\x1B[2J\\x07b");
  EXPECT_EQ(scene.materials[scene.faces[0].material].name, "l\\x1B[2Jamp");
  EXPECT_EQ(scene.materials[scene.faces[0].material].emission, Rgb(4.0));  // found by its name in the file
  EXPECT_EQ(printable(std::string("a\0b\x7F\xC3\xA9\t", 7)), "a\\x00b\\x7F\xC3\xA9\\x09");  // UTF-8 kept
}

// Points and lines have no area: aarad passes over them, good or bad. A bad one ("p 0") was refused by
// tinyobjloader with no line of the file and a line number shifted by the material libraries.
TEST_F(SceneImport, import_passes_over_points_and_lines) {
  write("s.mtl", kSquareMtl);
  for (const char* statements : {"p 1 2\nl 1 2 3\n", "p 0\n", "l 1 x\n", "l\np -99\n"}) {
    const std::string obj = write("points.obj", std::string("mtllib s.mtl\nmtllib s.mtl\n"
                                                            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n") +
                                                    statements + "usemtl grey\nf 1 2 3 4\n");
    const Scene scene = import_obj(obj);
    EXPECT_EQ(scene.faces.size(), 1u) << statements;
    EXPECT_EQ(scene.materials[scene.faces[0].material].name, "grey") << statements;
  }
}

// Statements aarad does not read are warned about and passed over, whatever their values: tinyobjloader's vertex
// weights (`vw`) and tags (`t`) stopped the import when bad ("vw 1 -1 0.5": "joint_id is negative"), with a line
// shifted by the material libraries and no file:line form.
TEST_F(SceneImport, import_passes_over_statements_it_does_not_read) {
  write("s.mtl", kSquareMtl);
  const std::string obj = write("vw.obj", "mtllib s.mtl\nmtllib s.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                          "vw 1 -1 0.5\nt crease 0/1 1 2\nusemtl grey\nf 1 2 3 4\n");
  const Scene scene = import_obj(obj);
  ASSERT_EQ(scene.faces.size(), 1u);
  EXPECT_EQ(scene.materials[scene.faces[0].material].name, "grey");
  EXPECT_TRUE(has_warning(scene, "vw.obj:7: 'vw' is not an OBJ statement"));
  EXPECT_TRUE(has_warning(scene, "vw.obj:8: 't' is not an OBJ statement"));
}

// aarad reads neither texture coordinates nor normals, but a face's reference to one the file has not defined says
// the file is damaged: one warning with the first line and the count (they were accepted in silence).
TEST_F(SceneImport, import_warns_of_texture_and_normal_references_out_of_range) {
  const std::string good = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 2 1 0\nvt 0 0\nvt 1 0\nvn 0 0 1\n";
  const Scene fine = import_obj(write("fine.obj", good + "f 1/1/1 2/2/1 3/-1/-1\nf 1//1 3//1 4//1\n"));
  EXPECT_EQ(fine.faces.size(), 2u);
  EXPECT_FALSE(has_warning(fine, "texture coordinate or normal"));
  const Scene bad = import_obj(write("bad.obj", good + "f 1/1/1 2/2/1 3/2/1\nf 1/3 3/2 4/1\nf 2//2 5//-2 6//1\n"));
  EXPECT_EQ(bad.faces.size(), 3u);
  EXPECT_TRUE(has_warning(bad, "bad.obj:11: a face refers to a texture coordinate or normal the file has not defined "
                               "(3 references in all, this line first)"));
}

TEST_F(SceneImport, import_vertex_index_out_of_range_is_error_with_line) {
  const InputError e = import_error(write("range.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\n\nf 1 2 7\n"));
  EXPECT_EQ(e.line(), 5);
  EXPECT_NE(e.message().find("out of range"), std::string::npos);
  // Beyond what an int holds, which would wrap around to vertex 2 (4294967298 = 2^32 + 2) or another.
  for (const char* face : {"f 1 2 4294967298", "f 1 2 -4294967295", "f 1 2 99999999999999999999/1"}) {
    const InputError big = import_error(write("big.obj", std::string("v 0 0 0\nv 1 0 0\nv 1 1 0\n") + face + "\n"));
    EXPECT_EQ(big.line(), 4) << face;
    EXPECT_NE(big.message().find("out of range"), std::string::npos) << face << ": " << big.message();
  }
}

TEST_F(SceneImport, import_face_with_a_token_that_is_not_a_vertex_reference_is_error_with_line) {
  const std::string vertices = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";
  for (const char* face : {"f 1 2 x 4", "f 1 2 3 4x", "f 1 2 3 0", "f 1/ 2 3 4/1/", "f 1//2/ 2 3", "f 1 2 3 4.5", "f 1/ 2 3"}) {
    const InputError e = import_error(write("token.obj", vertices + "# faces\n" + face + "\n"));
    EXPECT_EQ(e.line(), 6) << face;
    EXPECT_NE(e.message().find("not a vertex reference"), std::string::npos) << face << ": " << e.message();
  }
  // Index 0 is a whole number: the message says why it is refused ("with whole numbers" alone did not).
  EXPECT_NE(import_error(write("zero.obj", vertices + "f 0 1 2\n")).message().find("indices count from 1"),
            std::string::npos);
  // Every form OBJ allows: v, v/vt, v//vn, v/vt/vn, negative (relative) indices.
  const std::string ok = vertices + "vt 0 0\nvn 0 0 1\nf 1 2/1 3//1 -1/1/1\n";
  EXPECT_EQ(import_obj(write("forms.obj", ok)).faces.size(), 1u);
}

// A NUL byte cut its statement short without a word ("o wall\0A" and "o wall\0B" named one group); a text file
// holds none, so it is an error with its line, in the OBJ and in an MTL.
TEST_F(SceneImport, import_nul_byte_is_error_with_line) {
  write("s.mtl", kSquareMtl);
  const std::string obj = write("nul.obj", std::string("mtllib s.mtl\nusemtl lamp\nv 0 0 0\nv 1 0 0\nv 1 1 0\no wall\0A\n"
                                                       "f 1 2 3\n", 66));
  const InputError e = import_error(obj);
  EXPECT_EQ(e.file(), obj);
  EXPECT_EQ(e.line(), 6);
  EXPECT_NE(e.message().find("a NUL byte"), std::string::npos) << e.message();
  const std::string mtl = write("nul.mtl", std::string("newmtl lamp\nKd 0.5 0.5 0.5\nKe 1 1\0 1\n", 37));
  const InputError m = import_error(write("nul2.obj", "mtllib nul.mtl\nusemtl lamp\nv 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n"));
  EXPECT_EQ(m.file(), mtl);
  EXPECT_EQ(m.line(), 3);
}

// A file that opens but fails as it is read throws from the stream's buffer: it was an internal error (exit 3)
// naming no file. /proc/self/mem opens and fails to read at offset 0.
TEST_F(SceneImport, import_file_that_fails_as_it_is_read_is_an_input_error) {
  if (!fs::is_regular_file("/proc/self/mem")) GTEST_SKIP() << "no /proc/self/mem here";
  const InputError e = import_error("/proc/self/mem");
  EXPECT_EQ(e.file(), "/proc/self/mem");
  EXPECT_NE(e.message().find("cannot read the file"), std::string::npos) << e.message();
}

TEST_F(SceneImport, import_self_intersecting_face_is_error_with_line) {
  // Planar bow-ties: a symmetric one (its signed area is zero) and a lopsided one, in a tilted plane.
  const std::string head = "v 0 0 0\nv 1 1 0\nv 1 0 0\nv 0 1 0\nv 0 0 0\nv 3 2 3\nv 3 0 3\nv 0 1 0\n";
  const InputError symmetric = import_error(write("bow.obj", head + "f 1 2 3 4\n"));
  EXPECT_EQ(symmetric.line(), 9);
  EXPECT_NE(symmetric.message().find("intersects itself"), std::string::npos);
  // Vertices 5-8 lie in the plane z = x; in (x, y) they are (0,0) (3,2) (3,0) (0,1), whose first and third
  // edges cross at (1, 2/3). The valid triangle on line 10 comes first.
  const InputError lopsided = import_error(write("bow2.obj", head + "o fine\nf 1 3 2\nf 5 6 7 8\n"));
  EXPECT_EQ(lopsided.line(), 11);
  EXPECT_NE(lopsided.message().find("intersects itself"), std::string::npos);
}

TEST_F(SceneImport, import_kd_outside_unit_interval_is_error_with_mtl_line) {
  for (const std::string kd : {"1 0.5 0.5", "0.5 1.2 0.5", "0.5 0.5 -0.1", "nan 0.5 0.5"}) {
    const std::string mtl = write("bad.mtl", "# materials\nnewmtl ok\nKd 0.5 0.5 0.5\n\nnewmtl hot\nKe 1 1 1\nKd " + kd + "\n");
    const std::string obj = write("bad.obj", "mtllib bad.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nusemtl hot\nf 1 2 3\n");
    const InputError e = import_error(obj);
    EXPECT_EQ(e.file(), mtl) << kd;
    EXPECT_EQ(e.line(), 7) << kd;
    EXPECT_NE(e.message().find("would not converge"), std::string::npos) << kd;
    EXPECT_NE(e.message().find("'hot'"), std::string::npos) << kd;
  }
}

// Below 1e-100 but not 0, a channel of Kd or Ke is refused with its line: doubles lose its digits (a unit box lit
// with Ke 1e-308 solved 20 % off, and Kd 1e-320 split it into 139 000 elements).
TEST_F(SceneImport, import_kd_or_ke_below_1e_100_but_not_0_is_error_with_mtl_line) {
  for (const auto& [kd, ke, line] : {std::tuple{"0.5 1e-320 0.5", "1 1 1", 2}, {"0.5 0.5 0.5", "1e-308 0 0", 3},
                                     {"0.5 0.5 0.5", "1e-101 1 1", 3}}) {
    const std::string mtl = write("faint.mtl", std::string("newmtl lamp\nKd ") + kd + "\nKe " + ke + "\n");
    const std::string obj = write("faint.obj", "mtllib faint.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nusemtl lamp\nf 1 2 3\n");
    const InputError e = import_error(obj);
    EXPECT_EQ(e.file(), mtl) << kd << " / " << ke;
    EXPECT_EQ(e.line(), line) << kd << " / " << ke;
    EXPECT_NE(e.message().find("is below 1e-100 in a channel but not 0"), std::string::npos) << e.message();
  }
  write("faint.mtl", "newmtl lamp\nKd 1e-100 0 0.5\nKe 1e-100 0 1\n");
  EXPECT_NO_THROW(import_obj(write("faint.obj", "mtllib faint.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nusemtl lamp\nf 1 2 3\n")));
}

TEST_F(SceneImport, import_negative_ke_is_error_with_mtl_line) {
  const std::string mtl = write("neg.mtl", "newmtl lamp\nKd 0.5 0.5 0.5\nKe 1 -2 1\n");
  const std::string obj = write("neg.obj", "mtllib neg.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nusemtl lamp\nf 1 2 3\n");
  const InputError e = import_error(obj);
  EXPECT_EQ(e.file(), mtl);
  EXPECT_EQ(e.line(), 3);
  EXPECT_NE(e.message().find("Ke"), std::string::npos);
  EXPECT_NE(e.message().find(">= 0"), std::string::npos);
}

TEST_F(SceneImport, import_emission_too_large_for_the_solver_is_error) {
  // Ke 1e308 used to be taken: the first shot's sums overflowed and the solve reported convergence after it.
  const std::string mtl = write("big.mtl", "newmtl lamp\nKd 0.5 0.5 0.5\nKe 1e308 1e308 1e308\n");
  const std::string obj = write("big.obj", "mtllib big.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nusemtl lamp\nf 1 2 3\n");
  const InputError e = import_error(obj);
  EXPECT_EQ(e.file(), mtl);
  EXPECT_EQ(e.line(), 3);
  EXPECT_NE(e.message().find("at most 1e100"), std::string::npos) << e.message();
  // Within the bound per material, but over a vast area (both sides of a square 1e50 across, the largest
  // coordinate accepted): the scene's emitted flux is refused.
  write("ok.mtl", "newmtl lamp\nKd 0.5 0.5 0.5\nKe 1e100 1e100 1e100\n");
  const std::string vast = write("vast.obj", "mtllib ok.mtl\nv 0 0 0\nv 1e50 0 0\nv 1e50 1e50 0\nv 0 1e50 0\n"
                                             "usemtl lamp\nf 1 2 3 4\nf 4 3 2 1\n");
  EXPECT_NE(import_error(vast).message().find("emitted flux"), std::string::npos);
  // 1e100 over a unit triangle is fine.
  write("unit.obj", "mtllib ok.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nusemtl lamp\nf 1 2 3\n");
  EXPECT_NO_THROW(import_obj((dir_ / "unit.obj").string()));
}

TEST_F(SceneImport, import_empty_file_is_error) {
  const InputError e = import_error(write("empty.obj", "# nothing\nv 0 0 0\n"));
  EXPECT_NE(e.message().find("no usable faces"), std::string::npos);
}

// When every face is skipped, the error says so and names the first one (the warnings are not shown with an error).
TEST_F(SceneImport, import_with_every_face_skipped_names_the_first) {
  const InputError e = import_error(
      write("degenerate.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 3\nf 1 1 4\n"));
  EXPECT_NE(e.message().find("all 2 faces were skipped"), std::string::npos) << e.message();
  EXPECT_NE(e.message().find("degenerate.obj:5: face of zero area"), std::string::npos) << e.message();
  // Faces of fewer than three vertices count too (they were left out, and the error said the file had no 'f' line),
  // and the first is the one on the earliest line, whichever check skipped it.
  const InputError short_only = import_error(write("short.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\no a\nf 1 2\n"));
  EXPECT_NE(short_only.message().find("all 1 faces were skipped"), std::string::npos) << short_only.message();
  EXPECT_NE(short_only.message().find("short.obj:5: face with fewer than three vertices"), std::string::npos)
      << short_only.message();
  const InputError mixed =
      import_error(write("mixed.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\nf 1 2\nf 3 2 1\n"));
  EXPECT_NE(mixed.message().find("all 3 faces were skipped"), std::string::npos) << mixed.message();
  EXPECT_NE(mixed.message().find("mixed.obj:4: face of zero area"), std::string::npos) << mixed.message();
  // A face whose area overflows a double is skipped with its own reason, not taken for a line.
  const Scene scene = import_obj(write("vast_face.obj", "v 0 0 0\nv 1e200 0 0\nv 0 1e200 0\nv 1 0 0\nv 0 1 0\n"
                                                        "f 1 2 3\nf 1 4 5\n"));
  EXPECT_EQ(scene.faces.size(), 1u);
  ASSERT_FALSE(scene.warnings.empty());
  EXPECT_NE(scene.warnings.front().find("vast_face.obj:6: face too large"), std::string::npos) << scene.warnings.front();
}

// A valid scene scaled far up or down is refused as too large or too small for the solver's doubles, not as a face
// that intersects itself (squared lengths overflowed at 1e80) or lies on a line (they underflowed at 1e-100); the
// scales between import alike.
TEST_F(SceneImport, import_scales_beyond_double_precision_are_named_as_such) {
  write("s.mtl", kSquareMtl);
  const auto scaled = [&](double scale) {
    std::ostringstream text;
    text.precision(17);
    text << "mtllib s.mtl\n";
    for (const Vec3& p : {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(1, 1, 0), Vec3(0, 1, 0), Vec3(0.4, 0.4, 1),
                          Vec3(0.6, 0.4, 1), Vec3(0.6, 0.6, 1), Vec3(0.4, 0.6, 1)})
      text << "v " << p.x * scale << " " << p.y * scale << " " << p.z * scale << "\n";
    text << "g floor\nusemtl grey\nf 1 2 3 4\ng lamp\nusemtl lamp\nf 8 7 6 5\n";  // lines 12 and 15
    return write("scaled.obj", text.str());
  };
  for (const double scale : {1e-100, 1e-60}) {
    const std::string message = import_error(scaled(scale)).message();
    EXPECT_NE(message.find("all 2 faces were skipped; the first: " + (dir_ / "scaled.obj").string() +
                           ":12: face too small for double precision"),
              std::string::npos)
        << scale << ": " << message;
  }
  for (const double scale : {1e60, 1e80}) {
    const std::string message = import_error(scaled(scale)).message();
    EXPECT_NE(message.find("scaled.obj:12: face too large for double precision"), std::string::npos)
        << scale << ": " << message;
  }
  for (const double scale : {1e-45, 1e-12, 1.0, 1e6, 1e45}) {
    const Scene scene = import_obj(scaled(scale));
    EXPECT_EQ(scene.faces.size(), 2u) << scale;
    EXPECT_EQ(scene.surfaces.size(), 2u) << scale;
    EXPECT_TRUE(scene.warnings.empty()) << scale << ": " << scene.warnings.front();
    EXPECT_NEAR(scene.total_area() / (scale * scale), 1.04, 1e-12) << scale;
  }
  // A scene built in code is held to the same range.
  Scene vast;
  vast.name = "vast";
  const std::uint32_t m = vast.add_material({"lamp", Rgb(0.5), Rgb(1.0)});
  vast.add_face(vast.add_group("floor"), m, {{0, 0, 0}, {1e80, 0, 0}, {1e80, 1e80, 0}});
  vast.build_surfaces();
  try {
    vast.validate();
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_NE(e.message().find("face 0 (group 'floor') is too large for double precision"), std::string::npos)
        << e.message();
  }
}

// ---- Warnings: skipped and split faces -----------------------------------------------------------------

TEST_F(SceneImport, import_degenerate_faces_are_skipped_with_warning) {
  write("s.mtl", kSquareMtl);
  const std::string obj = write("deg.obj",
                                "mtllib s.mtl\n"                          // 1
                                "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"    // 2-5
                                "v 2 0 0\nv 3 0 0\n"                      // 6-7: vertices 5, 6
                                "usemtl lamp\n"                           // 8
                                "f 1 2\n"                                 // 9: two vertices
                                "f 1 2 2\n"                               // 10: two distinct
                                "f 1 2 1 2\n"                             // 11: two distinct
                                "f 1 2 5\n"                               // 12: collinear, zero area
                                "f 1 2 5 6\n"                             // 13: collinear, zero area
                                "f 1 2 3 4\n");                           // 14: fine
  const Scene scene = import_obj(obj);
  ASSERT_EQ(scene.faces.size(), 1u);
  EXPECT_EQ(scene.faces[0].source_line, 14);
  EXPECT_TRUE(has_warning(scene, obj + ":9: face with fewer than three vertices skipped"));
  EXPECT_TRUE(has_warning(scene, obj + ":10: face with fewer than three distinct vertices skipped"));
  EXPECT_TRUE(has_warning(scene, obj + ":11: face with fewer than three distinct vertices skipped"));
  EXPECT_TRUE(has_warning(scene, obj + ":12: face of zero area"));
  EXPECT_TRUE(has_warning(scene, obj + ":13: face of zero area"));
  EXPECT_EQ(scene.warnings.size(), 5u);
}

TEST_F(SceneImport, import_non_planar_face_is_split_into_triangles_with_warning) {
  // A unit square with one corner lifted by 0.2, and an L-shaped (concave) hexagon with one vertex
  // lifted: both split, covering the same outline.
  write("s.mtl", kSquareMtl);
  const std::string obj = write("bent.obj",
                                "mtllib s.mtl\nusemtl lamp\n"
                                "v 0 0 0\nv 1 0 0\nv 1 1 0.2\nv 0 1 0\n"
                                "v 0 0 5\nv 2 0 5\nv 2 1 5\nv 1 1 5.3\nv 1 2 5\nv 0 2 5\n"
                                "o square\nf 1 2 3 4\n"
                                "o ell\nf 5 6 7 8 9 10\n");
  const Scene scene = import_obj(obj);
  EXPECT_TRUE(has_warning(scene, obj + ":14: face is not planar"));
  EXPECT_TRUE(has_warning(scene, obj + ":16: face is not planar"));
  const Group& square = scene.groups[*scene.find_group("square")];
  ASSERT_EQ(square.faces.size(), 2u);
  double square_area = 0.0;
  for (const std::uint32_t f : square.faces) {
    EXPECT_EQ(scene.faces[f].vertices.size(), 3u);
    EXPECT_EQ(scene.faces[f].source_line, 14);
    EXPECT_GT(normal(scene.faces[f].vertices).z, 0.9);  // keeps the face's orientation
    square_area += area(scene.faces[f].vertices);
  }
  // Whichever diagonal the split takes, the triangles cover the square's footprint exactly once and,
  // being tilted, have more area than it.
  double footprint = 0.0;
  for (const std::uint32_t f : square.faces) footprint += vector_area(scene.faces[f].vertices).z;
  EXPECT_NEAR(footprint, 1.0, 1e-15);
  EXPECT_GT(square_area, 1.0);
  const Group& ell = scene.groups[*scene.find_group("ell")];
  EXPECT_EQ(ell.faces.size(), 4u);  // a hexagon gives four triangles
  double ell_footprint = 0.0;
  for (const std::uint32_t f : ell.faces) ell_footprint += vector_area(scene.faces[f].vertices).z;
  EXPECT_NEAR(ell_footprint, 3.0, 1e-14);
}

// A face is planar within the distance at which the scene takes faces for one plane, kPlaneDistance of its
// diagonal, not within that fraction of the face's own size: in a scene 6 x 6 x 1 (diagonal 8.544, so 8.544e-6), a unit
// square with a corner lifted by 1.2e-5 lies 3e-6 off its plane (a quarter of the lift; 2.1e-6 of its own size) and
// is kept whole, as a file's rounding to 6 digits bends faces; lifted by 4e-5 (1e-5 off) it is split.
TEST_F(SceneImport, import_face_bent_by_the_files_rounding_is_kept_whole) {
  write("s.mtl", kSquareMtl);
  const std::string obj = write("rounded.obj",
                                "mtllib s.mtl\n"
                                "v 0 0 0\nv 6 0 0\nv 6 6 0\nv 0 6 0\n"
                                "v 1 1 1\nv 2 1 1\nv 2 2 1.000012\nv 1 2 1\n"
                                "v 3 1 1\nv 4 1 1\nv 4 2 1.00004\nv 3 2 1\n"
                                "o floor\nusemtl lamp\nf 1 2 3 4\n"
                                "o rounded\nusemtl grey\nf 5 6 7 8\n"
                                "o bent\nf 9 10 11 12\n");
  const Scene scene = import_obj(obj);
  const Group& rounded = scene.groups[*scene.find_group("rounded")];
  ASSERT_EQ(rounded.faces.size(), 1u);
  EXPECT_EQ(scene.faces[rounded.faces[0]].vertices.size(), 4u);
  EXPECT_EQ(scene.groups[*scene.find_group("bent")].faces.size(), 2u);
  EXPECT_TRUE(has_warning(scene, obj + ":21: face is not planar (a vertex lies 9.99999999"));
  EXPECT_TRUE(has_warning(scene, "more than 1e-06 of the scene's diagonal, 8.544008427e-06); split into 2 triangles"));
  EXPECT_EQ(scene.warnings.size(), 1u);
}

TEST_F(SceneImport, import_concave_planar_face_is_kept_whole) {
  write("s.mtl", kSquareMtl);
  const std::string obj = write("ell.obj",
                                "mtllib s.mtl\nusemtl lamp\n"
                                "v 0 0 0\nv 2 0 0\nv 2 1 0\nv 1 1 0\nv 1 2 0\nv 0 2 0\nf 1 2 3 4 5 6\n");
  const Scene scene = import_obj(obj);
  ASSERT_EQ(scene.faces.size(), 1u);
  EXPECT_EQ(scene.faces[0].vertices.size(), 6u);
  EXPECT_DOUBLE_EQ(scene.surfaces[0].area, 3.0);
  EXPECT_TRUE(scene.warnings.empty()) << scene.warnings.front();
}

// tinyobjloader counts a face's vertices in an unsigned char: a 300-vertex face came back with 44 and the next
// face in its group was made of the other 256 (a quad turned into a sliver of the disc), a 256-vertex face was
// skipped as having fewer than three distinct vertices, and a 1000-vertex face kept 232.
TEST_F(SceneImport, import_faces_of_more_than_255_vertices_are_read_whole) {
  write("s.mtl", kSquareMtl);
  const auto disc = [](int n, double y) {
    std::ostringstream text;
    text.precision(17);
    for (int k = 0; k < n; ++k) {
      const double angle = 2.0 * kPi * k / n;
      text << "v " << std::cos(angle) << " " << y << " " << -std::sin(angle) << "\n";  // facing +y
    }
    return text.str();
  };
  const auto face = [](int first, int n) {
    std::ostringstream text;
    text << "f";
    for (int k = 0; k < n; ++k) text << " " << first + k;
    text << "\n";
    return text.str();
  };
  for (const int n : {255, 256, 300, 1000}) {
    // Line 1 mtllib, 2 usemtl, n + 4 vertices, then the disc on line n + 7 and the quad on line n + 8, one group.
    const std::string obj = write("disc.obj", "mtllib s.mtl\nusemtl lamp\n" + disc(n, 0.0) +
                                                  "v 3 0 0\nv 3 0 -1\nv 4 0 -1\nv 4 0 0\n" + face(1, n) +
                                                  face(n + 1, 4));
    const Scene scene = import_obj(obj);
    ASSERT_EQ(scene.faces.size(), 2u) << n;
    EXPECT_EQ(scene.groups.size(), 1u) << n;
    EXPECT_TRUE(scene.warnings.empty()) << n << ": " << scene.warnings.front();
    EXPECT_EQ(scene.faces[0].vertices.size(), static_cast<std::size_t>(n));
    EXPECT_EQ(scene.faces[0].source_line, n + 7);
    EXPECT_NEAR(area(scene.faces[0].vertices), 0.5 * n * std::sin(2.0 * kPi / n), 1e-12) << n;
    EXPECT_EQ(scene.faces[1].vertices, (std::vector<Vec3>{{3, 0, 0}, {3, 0, -1}, {4, 0, -1}, {4, 0, 0}})) << n;
    EXPECT_EQ(scene.faces[1].source_line, n + 8);
  }
}

// ---- Groups, surfaces, materials -----------------------------------------------------------------------

TEST_F(SceneImport, import_groups_follow_nearest_o_or_g) {
  write("s.mtl", kSquareMtl);
  const std::string obj = write("groups.obj",
                                "mtllib s.mtl\nusemtl lamp\n"
                                "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                "f 1 2 3\n"           // before any o/g: the file's stem
                                "o thing\nf 1 3 4\n"  // o
                                "g part\nf 1 2 4\n"   // g overrides the o
                                "o thing\nf 2 3 4\n"  // the same name again: the same group
                                "g\n");
  const Scene scene = import_obj(obj);
  ASSERT_EQ(scene.groups.size(), 3u);
  EXPECT_EQ(scene.groups[0].name, "groups");
  EXPECT_EQ(scene.groups[1].name, "thing");
  EXPECT_EQ(scene.groups[2].name, "part");
  EXPECT_EQ(scene.groups[1].faces.size(), 2u);
  EXPECT_EQ(scene.faces[scene.groups[2].faces[0]].source_line, 11);
  EXPECT_EQ(scene.faces[scene.groups[1].faces[1]].source_line, 13);
}

// An `o` or `g` without a name starts a group as a named one does, named after its line, with a warning. A bare `o`
// or `g` used to be passed over (its faces joined the group before) and one followed by blanks started a group
// named after the file; a bare `g` that no face follows (3ds Max ends objects with one) starts nothing.
TEST_F(SceneImport, import_o_or_g_without_a_name_starts_a_group_named_after_its_line) {
  write("s.mtl", kSquareMtl);
  const std::string obj = write("noname.obj",
                                "mtllib s.mtl\nusemtl lamp\n"
                                "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\n"
                                "o thing\nf 1 2 3\n"  // lines 8-9
                                "o\nf 1 3 4\n"        // lines 10-11: bare
                                "g  \t\nf 2 5 3\n"   // lines 12-13: blanks after it
                                "g\n");
  const Scene scene = import_obj(obj);
  ASSERT_EQ(scene.groups.size(), 3u);
  EXPECT_EQ(scene.groups[0].name, "thing");
  EXPECT_EQ(scene.groups[1].name, "unnamed_line_10");
  EXPECT_EQ(scene.groups[2].name, "unnamed_line_12");
  for (const Group& g : scene.groups) EXPECT_EQ(g.faces.size(), 1u) << g.name;
  EXPECT_EQ(scene.faces[scene.groups[1].faces[0]].source_line, 11);
  ASSERT_EQ(scene.warnings.size(), 2u) << scene.warnings.front();
  EXPECT_NE(scene.warnings[0].find("noname.obj:10: 'o' without a name: its faces form the group 'unnamed_line_10'"),
            std::string::npos)
      << scene.warnings[0];
  EXPECT_NE(scene.warnings[1].find("noname.obj:12: 'g' without a name"), std::string::npos) << scene.warnings[1];
}

TEST_F(SceneImport, import_coplanar_faces_of_a_group_form_one_surface) {
  write("s.mtl", kSquareMtl);
  const std::string obj = write("planes.obj",
                                "mtllib s.mtl\nusemtl grey\n"
                                "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 2 1 0\n"  // 1-6, z = 0
                                "v 5 5 5\n"                                             // 7, for scale
                                "v 0 0 1e-9\nv 1 0 1e-9\nv 1 1 1e-9\n"                  // 8-10, 1e-9 above
                                "v 0 0 0.01\nv 1 0 0.01\nv 1 1 0.01\n"                  // 11-13, 0.01 above
                                "g floor\n"
                                "f 1 2 3 4\nf 2 5 6 3\n"    // two coplanar pieces facing +z: one surface
                                "f 8 9 10\n"                 // within the tolerance: the same surface
                                "f 11 12 13\n"               // 0.01 above: another surface
                                "f 4 3 2 1\n"                // coplanar but facing -z: another surface
                                "usemtl lamp\nf 2 5 6\n"     // same plane, other material: another surface
                                "g other\nf 1 2 3\n"         // same plane, other group: another surface
                                "g tall\nf 1 2 7\n");
  const Scene scene = import_obj(obj);
  const Group& floor = scene.groups[*scene.find_group("floor")];
  ASSERT_EQ(floor.faces.size(), 6u);
  ASSERT_EQ(floor.surfaces.size(), 4u);
  const Surface& first = scene.surfaces[floor.surfaces[0]];
  EXPECT_EQ(first.faces.size(), 3u);
  EXPECT_DOUBLE_EQ(first.area, 2.5);
  EXPECT_EQ(first.plane.normal, Vec3(0, 0, 1));
  EXPECT_EQ(scene.surfaces[floor.surfaces[2]].plane.normal, Vec3(0, 0, -1));
  EXPECT_EQ(scene.surfaces.size(), 6u);
  for (std::uint32_t s = 0; s < scene.surfaces.size(); ++s)
    for (const std::uint32_t f : scene.surfaces[s].faces) EXPECT_EQ(scene.faces[f].surface, s);
}

// `s N` and `s off` set the smoothing group of the faces after them (Face::smoothing), across `o` lines as OBJ
// readers do; coplanar faces in two smoothing groups stay one physical surface (design.md), which smooths with
// none; a statement that is neither a whole number nor `off` warns with its line; write_obj writes the groups back.
TEST_F(SceneImport, import_smoothing_groups_are_read_per_face_and_written_back) {
  write("s.mtl", kSquareMtl);
  const std::string obj = write("smooth.obj",
                                "mtllib s.mtl\nusemtl grey\n"
                                "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0.5\nv 2 1 0.5\nv 3 0 0\nv 3 1 0\n"  // 1-8
                                "v 0 2 0\nv 1 2 0\nv 0 3 0\nv 1 3 0\nv 0 4 0\nv 1 4 0\n"                     // 9-14
                                "v 3 0 1\nv 3 1 1\nv 3 0 2\nv 3 1 2\n"                                          // 15-18
                                "o bent\n"
                                "s 1\nf 1 2 3 4\nf 2 5 6 3\n"  // lines 23-24: group 1
                                "s off\nf 5 7 8 6\n"           // none
                                "o flat\n"
                                "f 4 3 10 9\n"                  // still off
                                "s 2\nf 9 10 12 11\n"          // group 2, coplanar with the face before
                                "o later\n"
                                "f 11 12 14 13\n"               // group 2 holds across `o`
                                "s 0\nf 7 15 16 8\n"           // 0 is off
                                "s smooth\nf 15 17 18 16\n");  // line 35 warns
  const Scene scene = import_obj(obj);
  std::vector<std::uint32_t> smoothing;
  for (const Face& f : scene.faces) smoothing.push_back(f.smoothing);
  EXPECT_EQ(smoothing, (std::vector<std::uint32_t>{1, 1, 0, 0, 2, 2, 0, 0}));
  ASSERT_FALSE(scene.warnings.empty());
  EXPECT_TRUE(has_warning(scene, "smooth.obj:35: smoothing statement 's smooth' not understood")) << scene.warnings.front();
  EXPECT_EQ(scene.warnings.size(), 2u) << scene.warnings.back();  // and "no face emits light"
  const Group& flat = scene.groups[*scene.find_group("flat")];
  ASSERT_EQ(flat.surfaces.size(), 1u);  // one plane: one surface, its faces in no group and in group 2
  EXPECT_EQ(scene.surfaces[flat.surfaces[0]].smoothing, 0u);
  const Group& bent = scene.groups[*scene.find_group("bent")];
  ASSERT_EQ(bent.surfaces.size(), 3u);
  EXPECT_EQ(scene.surfaces[bent.surfaces[0]].smoothing, 1u);
  EXPECT_EQ(scene.surfaces[bent.surfaces[1]].smoothing, 1u);
  EXPECT_EQ(scene.surfaces[bent.surfaces[2]].smoothing, 0u);

  const std::string path = (dir_ / "back.obj").string();
  write_obj(scene, path);
  const Scene back = import_obj(path);
  ASSERT_EQ(back.faces.size(), scene.faces.size());
  for (std::size_t f = 0; f < scene.faces.size(); ++f) EXPECT_EQ(back.faces[f].smoothing, scene.faces[f].smoothing) << f;
}

// build_surfaces tries only the surfaces whose offset d can hold the face: a face tilted by 1e-5 radians (within
// the normal tolerance) about a line 1000 from the origin has its own d 0.01 away from its surface's, ten times
// the plane distance tolerance (1e-6 of a diagonal of about 1000), and still joins it; tilted by 2e-5 it does not.
TEST(SceneSurfaces, AFaceFarFromTheOriginJoinsASurfaceWhoseOffsetDiffersByItsTilt) {
  for (const double tilt : {1e-5, 2e-5}) {
    Scene scene;
    scene.name = "far";
    const std::uint32_t grey = scene.add_material(Material{"grey", Rgb(0.5), Rgb(0.0)});
    const std::uint32_t group = scene.add_group("floor");
    scene.add_face(group, grey, {{999, 0, 0}, {1000, 0, 0}, {1000, 1, 0}, {999, 1, 0}});
    // Pivoting about x = 1000.5: its vertices stay within 5e-6 (tilt 1e-5) of the first face's plane z = 0.
    const auto z = [&](double x) { return tilt * (x - 1000.5); };
    scene.add_face(group, grey, {{1000, 0, z(1000)}, {1001, 0, z(1001)}, {1001, 1, z(1001)}, {1000, 1, z(1000)}});
    scene.add_face(scene.add_group("far"), grey, {{0, 0, 5}, {1, 0, 5}, {0, 1, 5}});  // a diagonal of about 1000
    scene.build_surfaces();
    const Plane own = plane_of(scene.faces[1].vertices);
    EXPECT_GT(std::abs(own.d - scene.surfaces[0].plane.d), 5e-3) << "tilt " << tilt;
    EXPECT_EQ(scene.groups[group].surfaces.size(), tilt == 1e-5 ? 1u : 2u) << "tilt " << tilt;
  }
}

// build_surfaces looks a face's surface up among those whose normal lies in the same cell of 1e-4 per coordinate as
// the face's, or in a neighbouring one when the face's normal is near a cell's side. Two triangles in the planes
// through the z axis with normals (0.6, 0.8, 0) turned by -+5e-7 radians about z (their normals' x and y on either
// side of 0.6 and 0.8, cell sides; 1e-6 radians apart, within the normal tolerance, and their vertices within
// 1e-6 of each other's plane, within the distance tolerance) join one surface, with either one first. Turned
// -+5e-5 radians they are two.
TEST(SceneSurfaces, FacesWhoseNormalsLieEitherSideOfABinsEdgeJoinOneSurface) {
  for (const double turn : {5e-7, -5e-7, 5e-5}) {
    Scene scene;
    scene.name = "turned";
    const std::uint32_t grey = scene.add_material(Material{"grey", Rgb(0.5), Rgb(0.0)});
    const std::uint32_t group = scene.add_group("panel");
    const double base = std::atan2(0.8, 0.6);
    for (const double angle : {base - turn, base + turn}) {
      const Vec3 n(std::cos(angle), std::sin(angle), 0.0), along(-n.y, n.x, 0.0), up(0, 0, 1);
      scene.add_face(group, grey, {0.1 * along, 0.9 * along, 0.5 * along + 0.8 * up});
    }
    scene.build_surfaces();
    const Vec3 a = plane_of(scene.faces[0].vertices).normal, b = plane_of(scene.faces[1].vertices).normal;
    EXPECT_EQ(a.x < 0.6, b.x > 0.6) << "turn " << turn;
    EXPECT_EQ(scene.surfaces.size(), std::abs(turn) < 1e-6 ? 1u : 2u) << "turn " << turn;
  }
}

// coplanar_overlaps compares only surfaces whose bounds overlap on the two axes that project_to_2d keeps for the
// pair's first surface. A 30 x 30 grid of square tiles in one plane (900 surfaces, one group each, of two halves,
// touching along edges: no overlap) with a rug on two of them: exactly those overlaps, with their areas and lines.
TEST(SceneSurfaces, OverlapsAmongManySurfacesOfOnePlaneAreTheOnesThatMeet) {
  Scene scene;
  scene.name = "tiles";
  const std::uint32_t grey = scene.add_material(Material{"grey", Rgb(0.5), Rgb(0.0)});
  for (int j = 0; j < 30; ++j)
    for (int i = 0; i < 30; ++i) {
      const int line = 2 * (30 * j + i) + 1;
      const std::uint32_t tile = scene.add_group("tile" + std::to_string(line));
      const double x = i, z = j;
      scene.add_face(tile, grey, {{x, 0, z}, {x, 0, z + 1}, {x + 0.5, 0, z + 1}, {x + 0.5, 0, z}}, line);
      scene.add_face(tile, grey, {{x + 0.5, 0, z}, {x + 0.5, 0, z + 1}, {x + 1, 0, z + 1}, {x + 1, 0, z}}, line + 1);
    }
  // Rugs: on the second half of tile (3, 1) only (lines 67, 68), and across tiles (20, 25) and (21, 25)
  // (lines 1541-1544).
  scene.add_face(scene.add_group("rug a"), grey, {{3.6, 0, 1.1}, {3.6, 0, 1.3}, {3.9, 0, 1.3}, {3.9, 0, 1.1}}, 2001);
  scene.add_face(scene.add_group("rug b"), grey, {{20.5, 0, 25.5}, {20.5, 0, 26}, {21.75, 0, 26}, {21.75, 0, 25.5}}, 2002);
  scene.build_surfaces();
  ASSERT_EQ(scene.surfaces.size(), 902u);
  const std::vector<Scene::CoplanarOverlap> found = scene.coplanar_overlaps();
  ASSERT_EQ(found.size(), 3u);
  EXPECT_EQ(found[0].a, 33u);  // tile (3, 1)
  EXPECT_EQ(found[0].b, 900u);
  EXPECT_NEAR(found[0].area, 0.06, 1e-12);
  EXPECT_EQ(found[0].line_a, 68);
  EXPECT_EQ(found[0].line_b, 2001);
  EXPECT_EQ(found[1].a, 770u);  // tile (20, 25)
  EXPECT_EQ(found[1].b, 901u);
  EXPECT_NEAR(found[1].area, 0.25, 1e-12);
  EXPECT_EQ(found[2].a, 771u);  // tile (21, 25)
  EXPECT_EQ(found[2].b, 901u);
  EXPECT_NEAR(found[2].area, 0.375, 1e-12);
}

// Two faces on one another in a plane at 45 degrees between the x and y axes, tilted by 2e-7 radians either way
// (within the normal tolerance): the first surface's normal has its largest component along one axis and the
// other's along the other, so project_to_2d drops different axes for them. The overlap is found with either one
// first.
TEST(SceneSurfaces, OverlapsAreFoundBetweenSurfacesWhoseNormalsLeanToDifferentAxes) {
  for (const bool x_first : {true, false}) {
    Scene scene;
    scene.name = "diagonal";
    const std::uint32_t grey = scene.add_material(Material{"grey", Rgb(0.5), Rgb(0.0)});
    const auto square = [](double lean, double lo, double hi) {
      // In the plane through the origin with normal (1, 1 + lean, 0) (unnormalised): x = -(1 + lean) y.
      std::vector<Vec3> v;
      for (const auto& [y, z] : {std::pair{lo, lo}, std::pair{hi, lo}, std::pair{hi, hi}, std::pair{lo, hi}})
        v.push_back(Vec3(-(1.0 + lean) * y, y, z));
      return v;
    };
    const double first = x_first ? -4e-7 : 4e-7;
    scene.add_face(scene.add_group("a"), grey, square(first, 0.0, 1.0));
    scene.add_face(scene.add_group("b"), grey, square(-first, 0.5, 1.5));
    scene.build_surfaces();
    ASSERT_EQ(scene.surfaces.size(), 2u);
    const Vec3 na = glm::abs(scene.surfaces[0].plane.normal), nb = glm::abs(scene.surfaces[1].plane.normal);
    EXPECT_EQ(na.x > na.y, x_first);  // the two lean to different axes
    EXPECT_EQ(nb.x > nb.y, !x_first);
    const std::vector<Scene::CoplanarOverlap> found = scene.coplanar_overlaps();
    ASSERT_EQ(found.size(), 1u) << "x first " << x_first;
    EXPECT_EQ(found[0].a, 0u);
    EXPECT_EQ(found[0].b, 1u);
    // In the plane: y and z from 0.5 to 1, and x with y (0.25 in the projection that drops x or y, as before).
    EXPECT_NEAR(found[0].area, 0.25 * std::sqrt(2.0), 1e-6);
  }
}

// A rug on a floor, both turned off the axes: the overlap is its area in the plane, 2, not in the projection that
// coplanar_overlaps measures in (3.47 of 4 and 8.59 of 9 in a reviewer's turned rooms).
TEST(SceneSurfaces, TheOverlapOfARugOnAFloorTurnedOffTheAxesIsItsAreaInThePlane) {
  const Vec3 axis = glm::normalize(Vec3(0.3, 1.0, -0.4));
  const auto turn = [&](const Vec3& p) {  // 0.7 radians about `axis` (Rodrigues)
    const double c = std::cos(0.7), s = std::sin(0.7);
    return c * p + s * glm::cross(axis, p) + (1.0 - c) * glm::dot(axis, p) * axis;
  };
  const auto quad = [&](double x0, double x1, double z0, double z1) {
    return std::vector<Vec3>{turn({x0, 0, z0}), turn({x0, 0, z1}), turn({x1, 0, z1}), turn({x1, 0, z0})};
  };
  Scene scene;
  scene.name = "turned rug";
  const std::uint32_t grey = scene.add_material(Material{"grey", Rgb(0.5), Rgb(0.0)});
  const std::uint32_t red = scene.add_material(Material{"red", Rgb(0.5, 0.1, 0.1), Rgb(0.0)});
  scene.add_face(scene.add_group("floor"), grey, quad(0, 4, 0, 4));
  scene.add_face(scene.add_group("rug"), red, quad(1, 2, 1, 3));
  scene.build_surfaces();
  const std::vector<Scene::CoplanarOverlap> found = scene.coplanar_overlaps();
  ASSERT_EQ(found.size(), 1u);
  EXPECT_NEAR(found[0].area, 2.0, 1e-9);
}

// The shapes on which coplanar_overlaps was quadratic, small: a floor facing +y (the projection keeps z, x, and
// the old sweep ran along z) of 4 x 4 unit tiles and a 1 x 4 strip beside them along z (one surface, touching
// only), under three decals each its own group, one of them a runner along the strip; and planks 4 long along z
// side by side, one of them laid half over its neighbour. Each pair's area and the lines of its largest share by
// hand: decal a on tile (0, 0), 0.5 x 0.5; decal b across tiles (1, 1) and (2, 1), 0.5 x 0.5 and 0.75 x 0.5; the
// runner on the strip, 0.5 x 4; the planks, 0.5 x 4.
TEST(SceneSurfaces, OverlapsOfAFloorWithAStripUnderDecalsAndOfPlanksLaidOverOneAnotherAreTheirAreas) {
  Scene scene;
  scene.name = "floor";
  const std::uint32_t grey = scene.add_material(Material{"grey", Rgb(0.5), Rgb(0.0)});
  const auto quad = [](double x0, double x1, double z0, double z1) {  // facing +y
    return std::vector<Vec3>{{x0, 0, z0}, {x0, 0, z1}, {x1, 0, z1}, {x1, 0, z0}};
  };
  const std::uint32_t floor = scene.add_group("floor");
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) scene.add_face(floor, grey, quad(i, i + 1, j, j + 1), 1 + 4 * j + i);  // lines 1-16
  scene.add_face(floor, grey, quad(-1, 0, 0, 4), 17);                                                     // the strip
  scene.add_face(scene.add_group("decal a"), grey, quad(0.25, 0.75, 0.25, 0.75), 18);
  scene.add_face(scene.add_group("decal b"), grey, quad(1.5, 2.75, 1.25, 1.75), 19);
  scene.add_face(scene.add_group("runner"), grey, quad(-0.75, -0.25, 0, 4), 20);
  const std::uint32_t planks = scene.add_group("planks");
  for (int i = 0; i < 3; ++i) scene.add_face(planks, grey, quad(5 + i, 6 + i, 0, 4), 21 + i);
  scene.add_face(planks, grey, quad(7.5, 8.5, 0, 4), 24);
  scene.build_surfaces();
  ASSERT_EQ(scene.surfaces.size(), 5u);
  const std::vector<Scene::CoplanarOverlap> found = scene.coplanar_overlaps();
  ASSERT_EQ(found.size(), 4u);
  const std::array<Scene::CoplanarOverlap, 4> expected{{{0, 1, 0.25, 1, 18},  // decal a on tile (0, 0)
                                                       {0, 2, 0.625, 7, 19},  // decal b, mostly on tile (2, 1)
                                                       {0, 3, 2.0, 17, 20},   // the runner on the strip
                                                       {4, 4, 2.0, 23, 24}}};  // the planks
  for (std::size_t i = 0; i < expected.size(); ++i) {
    EXPECT_EQ(found[i].a, expected[i].a) << i;
    EXPECT_EQ(found[i].b, expected[i].b) << i;
    EXPECT_NEAR(found[i].area, expected[i].area, 1e-12) << i;
    EXPECT_EQ(found[i].line_a, expected[i].line_a) << i;
    EXPECT_EQ(found[i].line_b, expected[i].line_b) << i;
  }
}

TEST_F(SceneImport, import_faces_on_one_another_in_one_plane_warn_with_their_lines) {
  write("s.mtl", kSquareMtl);
  const std::string obj = write("rug.obj",
                                "mtllib s.mtl\n"
                                "v 0 0 0\nv 4 0 0\nv 4 4 0\nv 0 4 0\n"  // 1-4: the floor
                                "v 1 1 0\nv 2 1 0\nv 2 2 0\nv 1 2 0\n"  // 5-8: the rug
                                "v 4 8 0\nv 0 8 0\n"                    // 9-10: a tile beside the floor
                                "v 1 1 3\nv 2 1 3\nv 2 2 3\n"            // 11-13: the lamp
                                "g floor\nusemtl grey\nf 1 2 3 4\n"        // line 17
                                "g tile\nf 4 3 9 10\n"                    // line 19
                                "g rug\nf 5 6 7 8\n"                      // line 21
                                "g lamp\nusemtl lamp\nf 13 12 11\n");
  const Scene scene = import_obj(obj);
  EXPECT_TRUE(has_warning(scene, "rug.obj:17: 'floor' (material 'grey') and 'rug' (material 'grey') lie on one "
                                 "another in one plane over an area of 1 (lines 17 and 21 overlap most)"));
  int overlaps = 0;
  for (const std::string& w : scene.warnings) overlaps += w.find("one plane") != std::string::npos;
  EXPECT_EQ(overlaps, 1);  // the tile only shares an edge with the floor
}

// A face added to a group that does not exist is refused (it wrote past the groups' end).
TEST(SceneSurfaces, AFaceOfAGroupThatDoesNotExistIsRefused) {
  Scene scene;
  scene.add_material(Material{"grey", Rgb(0.5), Rgb(0.0)});
  try {
    scene.add_face(7, 0, {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}});
    ADD_FAILURE() << "no exception";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "Scene::add_face: group 7 does not exist (the scene has 0 groups); make it with add_group "
                           "first");
  }
  EXPECT_TRUE(scene.faces.empty());
}

// n copies of one face overlap in n (n - 1) / 2 pairs. The search stops at the limit it is given and says so: 200
// copies, each its own group (19 900 pairs of surfaces), and one surface of 200 copies side by side (19 900 pairs
// of its faces).
TEST(SceneSurfaces, TheOverlapSearchStopsAtItsLimitAndSaysSo) {
  for (const bool one_group : {false, true}) {
    Scene scene;
    scene.name = "stack";
    const std::uint32_t grey = scene.add_material(Material{"grey", Rgb(0.5), Rgb(0.0)});
    const std::uint32_t group = scene.add_group("stack");
    for (int i = 0; i < 200; ++i) {
      const double x = one_group ? 1e-5 * i : 0.0;
      scene.add_face(one_group ? group : scene.add_group("copy" + std::to_string(i)), grey,
                     {{x, 0, 0}, {x, 0, 1}, {x + 1, 0, 1}, {x + 1, 0, 0}}, i + 1);
    }
    scene.build_surfaces();
    bool complete = false;
    const std::size_t all = scene.coplanar_overlaps(std::numeric_limits<std::size_t>::max(), &complete).size();
    EXPECT_TRUE(complete);
    EXPECT_EQ(all, one_group ? 1u : 19'900u);
    const std::vector<Scene::CoplanarOverlap> some = scene.coplanar_overlaps(1'000, &complete);
    EXPECT_FALSE(complete) << one_group;
    EXPECT_LE(some.size(), 1'000u);
    EXPECT_GE(some.size(), 1u);
  }
}

// A file of 1 500 copies of one face (1.1 million pairs) is imported in bounded time and memory (16 000 copies took
// a minute and 8 GB before the limit), and the warning says the search stopped.
TEST_F(SceneImport, import_of_many_faces_on_one_another_stops_the_search_and_says_so) {
  std::string text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";
  for (int i = 0; i < 1'500; ++i) text += "g copy" + std::to_string(i) + "\nf 1 2 3 4\n";
  const Scene scene = import_obj(write("stack.obj", text));
  EXPECT_TRUE(has_warning(scene, "stack.obj: at least 999990 more pairs of surfaces overlap in one plane; the search "
                                 "for faces that overlap stopped after a million pairs"));
}

TEST_F(SceneImport, import_materials_and_emitters) {
  write("s.mtl", kSquareMtl);
  const std::string obj = write("lit.obj",
                                "mtllib s.mtl\n"
                                "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                "v 0 0 2\nv 0 1 2\nv 1 1 2\nv 1 0 2\n"
                                "g floor\nusemtl grey\nf 1 2 3 4\n"
                                "g light\nusemtl lamp\nf 5 6 7 8\n");
  const Scene scene = import_obj(obj);
  EXPECT_TRUE(scene.warnings.empty());
  const Surface& light = scene.surfaces[scene.groups[*scene.find_group("light")].surfaces[0]];
  EXPECT_EQ(scene.materials[light.material].emission, Rgb(4.0));
  EXPECT_EQ(scene.materials[light.material].reflectance, Rgb(0.2));
  EXPECT_EQ(light.plane.normal, Vec3(0, 0, -1));
  EXPECT_DOUBLE_EQ(light.plane.d, 2.0);
  EXPECT_FALSE(scene.camera.has_value());
  EXPECT_DOUBLE_EQ(scene.total_area(), 2.0);
  EXPECT_EQ(scene.bounds_max(), Vec3(1, 1, 2));
  EXPECT_DOUBLE_EQ(scene.diagonal(), std::sqrt(6.0));
}

// Notepad starts files with a UTF-8 byte-order mark, and OBJ allows a comment after a statement: neither may
// hide a statement (here the first line of each file, mtllib and newmtl) nor break a face line.
TEST_F(SceneImport, import_byte_order_marks_and_trailing_comments_are_read_as_text) {
  const std::string bom = "\xEF\xBB\xBF";
  write("s.mtl", bom + kSquareMtl);
  const std::string obj = write("lit.obj",
                                bom + "mtllib s.mtl # the materials\n"
                                "v 0 0 0 # origin\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                "v 0 0 2\nv 0 1 2\nv 1 1 2\nv 1 0 2\n"
                                "g floor #1\nusemtl grey\nf 1 2 3 4 # floor quad\n"
                                "g light\nusemtl lamp\t# the lamp\nf 5 6 7 8\n");
  const Scene scene = import_obj(obj);
  EXPECT_TRUE(scene.warnings.empty()) << scene.warnings.front();
  ASSERT_EQ(scene.groups.size(), 2u);
  EXPECT_EQ(scene.groups[0].name, "floor #1");  // a name keeps its '#'
  const Surface& light = scene.surfaces[scene.groups[*scene.find_group("light")].surfaces[0]];
  EXPECT_EQ(scene.materials[light.material].emission, Rgb(4.0));
  EXPECT_EQ(scene.materials[light.material].reflectance, Rgb(0.2));
  EXPECT_DOUBLE_EQ(scene.total_area(), 2.0);
}

// A backslash at the end of a line continues the statement on the next (the OBJ specification's line
// continuation), in OBJ and MTL files, with CRLF line ends too: the face was an error ("face vertex '\' is not a
// vertex reference"). Lines after a continued statement keep their numbers, and an error inside one names its
// first line; a comment ending in a backslash does not swallow the next line.
TEST_F(SceneImport, import_lines_ending_in_a_backslash_continue_on_the_next) {
  write("s.mtl", "newmtl grey\nKd 0.5 \\\n   0.5 0.5\nnewmtl lamp\nKd 0.2 0.2 0.2\nKe 4 \\\r\n4 4\r\n");
  const std::string obj = write("continued.obj",
                                "mtllib s.mtl\n"
                                "# C:\\models\\\n"
                                "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                "v 0 0 2\nv 0 1 2\nv 1 1 2\nv 1 0 \\\n 2\n"
                                "g floor\nusemtl grey\nf 1 2 \\\n  3 \\\t\n  4\n"
                                "g light\nusemtl lamp\nf 5 6 7 8\n");
  const Scene scene = import_obj(obj);
  EXPECT_DOUBLE_EQ(scene.total_area(), 2.0);
  const Surface& light = scene.surfaces[scene.groups[*scene.find_group("light")].surfaces[0]];
  EXPECT_EQ(scene.materials[light.material].emission, Rgb(4.0));
  const Surface& floor = scene.surfaces[scene.groups[*scene.find_group("floor")].surfaces[0]];
  EXPECT_EQ(scene.materials[floor.material].reflectance, Rgb(0.5));
  EXPECT_TRUE(scene.warnings.empty()) << scene.warnings.front();
  // A continued face has the line it starts on; the lines after it keep their numbers.
  EXPECT_EQ(scene.faces[scene.groups[*scene.find_group("floor")].faces[0]].source_line, 14);
  EXPECT_EQ(scene.faces[scene.groups[*scene.find_group("light")].faces[0]].source_line, 19);

  const std::string bad = write("bad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 \\\n 2 \\\n 9\nf 1 2 3\n");
  const InputError e = import_error(bad);
  EXPECT_EQ(e.line(), 4);
  EXPECT_NE(e.message().find("vertex index out of range"), std::string::npos) << e.what();
}

// A triangle 1e13 long and 1 wide is thinner than the 1e-12 of its size the checks resolve: skipped, and the warning
// says so (it said "all its vertices on one line", which they are not).
TEST_F(SceneImport, import_face_too_thin_to_resolve_says_so) {
  const Scene scene = import_obj(write("thin.obj", "v 0 0 0\nv 1e9 0 0\nv 1e9 1e9 0\nv 0 0 1e13\nv 0 1 0\n"
                                                   "f 1 2 3\nf 1 4 5\n"));
  EXPECT_EQ(scene.faces.size(), 1u);
  EXPECT_TRUE(has_warning(scene, "thin.obj:7: face of zero area or too thin to resolve skipped: its vertices lie on "
                                 "one line to within 1e-12 of its size (1e+13)"))
      << scene.warnings.front();
}

// A face written twice counts once (its area, a lamp's flux), with a warning naming both lines; the same
// vertices the other way round are the back of a two-sided panel and stay. A material defined twice warns too.
TEST_F(SceneImport, import_repeated_faces_are_skipped_and_repeated_materials_warn) {
  write("s.mtl", std::string(kSquareMtl) + "newmtl lamp\nKd 0.1 0.1 0.1\nKe 9 9 9\n");
  const std::string obj = write("twice.obj",
                                "mtllib s.mtl\n"
                                "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                "v 0 0 2\nv 0 1 2\nv 1 1 2\nv 1 0 2\n"
                                "g floor\nusemtl grey\nf 1 2 3 4\nf 1 4 3 2\n"  // the floor, and its back
                                "g light\nusemtl lamp\nf 5 6 7 8\nf 7 8 5 6\n");  // the lamp, twice
  const Scene scene = import_obj(obj);
  EXPECT_DOUBLE_EQ(scene.total_area(), 3.0);
  EXPECT_EQ(scene.groups[*scene.find_group("floor")].surfaces.size(), 2u);  // front and back
  ASSERT_EQ(scene.warnings.size(), 2u);
  EXPECT_NE(scene.warnings[0].find("s.mtl:6: material 'lamp' is defined again (first at"), std::string::npos)
      << scene.warnings[0];
  EXPECT_NE(scene.warnings[1].find("twice.obj:17: face repeats the face on line 16"), std::string::npos)
      << scene.warnings[1];
  const Surface& light = scene.surfaces[scene.groups[*scene.find_group("light")].surfaces[0]];
  EXPECT_EQ(scene.materials[light.material].emission, Rgb(4.0));  // the first definition
  // The ignored definition is no material of the scene (it was listed as a third, with the first one's values).
  EXPECT_EQ(scene.materials.size(), 2u);

  // The same polygon in another group or with another material is another object: kept.
  const Scene two = import_obj(write("shade.obj", "mtllib s.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                                  "g shade\nusemtl grey\nf 1 2 3 4\ng lamp\nusemtl lamp\nf 1 2 3 4\n"));
  EXPECT_EQ(two.faces.size(), 2u);
  EXPECT_EQ(two.groups.size(), 2u);
}

// Old Mac files end lines with CR alone; a material name with a space defines the whole name in MTL but is one
// word to usemtl (tinyobjloader's reading, which the importer follows), so it warns.
TEST_F(SceneImport, import_cr_line_ends_and_material_names_with_spaces) {
  const std::string obj = write("mac.obj", "v 0 0 0\rv 1 0 0\rv 1 1 0\rf 1 2 3 # lid\rv 0 0 1\rf 1 2 4\r");
  const Scene mac = import_obj(obj);
  EXPECT_EQ(mac.faces.size(), 2u);
  write("wood.mtl", "newmtl Wood Dark\nKd 0.2 0.1 0.05\n");
  const Scene wood = import_obj(write("wood.obj", "mtllib wood.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nusemtl Wood Dark\nf 1 2 3\n"));
  const auto said = std::find_if(wood.warnings.begin(), wood.warnings.end(), [](const std::string& w) {
    return w.find("wood.obj:5: material name with a space") != std::string::npos;
  });
  EXPECT_NE(said, wood.warnings.end());
}

// A face smaller than kSmallestFace (1e-5) of the scene's diagonal is below what the meshing resolves: it welds
// vertices closer than 1e-6 of the diagonal, and CGAL's mesher crashed on what was left of a face 1 across in a
// scene 1e6 across (a reviewer's fuzzing: `aarad solve` ended in a segmentation fault). It is skipped with a warning
// naming its line; where nothing is left, the error names the first.
TEST_F(SceneImport, import_skips_faces_too_small_against_the_scene) {
  const std::string pentagon = "v 0 0 0\nv 0 0 1\nv 1 0 1\nv 1 0 0\nv 0.5 0 -0.5\n";
  const Scene scene = import_obj(write("speck.obj", pentagon + "v -1e6 1 -1e6\nv 1e6 1 -1e6\nv 1e6 1 1e6\n"
                                                               "v -1e6 1 1e6\nf 1 2 3 4 5\nf 6 9 8 7\n"));
  ASSERT_EQ(scene.faces.size(), 1u);
  EXPECT_EQ(scene.faces[0].source_line, 11);
  EXPECT_TRUE(has_warning(scene, "speck.obj:10: face too small against the scene"));
  const InputError e = import_error(write("specks.obj", pentagon + "v 0 1e6 0\nv 1 1e6 0\nv 0 1e6 1\nf 1 2 3 4 5\n"
                                                                   "f 6 7 8\n"));
  EXPECT_NE(e.message().find("specks.obj:9: face too small against the scene"), std::string::npos) << e.message();
}

// An MTL file with no newmtl line (empty, or not an MTL file) defines no material: tinyobjloader still hands back
// one without a name, and the importer warned that "material ''" had no Kd (a reviewer's fuzzing).
TEST_F(SceneImport, import_an_mtl_file_without_materials_adds_none) {
  write("empty.mtl", "");
  write("garbage.mtl", "this is not\na material file\n");
  for (const char* library : {"empty.mtl", "garbage.mtl"}) {
    const Scene scene = import_obj(write("plain.obj", std::string("mtllib ") + library +
                                                          "\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"));
    for (const std::string& w : scene.warnings) EXPECT_EQ(w.find("material ''"), std::string::npos) << w;
    ASSERT_EQ(scene.materials.size(), 1u) << library;
    EXPECT_EQ(scene.materials[0].name, "default");
  }
}

// A CR alone in a file of LF line ends is a line end too, as the reader takes it: a comment with a CR in it
// ended there, what followed was read as a statement, and the line count, which took the CR for part of the line,
// gave up: every message said line 0. A vertical tab or form feed is a blank, as for the reader: the line count
// took "f 1\v2 3 4" for a face of 3 vertices and the reader for one of 4, and the error said to split the face
// into faces of at most 255. Found by a reviewer's fuzzing.
TEST_F(SceneImport, import_stray_line_ends_and_blanks_count_as_the_reader_takes_them) {
  const InputError e = import_error(write("stray.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n# note\rf 1 2 9\r\n"));
  EXPECT_EQ(e.line(), 6);
  EXPECT_NE(e.message().find("out of range"), std::string::npos) << e.message();
  const Scene scene = import_obj(write("mixed.obj", "v 0 0 0\r\nv 1 0 0\rv 0 1 0\nv 1 1 0\r\nf 1 2 3\rf 2 4 3\n"));
  ASSERT_EQ(scene.faces.size(), 2u);
  EXPECT_EQ(scene.faces[0].source_line, 5);
  EXPECT_EQ(scene.faces[1].source_line, 6);
  // A vertical tab or a form feed between two vertex references is a blank, as for the reader.
  const Scene blanks = import_obj(write("blanks.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1\v2\f3 4\n"));
  ASSERT_EQ(blanks.faces.size(), 1u);
  EXPECT_EQ(blanks.faces[0].vertices.size(), 4u);
  EXPECT_EQ(blanks.faces[0].source_line, 5);
}

// `fo`, an older spelling of `f`, is a face like any other; tinyobjloader passes over it, and its faces vanished.
TEST_F(SceneImport, import_fo_statements_are_read_as_faces) {
  write("s.mtl", kSquareMtl);
  const std::string obj = write("fo.obj", "mtllib s.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                          "v 0.4 0.4 1\nv 0.6 0.4 1\nv 0.6 0.6 1\nv 0.4 0.6 1\n"
                                          "g floor\nusemtl grey\n  fo 1 2 3 4 # the floor\n"
                                          "g lamp\nusemtl lamp\nf 8 7 6 5\n");
  const Scene scene = import_obj(obj);
  EXPECT_TRUE(scene.warnings.empty()) << scene.warnings.front();
  ASSERT_EQ(scene.faces.size(), 2u);
  EXPECT_EQ(scene.groups[scene.faces[0].group].name, "floor");
  EXPECT_EQ(scene.faces[0].source_line, 12);
  EXPECT_EQ(scene.faces[0].vertices, (std::vector<Vec3>{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}));
  EXPECT_EQ(scene.faces[1].source_line, 15);
}

// A statement OBJ does not have (a typo, or another format) is named with its first line and how many more.
TEST_F(SceneImport, import_unknown_statements_warn_once_with_their_first_line) {
  const std::string obj = write("typo.obj", "v 0 0 0\nvv 1 0 0\nv 1 0 0\nvt 0 0\nv 1 1 0\nvv 2 2 2\ns off\nf 1 2 3\n");
  const Scene scene = import_obj(obj);
  const auto said = std::find_if(scene.warnings.begin(), scene.warnings.end(), [](const std::string& w) {
    return w.find("typo.obj:2: 'vv' is not an OBJ statement; this line and 1 more are ignored") != std::string::npos;
  });
  EXPECT_NE(said, scene.warnings.end());
  for (const std::string& w : scene.warnings) {
    EXPECT_EQ(w.find("'vt'"), std::string::npos) << w;
    EXPECT_EQ(w.find("'s'"), std::string::npos) << w;
  }
  // Several unknown statements warn in the order of their first lines, not of their names.
  const Scene two = import_obj(write("typos.obj", "v 0 0 0\nzz 1\nv 1 0 0\naa 2\nv 1 1 0\nf 1 2 3\n"));
  ASSERT_GE(two.warnings.size(), 2u);
  EXPECT_NE(two.warnings[0].find("typos.obj:2: 'zz'"), std::string::npos) << two.warnings[0];
  EXPECT_NE(two.warnings[1].find("typos.obj:4: 'aa'"), std::string::npos) << two.warnings[1];
}

// Kd and Ke take one or three numbers: more are not silently dropped (a typo of a fourth channel).
TEST_F(SceneImport, import_colour_with_more_than_three_numbers_warns_with_its_line) {
  write("four.mtl", "newmtl grey\nKd 0.7 0.7 0.7 0.9\n");
  const std::string obj = write("four.obj", "mtllib four.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nusemtl grey\nf 1 2 3\n");
  const Scene scene = import_obj(obj);
  EXPECT_TRUE(has_warning(scene, "four.mtl:2: 'Kd' takes one or three numbers; the 1 after the third ('0.9' first) "
                                 "are ignored"))
      << scene.warnings.front();
  EXPECT_EQ(scene.materials[scene.faces[0].material].reflectance, Rgb(0.7));
}

TEST_F(SceneImport, import_colour_that_is_not_one_or_three_numbers_is_error_with_mtl_line) {
  const std::string obj = write("colour.obj", "mtllib colour.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nusemtl grey\nf 1 2 3\n");
  for (const std::string kd : {"0.5 abc 0.5", "0.5 0.5", ""}) {
    const std::string mtl = write("colour.mtl", "# materials\n\nnewmtl grey\nKd " + kd + "\n");
    const InputError e = import_error(obj);
    EXPECT_EQ(e.file(), mtl) << kd;
    EXPECT_EQ(e.line(), 4) << kd;
    EXPECT_NE(e.message().find("one or three numbers"), std::string::npos) << kd << ": " << e.message();
  }
}

TEST_F(SceneImport, import_camera_comment_is_read_back) {
  const std::string obj = write("cam.obj",
                                "# aarad camera: eye 1 2 3 forward 0 0 2 up 0 1 0 vertical_fov 0.5\n"
                                "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n");
  const Scene scene = import_obj(obj);
  ASSERT_TRUE(scene.camera.has_value());
  EXPECT_EQ(scene.camera->eye, Vec3(1, 2, 3));
  EXPECT_EQ(scene.camera->forward, Vec3(0, 0, 1));  // normalised
  EXPECT_EQ(scene.camera->vertical_fov, 0.5);
}

TEST_F(SceneImport, import_meshing_comment_is_read_back_and_a_bad_one_warns) {
  const std::string faces = "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n";
  const Scene scene = import_obj(write("mesh.obj", "# aarad meshing: patch_size 0.5 element_size 0.25 min_area 1e-3\n" + faces));
  ASSERT_TRUE(scene.meshing.has_value());
  EXPECT_EQ(scene.meshing->patch_size, 0.5);
  EXPECT_EQ(scene.meshing->element_size, 0.25);
  EXPECT_EQ(scene.meshing->min_area, 1e-3);
  EXPECT_FALSE(import_obj(write("plain.obj", faces)).meshing.has_value());
  // In another order, and with one left out (0: from the scene's size).
  const Scene some = import_obj(write("some.obj", "# aarad meshing: min_area 2e-3 patch_size 0.4\n" + faces));
  ASSERT_TRUE(some.meshing.has_value());
  EXPECT_EQ(some.meshing->patch_size, 0.4);
  EXPECT_EQ(some.meshing->element_size, 0.0);
  EXPECT_EQ(some.meshing->min_area, 2e-3);
  // The warning says what is wrong.
  const std::vector<std::pair<std::string, std::string>> bad{
      {"patch_size 0.5 element_size -1 min_area 1e-3", "(element_size '-1' is not a finite number >= 0)"},
      {"patch_size 0.5 patch_size 0.25", "(patch_size is given twice)"},
      {"size 1 2 3 4 5 6", "('size' is not one of its names)"},
      {"patch_size", "(patch_size has no number after it)"},
      {"", "(it gives no size)"}};
  for (const auto& [words, why] : bad) EXPECT_FALSE(import_refused_comment("meshing", words, why).meshing) << words;
}

TEST_F(SceneImport, import_camera_comment_that_cannot_be_used_warns_and_says_why) {
  const std::string faces = "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n";
  const std::vector<std::pair<std::string, std::string>> bad{
      {"eye 0 0 0 forward 0 0 0 up 0 1 0 vertical_fov 1", "(forward is the zero vector)"},
      {"eye 0 0 0 forward 0 0 1 up 0 0 0 vertical_fov 1", "(up is the zero vector)"},
      {"eye 0 0 0 forward 0 0 1 up 0 0 -3 vertical_fov 1", "(up is parallel to forward)"},
      {"eye 0 0 0 forward 0 0 1 up 0 1 0 vertical_fov 3.2", "(vertical_fov 3.2 is not between 0 and pi radians)"},
      {"eye 0 0 0 forward 0 0 1 up 0 1 0 vertical_fov 0", "(vertical_fov 0 is not between 0 and pi radians)"},
      {"eye nan 0 0 forward 0 0 1 up 0 1 0 vertical_fov 1", "('nan' is not a finite number)"},
      {"eye 0 0 0 forward 1e300 1e300 0 up 0 1 0 vertical_fov 1", "(forward is too long for a double)"},
      {"eye 0 0 0 forward 0 0 1 up 0 1 0", "(its words are not in the order below)"}};
  for (const auto& [words, why] : bad) EXPECT_FALSE(import_refused_comment("camera", words, why).camera) << words;
  // Short or long vectors that are not parallel are a camera: the test of parallel vectors is relative.
  const Scene tiny = import_obj(write("tiny.obj", "# aarad camera: eye 0 0 0 forward 0 0 1e-12 up 0 1e-12 1e-11 "
                                                  "vertical_fov 1\n" + faces));
  ASSERT_TRUE(tiny.camera.has_value());
  EXPECT_NEAR(tiny.camera->up.y, 1.0, 1e-15);
  EXPECT_NEAR(tiny.camera->up.z, 0.0, 1e-15);
}

TEST(SceneModel, scene_build_surfaces_tolerance_is_relative_to_scene_size) {
  // The same pair of nearly coplanar squares 1e-4 apart, in a scene 1 across and in one 1e3 across:
  // distinct surfaces in the first (1e-4 > 1e-6 x diagonal 2.45), one in the second (1e-4 < 1e-6 x 1000).
  for (const double size : {1.0, 1e3}) {
    Scene scene;
    const std::uint32_t g = scene.add_group("g");
    const std::uint32_t m = scene.add_material({"m", Rgb(0.5), Rgb(0.0)});
    scene.add_face(g, m, {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}});
    scene.add_face(g, m, {{1, 0, 1e-4}, {2, 0, 1e-4}, {2, 1, 1e-4}, {1, 1, 1e-4}});
    scene.add_face(g, m, {{0, 0, size}, {0, 0.001, size}, {0.001, 0, size}});  // sets the scene's size
    scene.build_surfaces();
    EXPECT_EQ(scene.groups[g].surfaces.size(), size == 1.0 ? 3u : 2u) << size;
  }
}

TEST(SceneModel, scene_fitted_camera_sees_the_whole_bounds) {
  const Scene scene = make_furnace();
  for (const double aspect : {0.5, 1.0, 2.0}) {
    const Camera c = scene.fitted_camera(aspect);
    EXPECT_NEAR(glm::length(c.forward), 1.0, 1e-12);
    EXPECT_NEAR(glm::dot(c.forward, c.up), 0.0, 1e-12);
    const Vec3 right = glm::cross(c.forward, c.up);
    const double tan_v = std::tan(0.5 * c.vertical_fov), tan_h = aspect * tan_v;
    const Vec3 lo = scene.bounds_min(), hi = scene.bounds_max();
    for (int corner = 0; corner < 8; ++corner) {
      const Vec3 p((corner & 1) ? hi.x : lo.x, (corner & 2) ? hi.y : lo.y, (corner & 4) ? hi.z : lo.z);
      const Vec3 d = p - c.eye;
      const double depth = glm::dot(d, c.forward);
      ASSERT_GT(depth, 0.0);
      EXPECT_LE(std::abs(glm::dot(d, c.up)) / depth, tan_v * (1 + 1e-12)) << aspect;
      EXPECT_LE(std::abs(glm::dot(d, right)) / depth, tan_h * (1 + 1e-12)) << aspect;
    }
  }
}

// The renderer culls back faces: a scene without a camera is seen from the side that shows its front faces (a
// reviewer's wall facing +z, and a wall in the plane x = 0, rendered black from the conventional -z side), a closed
// room keeps the conventional view, and the camera's distance follows the scene's size however small (a scene
// 1e-12 across was framed as if it were 1e-9 across, a dot in a black image).
TEST(SceneModel, scene_fitted_camera_looks_at_the_front_faces) {
  const auto one_quad = [](double size, const Vec3& u, const Vec3& v) {
    Scene scene;
    scene.name = "quad";
    const std::uint32_t g = scene.add_group("wall");
    const std::uint32_t m = scene.add_material({"white", Rgb(0.5), Rgb(1.0)});
    scene.add_face(g, m, {Vec3(0.0), size * u, size * (u + v), size * v});  // front normal u x v
    scene.build_surfaces();
    return scene;
  };
  const Vec3 x(1, 0, 0), y(0, 1, 0), z(0, 0, 1);
  for (const auto& [u, v] : {std::pair{x, y}, std::pair{y, z}, std::pair{z, x}, std::pair{y, x}}) {
    const Vec3 front = glm::cross(u, v);
    const Camera c = one_quad(1.0, u, v).fitted_camera(1.0);
    EXPECT_LT(glm::dot(c.forward, front), -0.9) << front.x << " " << front.y << " " << front.z;
  }
  const Camera room = make_furnace().fitted_camera(1.0);  // closed, facing inwards
  EXPECT_NEAR(glm::dot(room.forward, glm::normalize(Vec3(0.0, -0.2, 1.0))), 1.0, 1e-12);
  const Camera unit = one_quad(1.0, x, y).fitted_camera(1.0);
  for (const double size : {1e-12, 1e-45, 1e12}) {
    const Camera c = one_quad(size, x, y).fitted_camera(1.0);
    EXPECT_NEAR(glm::length(c.eye - Vec3(0.5 * size, 0.5 * size, 0.0)) / size,
                glm::length(unit.eye - Vec3(0.5, 0.5, 0.0)), 1e-9)
        << size;
  }
}

TEST(SceneModel, scene_validate_rejects_bad_materials) {
  Scene scene;
  scene.name = "handmade";
  const std::uint32_t g = scene.add_group("g");
  const std::uint32_t m = scene.add_material({"mirror", Rgb(1.0), Rgb(0.0)});
  scene.add_face(g, m, {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}});
  scene.build_surfaces();
  EXPECT_THROW(scene.validate(), InputError);
  scene.materials[m].reflectance = Rgb(0.9);
  EXPECT_NO_THROW(scene.validate());
  scene.materials[m].emission = Rgb(1.0, -1.0, 0.0);
  EXPECT_THROW(scene.validate(), InputError);
  // 0, or at least 1e-100: below, doubles lose the digits of the light (kMinEmission, kMinReflectance).
  scene.materials[m].emission = Rgb(1e-100, 0.0, 1.0);
  scene.materials[m].reflectance = Rgb(1e-100, 0.0, 0.5);
  EXPECT_NO_THROW(scene.validate());
  scene.materials[m].emission = Rgb(1e-101, 0.0, 1.0);
  EXPECT_THROW(scene.validate(), InputError);
  scene.materials[m].emission = Rgb(1.0);
  scene.materials[m].reflectance = Rgb(0.5, 1e-320, 0.5);
  EXPECT_THROW(scene.validate(), InputError);
}

// A unit box 1e13 from the origin solved 6 % off, and 1e15 out the hemicube found its faces turned round: a scene
// farther from the origin than kMaxRemoteness (4.5e8) of its diagonals is refused with the line of a face out
// there; 1e8 out (5.8e7 diagonals) it is accepted.
TEST_F(SceneImport, import_refuses_a_scene_too_far_from_the_origin_for_its_size) {
  write("s.mtl", kSquareMtl);
  for (const double offset : {1e8, 1e12}) {
    std::string text = "mtllib s.mtl\nusemtl lamp\n";
    for (const auto& [x, y, z] : {std::array{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}})
      text += "v " + std::to_string(offset + x) + " " + std::to_string(offset + y) + " " + std::to_string(offset + z) +
              "\n";
    text += "f 1 2 3 4\nf 5 6 2 1\n";
    const std::string obj = write("far.obj", text);
    if (offset == 1e8) {
      EXPECT_NO_THROW(import_obj(obj));
      continue;
    }
    try {
      import_obj(obj);
      ADD_FAILURE() << "a unit scene 1e12 from the origin was accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), obj);
      EXPECT_EQ(e.line(), 9);
      EXPECT_NE(e.message().find("face 0 (group 'far') lies too far from the origin for the scene's size: a "
                                 "coordinate of 1e+12 where the scene is 1.73 across (5.77e+11 times; at most "
                                 "4.5e+08)"),
                std::string::npos)
          << e.message();
    }
  }
}

// A face in code smaller than kSmallestFace of the scene's diagonal is an error, which the mesher crashed on.
TEST(SceneModel, scene_validate_rejects_faces_too_small_against_the_scene) {
  Scene scene;
  scene.name = "handmade";
  const std::uint32_t g = scene.add_group("g");
  const std::uint32_t m = scene.add_material({"grey", Rgb(0.5), Rgb(1.0)});
  scene.add_face(g, m, {{0, 0, 0}, {1e6, 0, 0}, {1e6, 1e6, 0}});
  scene.add_face(g, m, {{0, 0, 1}, {1, 0, 1}, {1, 1, 1}});
  scene.build_surfaces();
  try {
    scene.validate();
    ADD_FAILURE() << "a face 1 across in a scene 1.4e6 across passed";
  } catch (const InputError& e) {
    EXPECT_NE(e.message().find("face 1 (group 'g') is smaller than 1e-5 of the scene's diagonal"), std::string::npos)
        << e.message();
  }
  scene.faces[1].vertices = {{0, 0, 1}, {100, 0, 1}, {100, 100, 1}};
  scene.build_surfaces();
  EXPECT_NO_THROW(scene.validate());
}

// A scene built in code is checked as an imported one is (core/face_check.h): a face with its vertices on one
// line and a bow-tie used to pass and crash the initial meshing (CGAL's refine_Delaunay_mesh_2).
TEST(SceneModel, scene_validate_rejects_zero_area_and_self_intersecting_faces) {
  const auto scene_with = [](std::vector<Vec3> face) {
    Scene scene;
    scene.name = "handmade";
    const std::uint32_t light = scene.add_group("light");
    const std::uint32_t floor = scene.add_group("floor");
    const std::uint32_t m = scene.add_material({"lamp", Rgb(0.5), Rgb(1.0)});
    scene.add_face(light, m, {{0, 1, 0}, {1, 1, 0}, {1, 1, 1}, {0, 1, 1}});
    scene.add_face(floor, m, std::move(face));
    scene.build_surfaces();
    return scene;
  };
  const auto message = [](const Scene& scene) {
    try {
      scene.validate();
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), "handmade");
      return e.message();
    }
    return std::string("no InputError");
  };
  const std::string collinear = message(scene_with({{0, 0, 0}, {0.5, 0, 0.5}, {1, 0, 1}}));
  EXPECT_NE(collinear.find("face 1 (group 'floor') has zero area or is too thin to resolve: its vertices lie on one "
                           "line"),
            std::string::npos)
      << collinear;
  const std::string bowtie = message(scene_with({{0, 0, 0}, {1, 0, 1}, {1, 0, 0}, {0, 0, 1}}));
  EXPECT_NE(bowtie.find("face 1 (group 'floor') intersects itself"), std::string::npos) << bowtie;
  const std::string not_finite = message(scene_with({{0, 0, 0}, {1, 0, std::nan("")}, {1, 0, 1}}));
  EXPECT_NE(not_finite.find("face 1 (group 'floor') has a vertex that is not finite"), std::string::npos) << not_finite;
  const std::string two = message(scene_with({{0, 0, 0}, {1, 0, 0}, {0, 0, 0}}));
  EXPECT_NE(two.find("face 1 (group 'floor') has fewer than three distinct vertices"), std::string::npos) << two;
  // A repeated vertex is dropped as the importer drops it, and the square is fine.
  EXPECT_NO_THROW(scene_with({{0, 0, 0}, {0, 0, 1}, {0, 0, 1}, {1, 0, 1}, {1, 0, 0}}).validate());
}

// ---- The Cornell box from data/ --------------------------------------------------------------------------

TEST(SceneImportCornell, import_cornell_obj_matches_builtin) {
  const std::string path = std::string(AARAD_SOURCE_DIR) + "/data/scenes/cornell.obj";
  const Scene imported = import_obj(path);
  const Scene builtin = make_cornell_box();
  EXPECT_TRUE(imported.warnings.empty()) << imported.warnings.front();
  ASSERT_EQ(imported.groups.size(), builtin.groups.size());
  ASSERT_EQ(imported.surfaces.size(), builtin.surfaces.size());
  ASSERT_EQ(imported.faces.size(), builtin.faces.size());
  for (std::size_t g = 0; g < builtin.groups.size(); ++g) {
    EXPECT_EQ(imported.groups[g].name, builtin.groups[g].name);
    EXPECT_EQ(imported.groups[g].faces.size(), builtin.groups[g].faces.size());
    EXPECT_EQ(imported.groups[g].surfaces.size(), builtin.groups[g].surfaces.size());
  }
  for (std::size_t s = 0; s < builtin.surfaces.size(); ++s) {
    const Surface& a = imported.surfaces[s];
    const Surface& b = builtin.surfaces[s];
    EXPECT_EQ(imported.groups[a.group].name, builtin.groups[b.group].name);
    EXPECT_EQ(a.area, b.area) << s;  // coordinates round-trip exactly
    EXPECT_EQ(a.plane.normal, b.plane.normal) << s;
    EXPECT_EQ(imported.materials[a.material].name, builtin.materials[b.material].name);
    EXPECT_EQ(imported.materials[a.material].reflectance, builtin.materials[b.material].reflectance);
    EXPECT_EQ(imported.materials[a.material].emission, builtin.materials[b.material].emission);
  }
  ASSERT_TRUE(imported.camera.has_value());
  EXPECT_EQ(imported.camera->eye, builtin.camera->eye);
  EXPECT_EQ(imported.camera->vertical_fov, builtin.camera->vertical_fov);
  // The meshing sizes come along, so the copy solves as the built-in.
  ASSERT_TRUE(imported.meshing.has_value());
  ASSERT_TRUE(builtin.meshing.has_value());
  EXPECT_EQ(imported.meshing->patch_size, builtin.meshing->patch_size);
  EXPECT_EQ(imported.meshing->element_size, builtin.meshing->element_size);
  EXPECT_EQ(imported.meshing->min_area, builtin.meshing->min_area);
}

TEST(SceneImportCornell, scene_load_resolves_builtin_names_before_paths) {
  EXPECT_EQ(load_scene("cornell").name, "cornell");
  EXPECT_EQ(load_scene("furnace").name, "furnace");
  const std::string path = std::string(AARAD_SOURCE_DIR) + "/data/scenes/furnace.obj";
  EXPECT_EQ(load_scene(path).name, path);
  try {
    load_scene("cornel");
    ADD_FAILURE() << "no error for an unknown name";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "cornel");
    EXPECT_NE(e.message().find("cornell, office, furnace"), std::string::npos);
  }
}

// check_face's bounds (kMaxCoordinate 1e50 in magnitude, either sign; kMinFaceSize 1e-50 of bounding-box diagonal),
// its normal (Newell's, counter-clockwise seen from its tip) and its deviation from planarity.
TEST(FaceCheck, BoundsNormalAndDeviation) {
  const auto square = [](double x0, double side) {
    return std::vector<Vec3>{{x0, 0, 0}, {x0 + side, 0, 0}, {x0 + side, side, 0}, {x0, side, 0}};
  };
  EXPECT_EQ(check_face(square(0.0, 1e50)).problem, FaceProblem::kNone);
  EXPECT_EQ(check_face(square(0.0, 2e50)).problem, FaceProblem::kTooLarge);
  EXPECT_EQ(check_face(square(-2e50, 1e50)).problem, FaceProblem::kTooLarge);  // -2e50 .. -1e50
  EXPECT_EQ(check_face(square(0.0, 1e-50)).problem, FaceProblem::kNone);        // diagonal 1.41e-50
  EXPECT_EQ(check_face(square(0.0, 3e-51)).problem, FaceProblem::kTooSmall);    // diagonal 4.2e-51
  const FaceCheck unit = check_face(square(0.0, 1.0));
  EXPECT_EQ(unit.problem, FaceProblem::kNone);
  EXPECT_EQ(unit.normal, Vec3(0, 0, 1));
  EXPECT_EQ(unit.size, std::sqrt(2.0));
  EXPECT_EQ(unit.deviation, 0.0);
  // A house whose roof apex (0.5, 1.5) lies 0.004 below the rest: Newell's normal is (0, 0.004, 2.5) (unnormalised),
  // the mean (0.5, 0.7, -0.0008), and the apex lies (0.004 x 0.8 - 2.5 x 0.0032) / 2.5 = -0.00192 from that plane,
  // farther than any other corner (at most 0.00128, on the other side).
  const FaceCheck bent =
      check_face(std::vector<Vec3>{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0.5, 1.5, -0.004}, {0, 1, 0}});
  EXPECT_EQ(bent.problem, FaceProblem::kNone);
  EXPECT_NEAR(bent.deviation, 0.00192, 1e-8);
}

// The bounds hold on every axis (a coordinate beyond 1e50 in z alone is too large), and the size is the bounding
// box's diagonal wherever the face lies: a unit square moved far from the origin keeps the size sqrt 2, and a square
// of side 1e-3 a million units out is a small face, not a line (its twice-area 1e-6 against 1e-12 of its squared
// size 2e-6, not of the squared distance 1e12).
TEST(FaceCheck, BoundsHoldOnEveryAxisAndTheSizeIsTheBoxDiagonalWhereverTheFaceLies) {
  const auto square = [](const Vec3& corner, double side) {
    return std::vector<Vec3>{corner, corner + Vec3(side, 0, 0), corner + Vec3(side, side, 0), corner + Vec3(0, side, 0)};
  };
  EXPECT_EQ(check_face(square(Vec3(0, 0, 2e50), 1.0)).problem, FaceProblem::kTooLarge);
  EXPECT_EQ(check_face(square(Vec3(0, 0, -2e50), 1.0)).problem, FaceProblem::kTooLarge);
  EXPECT_EQ(check_face(square(Vec3(0, 0, 1e50), 1.0)).problem, FaceProblem::kNone);
  const FaceCheck moved = check_face(square(Vec3(1e8, -1e8, 5.0), 1.0));
  EXPECT_EQ(moved.problem, FaceProblem::kNone);
  EXPECT_EQ(moved.size, std::sqrt(2.0));  // 1e8 + 1 - 1e8 is exactly 1
  const FaceCheck small = check_face(square(Vec3(1e6, 0, 0), 1e-3));
  EXPECT_EQ(small.problem, FaceProblem::kNone);
  EXPECT_NEAR(small.size, 1e-3 * std::sqrt(2.0), 1e-9);  // 1e6 + 1e-3 is 1e-3 within an ulp of 1e6, 1.2e-10
  EXPECT_EQ(small.normal, Vec3(0, 0, 1));
}

// A face that lists its first vertex again at its end (f 1 2 3 4 1) is the face without the repeat, not one with a
// zero-length closing edge (which is_simple would call self-intersecting).
TEST(FaceCheck, AFirstVertexRepeatedAtTheEndIsDropped) {
  const FaceCheck closed = check_face(std::vector<Vec3>{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 0}});
  EXPECT_EQ(closed.problem, FaceProblem::kNone);
  EXPECT_EQ(closed.vertices, (std::vector<Vec3>{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}));
  EXPECT_EQ(closed.normal, Vec3(0, 0, 1));
}

// A chevron (0, 0), (1, 1 - d), (2, 0), (1, 1) is simple and spans a triangle of area 1, so it is neither a line nor
// self-intersecting, but it encloses only the sliver of area d between its two upper edges. With d = 1e-13, far below
// 1e-12 of its squared size 5, it is of zero area; with d = 1e-3 it is a face.
TEST(FaceCheck, AThinChevronEnclosingNoAreaIsOfZeroArea) {
  const auto chevron = [](double d) {
    return std::vector<Vec3>{{0, 0, 0}, {1, 1 - d, 0}, {2, 0, 0}, {1, 1, 0}};
  };
  EXPECT_EQ(check_face(chevron(1e-13)).problem, FaceProblem::kZeroArea);
  const FaceCheck face = check_face(chevron(1e-3));
  EXPECT_EQ(face.problem, FaceProblem::kNone);
  EXPECT_NEAR(area(face.vertices), 1e-3, 1e-15);
  EXPECT_EQ(face.normal, Vec3(0, 0, 1));
}

// What obj_text and mtl_text write for a scene: comment lines ("#" alone for an empty one), one `v` per distinct
// position (-0 is 0, and written as 0), a `usemtl` where the material changes, no `o` for a group without faces, and
// material names as one word each: "unnamed" for an empty name, blanks and tabs as underscores, and "_2" for a name
// an earlier material took.
TEST(ObjExport, TextOfASmallScene) {
  Scene scene;
  const auto nameless = scene.add_material({"", Rgb(0.5), Rgb(0.0)});
  const auto tabbed = scene.add_material({"a\tb", Rgb(0.25), Rgb(1.0)});
  scene.add_material({"red paint", Rgb(0.5), Rgb(0.0)});
  scene.add_material({"red_paint", Rgb(0.5), Rgb(0.0)});
  const auto floor = scene.add_group("floor");
  scene.add_group("empty");
  scene.add_face(floor, nameless, {{-0.0, 0, -0.0}, {1, 0, 0}, {1, 1, 0}});
  scene.add_face(floor, tabbed, {{0, 0, 0}, {1, 1, 0}, {0, 1, 0}});
  EXPECT_EQ(obj_text(scene, "small.mtl", "first\n\nthird"),
            "# first\n#\n# third\nmtllib small.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\no floor\nusemtl unnamed\n"
            "f 1 2 3\nusemtl a_b\nf 1 3 4\n");
  EXPECT_EQ(mtl_text(scene),
            "newmtl unnamed\nKd 0.5 0.5 0.5\nKe 0 0 0\nnewmtl a_b\nKd 0.25 0.25 0.25\nKe 1 1 1\n"
            "newmtl red_paint\nKd 0.5 0.5 0.5\nKe 0 0 0\nnewmtl red_paint_2\nKd 0.5 0.5 0.5\nKe 0 0 0\n");
}

// A triangle 1.6 long and 7e-11 wide (rotated, 9 digits) is narrower than the meshing's weld distance (1e-6 of the
// diagonal): skipped with a warning naming its line, as the faces too small are. Kept, it was a surface of its own
// whose grid of patches had children 6.7e-8 off their parents' planes.
TEST_F(SceneImport, import_skips_faces_narrower_than_the_weld_distance) {
  const Scene scene = import_obj(write("sliver.obj",
                                       "v -0.887548019 -1.2641943 0.407461708\nv -0.20628168 -0.293820862 0.0947012262\n"
                                       "v 0 0 0\nf 1 2 3\n"
                                       "v -0.507823734 -2.43165219 3.34620316\nv -0.890774166 -1.57353266 5.17445575\n"
                                       "v 0.459412972 -2.3177186 5.80656493\nv 0.842363403 -3.17583813 3.97831235\n"
                                       "f 4 5 6 7\n"));
  ASSERT_EQ(scene.faces.size(), 1u);
  EXPECT_EQ(scene.faces[0].source_line, 9);
  EXPECT_TRUE(has_warning(scene, "sliver.obj:4: face too narrow against the scene"));
}

}  // namespace
}  // namespace aarad
