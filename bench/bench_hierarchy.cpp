// Hierarchy refinement cost: the Cornell box refined uniformly (breadth first) and adaptively (towards the
// edges of its faces, where radiosity changes fast: a leaf is split when its centroid lies within
// 0.75 sqrt(area) of a face edge; with balance on) to 10^4, 10^5 and 10^6 leaves.
// Reported: time per split (thread CPU time of split() calls only, balance splits included in the count) and bytes per leaf
// (heap growth from mallinfo2, and the hierarchy's own container count). Goals (issue 4): time per split
// within 1.5x across the sizes, under 1 KiB per leaf. Also: building the surfaces and the hierarchy of a scene of
// many surfaces (BM_BuildTerrain) and of a tessellated ball (BM_BuildSurfacesBall), and the check for faces lying
// on one another in a scene of many coplanar surfaces (BM_CoplanarOverlapsCubes) and in the shapes it was once
// quadratic on (BM_CoplanarOverlapsDecals, BM_CoplanarOverlapsPlanks); meshing and checking a floor with many
// holes (BM_FloorWithHoles); meshing a floor cut along the feet of many posts standing on it
// (BM_FloorWithStandingPosts).
#include "aarad/core/builtin_scenes.h"
#include "aarad/mesh/hierarchy.h"
#include "aarad/mesh/invariants.h"

#include <benchmark/benchmark.h>
#include <malloc.h>

#include <cmath>
#include <ctime>
#include <deque>
#include <string>
#include <limits>

namespace {

using aarad::Vec3;
using aarad::mesh::Hierarchy;
using aarad::mesh::NodeId;

// CPU time of this thread: the machine is shared, so wall time would count other processes.
double thread_seconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// Heap in use, including blocks glibc serves by mmap (large vectors).
std::size_t heap_in_use() {
  const struct mallinfo2 info = mallinfo2();
  return info.uordblks + info.hblkhd;
}

double distance_to_segment(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 d = b - a;
  const double t = std::clamp(glm::dot(p - a, d) / glm::dot(d, d), 0.0, 1.0);
  return glm::length(a + t * d - p);
}

void refine(benchmark::State& state, bool adaptive) {
  const auto target = static_cast<std::size_t>(state.range(0));
  const aarad::Scene scene = aarad::make_cornell_box();
  std::vector<std::array<Vec3, 2>> features;  // every face edge of the scene
  for (const aarad::Face& f : scene.faces)
    for (std::size_t i = 0; i < f.vertices.size(); ++i) features.push_back({f.vertices[i], f.vertices[(i + 1) % f.vertices.size()]});
  aarad::mesh::MeshingOptions options;
  options.max_level = 40;
  options.min_area = 1e-14 * scene.diagonal() * scene.diagonal();
  options.balance = adaptive;

  for (auto _ : state) {
    const std::size_t heap_before = heap_in_use();
    Hierarchy h(scene, options);
    std::deque<NodeId> work;
    for (NodeId n : h.leaves()) work.push_back(n);
    std::size_t splits = 0;
    double seconds = 0.0;
    while (h.leaf_count() < target && !work.empty()) {
      const NodeId n = work.front();
      work.pop_front();
      if (!h.is_leaf(n)) continue;  // split by balancing meanwhile
      if (adaptive) {
        const Vec3 c = h.centroid(n);
        double nearest = std::numeric_limits<double>::infinity();
        for (const auto& e : features) nearest = std::min(nearest, distance_to_segment(c, e[0], e[1]));
        if (nearest > 0.75 * std::sqrt(h.area(n))) continue;
      }
      const double start = thread_seconds();
      const aarad::mesh::SplitResult r = h.split(n);
      seconds += thread_seconds() - start;
      if (!r.ok) continue;
      splits += 1 + r.also_split.size();
      for (NodeId c : r.children) work.push_back(c);
      for (NodeId s : r.also_split)
        for (NodeId c : h.children(s)) work.push_back(c);
    }
    const std::size_t heap_after = heap_in_use();
    state.counters["leaves"] = static_cast<double>(h.leaf_count());
    state.counters["splits"] = static_cast<double>(splits);
    state.counters["ns_per_split"] = 1e9 * seconds / static_cast<double>(splits);
    state.counters["heap_bytes_per_leaf"] = static_cast<double>(heap_after - heap_before) / static_cast<double>(h.leaf_count());
    state.counters["counted_bytes_per_leaf"] = static_cast<double>(h.memory_bytes()) / static_cast<double>(h.leaf_count());
    int deepest = 0;
    for (NodeId n = 0; n < h.node_count(); ++n) deepest = std::max(deepest, h.level(n));
    state.counters["max_level"] = deepest;
    if (h.leaf_count() < target) state.SkipWithError("refinement stopped before the target leaf count");
  }
}

void BM_RefineUniform(benchmark::State& state) { refine(state, false); }
void BM_RefineAdaptiveBalanced(benchmark::State& state) { refine(state, true); }

BENCHMARK(BM_RefineUniform)->Arg(10000)->Arg(100000)->Arg(1000000)->Iterations(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RefineAdaptiveBalanced)->Arg(10000)->Arg(100000)->Arg(1000000)->Iterations(1)->Unit(benchmark::kMillisecond);

// Scenes of many surfaces: an n x n heightfield (z = 0.3 sin(0.21 i) cos(0.17 j) over a grid of spacing 0.05) of
// 2 n^2 triangles, each in a plane of its own, so each its own surface of one group: grouping the faces into
// surfaces (Scene::build_surfaces) and the initial meshing (the Hierarchy's constructor). Both were quadratic in
// the surfaces (190 s for n = 200); the time per face should stay about the same across n.
void BM_BuildTerrain(benchmark::State& state) {
  const auto n = static_cast<int>(state.range(0));
  aarad::Scene scene;
  scene.name = "terrain";
  const std::uint32_t ground = scene.add_material(aarad::Material{"ground", aarad::Rgb(0.5), aarad::Rgb(0.0)});
  const std::uint32_t group = scene.add_group("terrain");
  const auto point = [](int i, int j) {
    return Vec3(0.05 * i, 0.3 * std::sin(0.21 * i) * std::cos(0.17 * j), 0.05 * j);
  };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      scene.add_face(group, ground, {point(i, j), point(i, j + 1), point(i + 1, j + 1)});
      scene.add_face(group, ground, {point(i, j), point(i + 1, j + 1), point(i + 1, j)});
    }
  double surfaces_seconds = 0.0, meshing_seconds = 0.0;
  for (auto _ : state) {
    const double t0 = thread_seconds();
    scene.build_surfaces();
    const double t1 = thread_seconds();
    const Hierarchy h(scene, aarad::mesh::MeshingOptions{});
    const double t2 = thread_seconds();
    benchmark::DoNotOptimize(h.leaf_count());
    surfaces_seconds += t1 - t0;
    meshing_seconds += t2 - t1;
  }
  const double faces = static_cast<double>(scene.faces.size()), runs = static_cast<double>(state.iterations());
  state.counters["faces"] = faces;
  state.counters["surfaces"] = static_cast<double>(scene.surfaces.size());
  state.counters["surfaces_us_per_face"] = 1e6 * surfaces_seconds / runs / faces;
  state.counters["meshing_us_per_face"] = 1e6 * meshing_seconds / runs / faces;
}

