#include "tests/bench/confined_bench_lib.h"

#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <random>
#include <string>
#include <unordered_map>
#include <vector>

#include "absl/strings/str_format.h"
#include "core/geodesic/confined_geodesic.h"
#include "core/geodesic/exact_geodesic.h"
#include "core/mesh/mesh.h"
#include "core/mesh/mesh_repair.h"

namespace geodex::bench {
namespace {

using geodex::geodesic::ConfinedGeodesicSolver;
using geodex::geodesic::ExactGeodesicSolver;
using geodex::geodesic::GeodesicOptions;
using geodex::mesh::Mesh;
using geodex::mesh::SurfacePoint;
using geodex::mesh::Vec3;

std::string SharedMeshDir() {
  if (const char* env = std::getenv("GEODEX_SHARED_MESHES"); env != nullptr && *env != '\0') {
    return env;
  }
  return GEODEX_SHARED_MESHES_DEFAULT;
}

double ThreadSeconds() {
  timespec t;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

struct Pair {
  SurfacePoint p, q;
  std::vector<int32_t> path_faces;
};

double Quantile(std::vector<double> v, double q) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<size_t>(q * v.size()))];
}

class PairMaker {
 public:
  PairMaker(const Mesh& mesh, uint32_t seed) : mesh_(mesh), random_(seed), solver_(mesh) {
    double total = 0;
    for (int32_t f = 0; f < mesh.num_faces(); ++f) cumulative_.push_back(total += mesh.Area(f));
    spacing_ = std::sqrt(2 * total / (std::sqrt(3.0) * 1000));
  }

  double spacing() const { return spacing_; }

  // A pair 1L-3L apart; `in_face` puts q inside a face rather than at a vertex.
  Pair Make(bool in_face) {
    for (;;) {
      const SurfacePoint p = RandomPoint();
      GeodesicOptions options;
      options.stop_radius = 3.2 * spacing_;
      if (!solver_.Propagate({p}, options).ok()) continue;
      std::vector<int32_t> candidates;
      for (int32_t v = 0; v < mesh_.num_vertices(); ++v) {
        const double d = solver_.VertexDistance(v);
        if (d >= spacing_ && d <= 3 * spacing_) candidates.push_back(v);
      }
      if (candidates.empty()) continue;
      const int32_t v = candidates[Uniform(candidates.size())];
      SurfacePoint q = *geodex::mesh::VertexPoint(mesh_, v);
      if (in_face) {
        const auto fan = mesh_.Outgoing(v);
        q = InFace(Mesh::FaceOf(fan[Uniform(fan.size())]));
        const double d = solver_.DistanceAt(q);
        if (!(d >= spacing_ && d <= 3 * spacing_)) continue;
      }
      return {p, q, {}};
    }
  }

 private:
  size_t Uniform(size_t n) { return std::uniform_int_distribution<size_t>(0, n - 1)(random_); }

  SurfacePoint InFace(int32_t f) {
    std::uniform_real_distribution<double> unit(0, 1);
    const double r = std::sqrt(unit(random_)), s = unit(random_);
    return {f, {1 - r, r * (1 - s), r * s}};
  }

  SurfacePoint RandomPoint() {
    std::uniform_real_distribution<double> unit(0, cumulative_.back());
    const int32_t f = static_cast<int32_t>(
        std::upper_bound(cumulative_.begin(), cumulative_.end(), unit(random_)) -
        cumulative_.begin());
    return InFace(std::min(f, mesh_.num_faces() - 1));
  }

  const Mesh& mesh_;
  std::mt19937 random_;
  ExactGeodesicSolver solver_;
  std::vector<double> cumulative_;
  double spacing_ = 0;
};

// Microseconds per pair of `run` over `pairs`, after a warm-up pass.
template <typename Run>
std::vector<double> TimePairs(const std::vector<Pair>& pairs, Run run) {
  for (size_t i = 0; i < std::min<size_t>(pairs.size(), 20); ++i) run(i);
  std::vector<double> micros;
  for (size_t i = 0; i < pairs.size(); ++i) {
    const double start = ThreadSeconds();
    run(i);
    micros.push_back(1e6 * (ThreadSeconds() - start));
  }
  return micros;
}

// The cost of making `faces` a mesh of its own and a solver over it.
double ExtractMicros(const Mesh& mesh, std::span<const int32_t> faces) {
  const double start = ThreadSeconds();
  std::unordered_map<int32_t, int32_t> local;
  std::vector<Vec3> positions;
  std::vector<geodex::mesh::Triangle> triangles;
  for (const int32_t f : faces) {
    geodex::mesh::Triangle t;
    for (int k = 0; k < 3; ++k) {
      const int32_t v = mesh.face(f)[k];
      auto [it, added] = local.try_emplace(v, static_cast<int32_t>(positions.size()));
      if (added) positions.push_back(mesh.position(v));
      t[k] = it->second;
    }
    triangles.push_back(t);
  }
  geodex::mesh::MeshOptions options;
  options.allow_zero_area_faces = true;
  absl::StatusOr<Mesh> sub =
      Mesh::Create(std::move(positions), std::move(triangles), "region", options);
  if (sub.ok()) ExactGeodesicSolver solver(*sub);
  return 1e6 * (ThreadSeconds() - start);
}

