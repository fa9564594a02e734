// Time per shot of the classical and the anti-aliased hemicube (Chandran, Kiran, Phani and Rai, section 4:
// AA 10 s vs classical 6 s on the Cornell room, a 1.67x ratio) at N = 100, 300 and 1000, over the Cornell box
// cut into about 4 000 receivers and the office (the paper's second scene) cut into about 16 000, shooting
// from the centre of a light. BM_Pair runs both back ends on the same shot, alternately, and reports their
// wall times and the AA / classical ratios of wall and of process CPU time as counters; BM_Shot times one back
// end alone (Time = wall, CPU = all threads of the process).
//
//   build-bench/bench/bench_formfactor --benchmark_counters_tabular=true
#include "aarad/core/builtin_scenes.h"
#include "aarad/core/polygon.h"
#include "aarad/formfactor/aa_hemicube.h"
#include "aarad/formfactor/backend.h"
#include "aarad/formfactor/hemicube.h"
#include "aarad/formfactor/hemicube_geometry.h"

#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>
#include <ctime>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace {

using namespace aarad;
using namespace aarad::formfactor;

struct Shot {
  ReceiverView receivers;
  Shooter shooter;
};

// Every face of the scene fan-triangulated and each triangle cut into m^2 congruent triangles, m chosen so
// that the element count is close to `target`; a face is a patch, its scene surface the physical surface.
Shot make_shot(const std::string& scene_name, std::size_t target, const std::string& light_group) {
  const Scene scene = load_scene(scene_name);
  double total_area = 0.0;
  for (const Face& f : scene.faces) total_area += area(f.vertices);
  const double element_area = total_area / static_cast<double>(target);
  Shot shot;
  std::uint32_t base = 0;  // keys of the current triangle's lattice points: base + i (m + 1) + j
  for (std::uint32_t fi = 0; fi < scene.faces.size(); ++fi) {
    const Face& face = scene.faces[fi];
    const Plane plane = scene.surfaces[face.surface].plane;
    for (std::size_t k = 1; k + 1 < face.vertices.size(); ++k) {
      const Vec3 a = face.vertices[0], b = face.vertices[k], c = face.vertices[k + 1];
      const double tri_area = 0.5 * glm::length(glm::cross(b - a, c - a));
      const int m = std::max(1, static_cast<int>(std::lround(std::sqrt(tri_area / element_area))));
      const Vec3 u = (b - a) / double(m), v = (c - a) / double(m);
      // Lattice point (i, j) and its key: elements share their vertices, as the solver's receivers do.
      const auto at = [&](int i, int j) { return a + double(i) * u + double(j) * v; };
      const auto key = [&](int i, int j) { return base + static_cast<std::uint32_t>(i * (m + 1) + j); };
      for (int i = 0; i < m; ++i)
        for (int j = 0; i + j < m; ++j) {
          const Vec3 up[3] = {at(i, j), at(i + 1, j), at(i, j + 1)};
          const std::uint32_t up_keys[3] = {key(i, j), key(i + 1, j), key(i, j + 1)};
          shot.receivers.add(up, up_keys, plane, face.surface, fi);
          if (i + j + 1 < m) {
            const Vec3 down[3] = {at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)};
            const std::uint32_t down_keys[3] = {key(i + 1, j), key(i + 1, j + 1), key(i, j + 1)};
            shot.receivers.add(down, down_keys, plane, face.surface, fi);
          }
        }
      base += static_cast<std::uint32_t>((m + 1) * (m + 1));
    }
  }
  const Group& light = scene.groups[*scene.find_group(light_group)];
  const Face& lf = scene.faces[light.faces.front()];
  shot.shooter = Shooter::from_normal(centroid(lf.vertices), scene.surfaces[lf.surface].plane.normal);
  return shot;
}

const Shot& shot_for(int scene) {
  static std::map<int, Shot> cache;
  auto it = cache.find(scene);
  if (it == cache.end())
    it = cache.emplace(scene, scene == 0 ? make_shot("cornell", 4000, "light") : make_shot("office", 16000, "light_1")).first;
  return it->second;
}

double process_cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

const char* scene_label(int scene) { return scene == 0 ? "cornell_4k" : "office_16k"; }