BENCHMARK(BM_BuildTerrain)->Arg(50)->Arg(100)->Arg(200)->Iterations(1)->Unit(benchmark::kMillisecond);

// A floor with n x n square holes (where boxes stand, cut out as the Cornell box's floor is): the unit cells of a
// (2n + 1) x (2n + 1) grid without the cells (odd, odd), 3 n^2 + 4 n + 1 faces of one surface, which the Delaunay
// mesher takes as a whole. Reported: the initial meshing (the Hierarchy's constructor) and the invariant checker
// on the result, thread CPU time per face. Finding the holes' seeds tried every face for every triangle, and the
// checker's no-crack test every boundary segment for every boundary edge: both quadratic (n = 128: 50 s).
void BM_FloorWithHoles(benchmark::State& state) {
  const auto n = static_cast<int>(state.range(0));
  aarad::Scene scene;
  scene.name = "floor with holes";
  const std::uint32_t grey = scene.add_material(aarad::Material{"grey", aarad::Rgb(0.5), aarad::Rgb(0.0)});
  const std::uint32_t group = scene.add_group("floor");
  for (int j = 0; j <= 2 * n; ++j)
    for (int i = 0; i <= 2 * n; ++i) {
      if (i % 2 == 1 && j % 2 == 1) continue;  // a hole
      const double x = i, z = j;
      scene.add_face(group, grey, {Vec3(x, 0, z), Vec3(x, 0, z + 1), Vec3(x + 1, 0, z + 1), Vec3(x + 1, 0, z)});
    }
  scene.build_surfaces();
  double meshing_seconds = 0.0, check_seconds = 0.0;
  std::size_t leaves = 0, violations = 0;
  for (auto _ : state) {
    const double t0 = thread_seconds();
    const Hierarchy h(scene, aarad::mesh::MeshingOptions{});
    const double t1 = thread_seconds();
    violations = aarad::mesh::check_invariants(h).size();
    const double t2 = thread_seconds();
    leaves = h.leaf_count();
    meshing_seconds += t1 - t0;
    check_seconds += t2 - t1;
  }
  if (violations != 0) state.SkipWithError("the floor's mesh breaks an invariant");
  const double faces = static_cast<double>(scene.faces.size()), runs = static_cast<double>(state.iterations());
  state.counters["faces"] = faces;
  state.counters["leaves"] = static_cast<double>(leaves);
  state.counters["meshing_us_per_face"] = 1e6 * meshing_seconds / runs / faces;
  state.counters["check_us_per_face"] = 1e6 * check_seconds / runs / faces;
}