// The whole-mesh engine stopped at q: its times, its distances (`want`) and
// windows, and each pair's exact geodesic faces (the seeds of the path mode).
std::vector<double> TimeWhole(const Mesh& mesh, std::vector<Pair>& pairs, std::vector<double>& want,
                              std::vector<double>& whole_windows) {
  ExactGeodesicSolver whole(mesh);
  const std::vector<double> whole_us = TimePairs(pairs, [&](size_t i) {
    GeodesicOptions options;
    options.stop_points = {pairs[i].q};
    if (!whole.Propagate({pairs[i].p}, options).ok()) std::abort();
    want[i] = whole.DistanceAt(pairs[i].q);
  });
  for (Pair& pair : pairs) {
    GeodesicOptions options;
    options.stop_points = {pair.q};
    if (!whole.Propagate({pair.p}, options).ok()) std::abort();
    const absl::StatusOr<std::vector<SurfacePoint>> geodesic = whole.PathTo(pair.q);
    if (!geodesic.ok()) std::abort();
    for (const SurfacePoint& x : *geodesic) pair.path_faces.push_back(x.face);
    whole_windows.push_back(whole.stats().windows_created);
  }
  return whole_us;
}

int RunMesh(const std::string& path, int num_pairs, uint32_t seed,
            const geodex::geodesic::ConfinedOptions& confined_options) {
  absl::StatusOr<geodex::mesh::RepairedMesh> loaded = geodex::mesh::LoadAndRepairMesh(path);
  if (!loaded.ok()) {
    std::fprintf(stderr, "%s: %s\n", path.c_str(), loaded.status().ToString().c_str());
    return 1;
  }
  const Mesh& mesh = loaded->mesh;
  PairMaker maker(mesh, seed);
  std::vector<Pair> pairs;
  for (int i = 0; i < num_pairs; ++i) pairs.push_back(maker.Make(i % 2 == 1));

  std::vector<double> want(pairs.size()), whole_windows;
  const std::vector<double> whole_us = TimeWhole(mesh, pairs, want, whole_windows);

  ConfinedGeodesicSolver confined(mesh, confined_options);
  double max_diff = 0;
  struct Mode {
    std::vector<double> micros, region, windows;
    int grew = 0, rounds = 0;
  } chain, seeded, pruned;
  std::vector<double> extract;
  // `tight`: the exact distance itself as the upper bound, the tightest a
  // caller can give, where pruning comes nearest to dropping the geodesic.
  auto run_mode = [&](Mode& mode, bool use_seed, bool tight) {
    auto upper = [&](size_t i) { return tight ? want[i] : std::numeric_limits<double>::infinity(); };
    mode.micros = TimePairs(pairs, [&](size_t i) {
      const std::span<const int32_t> seeds =
          use_seed ? std::span<const int32_t>(pairs[i].path_faces) : std::span<const int32_t>();
      const absl::StatusOr<double> d = confined.Distance(pairs[i].p, pairs[i].q, seeds, upper(i));
      if (!d.ok()) std::abort();
      max_diff = std::max(max_diff, std::abs(*d - want[i]) / want[i]);
    });
    for (size_t i = 0; i < pairs.size(); ++i) {
      const Pair& pair = pairs[i];
      const std::span<const int32_t> seeds =
          use_seed ? std::span<const int32_t>(pair.path_faces) : std::span<const int32_t>();
      if (!confined.Distance(pair.p, pair.q, seeds, upper(i)).ok()) std::abort();
      mode.grew += confined.stats().rounds > 1;
      mode.rounds += confined.stats().rounds;
      mode.region.push_back(confined.stats().region_faces);
      mode.windows.push_back(confined.stats().windows_created);
      if (!use_seed && !tight) extract.push_back(ExtractMicros(mesh, confined.region_faces()));
    }
  };
  run_mode(chain, false, false);
  run_mode(seeded, true, false);
  run_mode(pruned, false, true);

  const double n = static_cast<double>(pairs.size());
  auto cells = [&](const Mode& m) {
    return absl::StrFormat("%.1f | %.1f | %.0f%% | %.2f | %.0f | %.0f", Quantile(m.micros, 0.5),
                           Quantile(m.micros, 0.99), 100 * m.grew / n, m.rounds / n,
                           Quantile(m.region, 0.5), Quantile(m.windows, 0.5));
  };
  std::printf("| %s | %d | %zu | %.1f | %.1f | %.0f | %s | %s | %s | %.1f | %.1e |\n",
              std::filesystem::path(path).stem().c_str(), mesh.num_vertices(), pairs.size(),
              Quantile(whole_us, 0.5), Quantile(whole_us, 0.99), Quantile(whole_windows, 0.5),
              cells(chain).c_str(), cells(seeded).c_str(), cells(pruned).c_str(),
              Quantile(extract, 0.5), max_diff);
  std::fflush(stdout);
  return max_diff <= 1e-9 ? 0 : 2;
}

}  // namespace

std::vector<std::string> DefaultConfinedMeshes() {
  std::vector<std::string> meshes;
  for (const char* name :
       {"bunny_3k", "homer_6k", "cheburashka_7k", "kitten_9k", "bunny_closed_30k"}) {
    const std::string path = SharedMeshDir() + "/" + name + ".obj";
    if (std::filesystem::exists(path)) {
      meshes.push_back(path);
    } else {
      std::fprintf(stderr, "skipping %s: not found (set GEODEX_SHARED_MESHES)\n", path.c_str());
    }
  }
  return meshes;
}

int RunConfinedBench(const std::vector<std::string>& meshes, int num_pairs, uint32_t seed,
                     const geodesic::ConfinedOptions& options) {
  std::printf(
      "| mesh | V | pairs | whole µs med | p99 | windows | chain µs med | p99 | grew | rounds | "
      "region faces | windows | path-seeded µs med | p99 | grew | rounds | region faces | "
      "windows | chain, upper bound given µs med | p99 | grew | rounds | region faces | windows | "
      "extract µs med | max rel diff |\n"
      "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
      "---|---|---|\n");
  int status = 0;
  for (const std::string& path : meshes) {
    status = std::max(status, RunMesh(path, num_pairs, seed, options));
  }
  return status;
}

}  // namespace geodex::bench