void BM_Shot(benchmark::State& state, const char* backend_name) {
  const Shot& shot = shot_for(static_cast<int>(state.range(0)));
  const auto backend = make_backend(backend_name, {.resolution = static_cast<int>(state.range(1))});
  std::vector<double> out(shot.receivers.size());
  for (auto _ : state) {
    backend->compute(shot.shooter, shot.receivers, {}, out);
    benchmark::DoNotOptimize(out.data());
  }
  state.SetLabel(scene_label(static_cast<int>(state.range(0))));
  state.counters["receivers"] = static_cast<double>(shot.receivers.size());
  state.counters["shots/s"] = benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

void BM_Pair(benchmark::State& state) {
  const Shot& shot = shot_for(static_cast<int>(state.range(0)));
  const int n = static_cast<int>(state.range(1));
  HemicubeBackend classical(n);
  AaHemicubeBackend aa(n);
  std::vector<double> out(shot.receivers.size());
  double classical_s = 0.0, aa_s = 0.0, classical_cpu = 0.0, aa_cpu = 0.0;
  using Clock = std::chrono::steady_clock;
  for (auto _ : state) {
    const auto t0 = Clock::now();
    const double c0 = process_cpu_seconds();
    classical.compute(shot.shooter, shot.receivers, {}, out);
    benchmark::DoNotOptimize(out.data());
    const auto t1 = Clock::now();
    const double c1 = process_cpu_seconds();
    aa.compute(shot.shooter, shot.receivers, {}, out);
    benchmark::DoNotOptimize(out.data());
    const auto t2 = Clock::now();
    const double c2 = process_cpu_seconds();
    classical_s += std::chrono::duration<double>(t1 - t0).count();
    aa_s += std::chrono::duration<double>(t2 - t1).count();
    classical_cpu += c1 - c0;
    aa_cpu += c2 - c1;
  }
  const double iterations = static_cast<double>(state.iterations());
  state.SetLabel(scene_label(static_cast<int>(state.range(0))));
  state.counters["receivers"] = static_cast<double>(shot.receivers.size());
  state.counters["classical_ms"] = 1e3 * classical_s / iterations;
  state.counters["aa_ms"] = 1e3 * aa_s / iterations;
  state.counters["aa/classical"] = aa_s / classical_s;
  // CPU time of all threads: steadier than wall time when other processes share the two cores.
  state.counters["aa/classical_cpu"] = aa_cpu / classical_cpu;
  state.counters["aa_entries"] = static_cast<double>(aa.last_entries());
}

// The per-shot preparation both hemicubes share (hemicube_geometry.h): back-face culling, every point into the
// shooter's frame with its outcode, every receiver's face mask. Runs on the calling thread and the TBB workers.
void BM_Prepare(benchmark::State& state) {
  const Shot& shot = shot_for(static_cast<int>(state.range(0)));
  // Lifted off the light's plane as the solver lifts its shooting points (refine/solver.cpp), so that the points
  // of the light's own surface are decided by the floating-point filter, not in exact arithmetic.
  Shooter shooter = shot.shooter;
  shooter.centre += 1e-9 * shooter.normal;
  PreparedReceivers prepared;
  for (auto _ : state) {
    prepared.prepare(shooter, shot.receivers);
    benchmark::DoNotOptimize(prepared.face_mask(0));
  }
  state.SetLabel(scene_label(static_cast<int>(state.range(0))));
  state.counters["points"] = static_cast<double>(shot.receivers.points().size());
}

void resolutions(benchmark::internal::Benchmark* b) {
  for (int scene : {0, 1})
    for (int n : {100, 300, 1000}) b->Args({scene, n});
  b->Unit(benchmark::kMillisecond)->UseRealTime()->MeasureProcessCPUTime();
}

BENCHMARK(BM_Pair)->Apply(resolutions);
BENCHMARK(BM_Prepare)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond)->UseRealTime()->MeasureProcessCPUTime();
BENCHMARK_CAPTURE(BM_Shot, classical, "hemicube")->Apply(resolutions);
BENCHMARK_CAPTURE(BM_Shot, aa, "aa-hemicube")->Apply(resolutions);

}  // namespace

BENCHMARK_MAIN();