BENCHMARK(BM_FloorWithHoles)->Arg(16)->Arg(32)->Arg(64)->Iterations(1)->Unit(benchmark::kMillisecond);

// An n x n floor (one quad) with a post standing on each unit cell: four side faces round a square foot of side
// 0.3 turned by an angle that varies from post to post, each post its own group. The floor is cut along the 4 n^2
// sides' feet (docs/hierarchy.md, "Contact lines"); with a patch per cell, every patch of the floor is cut, so the
// cut region is the whole floor, with as many points as posts. Reported: the initial meshing (the Hierarchy's
// constructor), thread CPU time per face of the scene, and the floor's leaves; the invariant checker runs after
// each meshing, untimed.
void BM_FloorWithStandingPosts(benchmark::State& state) {
  const auto n = static_cast<int>(state.range(0));
  aarad::Scene scene;
  scene.name = "floor with posts";
  const std::uint32_t grey = scene.add_material(aarad::Material{"grey", aarad::Rgb(0.5), aarad::Rgb(0.0)});
  scene.add_face(scene.add_group("floor"), grey, {Vec3(0, 0, 0), Vec3(0, 0, n), Vec3(n, 0, n), Vec3(n, 0, 0)});
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const std::uint32_t group = scene.add_group("post_" + std::to_string(i) + "_" + std::to_string(j));
      const double angle = 0.37 * (i + n * j);
      const Vec3 centre(i + 0.5, 0.0, j + 0.5), along(0.15 * std::cos(angle), 0.0, 0.15 * std::sin(angle));
      const Vec3 across(-along.z, 0.0, along.x);
      const Vec3 foot[4] = {centre - along - across, centre + along - across, centre + along + across,
                            centre - along + across};
      for (int k = 0; k < 4; ++k) {
        const Vec3 a = foot[k], b = foot[(k + 1) % 4];
        scene.add_face(group, grey, {a, b, b + Vec3(0, 1, 0), a + Vec3(0, 1, 0)});
      }
    }
  scene.build_surfaces();
  aarad::mesh::MeshingOptions options;  // a patch per post, 2 x 2 elements: the cut region has 4 n^2 + 4 n + 1 points
  options.patch_size = 1.0;
  options.element_size = 0.5;
  double meshing_seconds = 0.0;
  std::size_t floor_leaves = 0;
  for (auto _ : state) {
    const double t0 = thread_seconds();
    const Hierarchy h(scene, options);
    meshing_seconds += thread_seconds() - t0;
    floor_leaves = 0;
    for (const NodeId leaf : h.leaves()) floor_leaves += h.surface(leaf) == 0 ? 1 : 0;
    if (!aarad::mesh::check_invariants(h).empty()) state.SkipWithError("the cut floor breaks an invariant");
  }
  const double faces = static_cast<double>(scene.faces.size()), runs = static_cast<double>(state.iterations());
  state.counters["faces"] = faces;
  state.counters["floor_leaves"] = static_cast<double>(floor_leaves);
  state.counters["meshing_us_per_face"] = 1e6 * meshing_seconds / runs / faces;
}

BENCHMARK(BM_FloorWithStandingPosts)->Arg(16)->Arg(32)->Arg(64)->Iterations(1)->Unit(benchmark::kMillisecond);

// A ball: a unit sphere about the origin tessellated into n rings of 2n quads, each cut into two triangles (one
// at the poles), one group and one smoothing group: 4 n^2 - 2 n faces, each in a plane of its own, every plane at
// about the same distance from the origin, so with about the same offset d. Grouping them into surfaces
// (Scene::build_surfaces) tried every surface whose d lay within a face's window, nearly all of them (160 000
// triangles: 89 s); the time per face should stay about the same.
void BM_BuildSurfacesBall(benchmark::State& state) {
  const auto n = static_cast<int>(state.range(0));
  aarad::Scene scene;
  scene.name = "ball";
  const std::uint32_t grey = scene.add_material(aarad::Material{"grey", aarad::Rgb(0.5), aarad::Rgb(0.0)});
  const std::uint32_t group = scene.add_group("ball");
  const double pi = std::acos(-1.0);
  const auto point = [&](int ring, int column) {
    const double theta = pi * ring / n, phi = 2.0 * pi * column / (2 * n);
    return Vec3(std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi));
  };
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < 2 * n; ++c) {
      if (r > 0) scene.add_face(group, grey, {point(r, c), point(r, c + 1), point(r + 1, c + 1)}, 0, 1);
      if (r < n - 1) scene.add_face(group, grey, {point(r, c), point(r + 1, c + 1), point(r + 1, c)}, 0, 1);
    }
  double seconds = 0.0;
  for (auto _ : state) {
    const double t0 = thread_seconds();
    scene.build_surfaces();
    seconds += thread_seconds() - t0;
    benchmark::DoNotOptimize(scene.surfaces.size());
  }
  const double faces = static_cast<double>(scene.faces.size());
  state.counters["faces"] = faces;
  state.counters["surfaces"] = static_cast<double>(scene.surfaces.size());
  state.counters["us_per_face"] = 1e6 * seconds / static_cast<double>(state.iterations()) / faces;
}

BENCHMARK(BM_BuildSurfacesBall)->Arg(50)->Arg(100)->Arg(200)->Iterations(1)->Unit(benchmark::kMillisecond);

// Many surfaces in one plane: n cubes of side 0.1 on a square grid of spacing 0.3, each cube its own group (the
// tops of all n share the plane y = 0.1, the bottoms y = 0): the check for faces lying on one another
// (Scene::coplanar_overlaps, run by the OBJ importer). It tested every pair of surfaces of one plane and flattened
// both of each pair, quadratic (20 000 cubes: 5 minutes and 4 GB); the time per surface should stay about the same.
void BM_CoplanarOverlapsCubes(benchmark::State& state) {
  const auto n = static_cast<int>(state.range(0));
  aarad::Scene scene;
  scene.name = "cubes";
  const std::uint32_t grey = scene.add_material(aarad::Material{"grey", aarad::Rgb(0.5), aarad::Rgb(0.0)});
  const int k = static_cast<int>(std::ceil(std::sqrt(n)));
  for (int q = 0; q < n; ++q) {
    const std::uint32_t group = scene.add_group("cube" + std::to_string(q));
    const Vec3 o(0.3 * (q % k), 0.0, 0.3 * (q / k));
    const auto p = [&](int x, int y, int z) { return o + 0.1 * Vec3(x, y, z); };
    scene.add_face(group, grey, {p(0, 0, 0), p(0, 0, 1), p(0, 1, 1), p(0, 1, 0)});
    scene.add_face(group, grey, {p(1, 0, 0), p(1, 1, 0), p(1, 1, 1), p(1, 0, 1)});
    scene.add_face(group, grey, {p(0, 0, 0), p(1, 0, 0), p(1, 0, 1), p(0, 0, 1)});
    scene.add_face(group, grey, {p(0, 1, 0), p(0, 1, 1), p(1, 1, 1), p(1, 1, 0)});
    scene.add_face(group, grey, {p(0, 0, 0), p(0, 1, 0), p(1, 1, 0), p(1, 0, 0)});
    scene.add_face(group, grey, {p(0, 0, 1), p(1, 0, 1), p(1, 1, 1), p(0, 1, 1)});
  }
  scene.build_surfaces();
  double seconds = 0.0;
  for (auto _ : state) {
    const double t0 = thread_seconds();
    const auto overlaps = scene.coplanar_overlaps();
    seconds += thread_seconds() - t0;
    benchmark::DoNotOptimize(overlaps.size());
  }
  const double surfaces = static_cast<double>(scene.surfaces.size());
  state.counters["surfaces"] = surfaces;
  state.counters["us_per_surface"] = 1e6 * seconds / static_cast<double>(state.iterations()) / surfaces;
}

BENCHMARK(BM_CoplanarOverlapsCubes)->Arg(1000)->Arg(4000)->Arg(16000)->Iterations(1)->Unit(benchmark::kMillisecond);

// Faces of one plane that the check once compared all with all (Scene::coplanar_overlaps; y up, the projection keeps
// z and x and its old sweep ran along z). Decals: a floor of n unit tiles, one group, with a strip along z beside
// them, under n / 10 decals 0.5 x 0.5, each its own group, on every tenth tile: the strip was reach for every tile,
// and the floor was flattened, sorted and tested in-plane once per decal (40 000 tiles: 85 s on the decals alone).
// Planks: n planks 100 x 1 along z side by side along x, in one group, or (second argument 1) each its own group: the
// sweep compared every plank with every other (80 000: 23 s), as did box_intersection_d for the surfaces while their
// d was its last dimension (40 000 groups: 2.2 s). The time per face should stay about the same.
void coplanar_overlaps(benchmark::State& state, const aarad::Scene& scene, std::size_t expected) {
  double seconds = 0.0;
  for (auto _ : state) {
    const double t0 = thread_seconds();
    const auto overlaps = scene.coplanar_overlaps();
    seconds += thread_seconds() - t0;
    if (overlaps.size() != expected) state.SkipWithError("unexpected overlaps");
    benchmark::DoNotOptimize(overlaps.size());
  }
  const double faces = static_cast<double>(scene.faces.size());
  state.counters["faces"] = faces;
  state.counters["surfaces"] = static_cast<double>(scene.surfaces.size());
  state.counters["us_per_face"] = 1e6 * seconds / static_cast<double>(state.iterations()) / faces;
}

std::vector<Vec3> floor_quad(double x0, double x1, double z0, double z1) {  // facing +y
  return {Vec3(x0, 0, z0), Vec3(x0, 0, z1), Vec3(x1, 0, z1), Vec3(x1, 0, z0)};
}

void BM_CoplanarOverlapsDecals(benchmark::State& state) {
  const auto n = static_cast<int>(state.range(0));
  const int k = static_cast<int>(std::lround(std::sqrt(n)));
  aarad::Scene scene;
  scene.name = "decals";
  const std::uint32_t grey = scene.add_material(aarad::Material{"grey", aarad::Rgb(0.5), aarad::Rgb(0.0)});
  const std::uint32_t floor = scene.add_group("floor");
  for (int j = 0; j < k; ++j)
    for (int i = 0; i < k; ++i) scene.add_face(floor, grey, floor_quad(i, i + 1, j, j + 1));
  scene.add_face(floor, grey, floor_quad(-1, 0, 0, k));
  const int decals = k * k / 10;
  for (int q = 0; q < decals; ++q) {
    const double x = (10 * q) % k + 0.25, z = (10 * q) / k + 0.25;
    scene.add_face(scene.add_group("decal" + std::to_string(q)), grey, floor_quad(x, x + 0.5, z, z + 0.5));
  }
  scene.build_surfaces();
  coplanar_overlaps(state, scene, static_cast<std::size_t>(decals));
}

BENCHMARK(BM_CoplanarOverlapsDecals)->Arg(10000)->Arg(40000)->Arg(160000)->Iterations(1)->Unit(benchmark::kMillisecond);

void BM_CoplanarOverlapsPlanks(benchmark::State& state) {
  const auto n = static_cast<int>(state.range(0));
  const bool groups = state.range(1) != 0;
  aarad::Scene scene;
  scene.name = "planks";
  const std::uint32_t grey = scene.add_material(aarad::Material{"grey", aarad::Rgb(0.5), aarad::Rgb(0.0)});
  const std::uint32_t planks = scene.add_group("planks");
  for (int i = 0; i < n; ++i)
    scene.add_face(groups ? scene.add_group("plank" + std::to_string(i)) : planks, grey, floor_quad(i, i + 1, 0, 100));
  scene.build_surfaces();
  coplanar_overlaps(state, scene, 0);
}

BENCHMARK(BM_CoplanarOverlapsPlanks)
    ->ArgsProduct({{10000, 40000, 160000}, {0, 1}})
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
  // glibc raises its mmap threshold when a large block is freed, so a refinement run after a larger one finds its
  // vectors' memory already in the heap and skips the page faults that the first run of the process paid: the
  // time per split then depended on which benchmark ran before (docs/benchmarks.md, "Hierarchy"). Setting the
  // threshold (to its default) turns that off: every refinement grows its vectors in fresh pages, at every size.
  mallopt(M_MMAP_THRESHOLD, 128 * 1024);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
}
