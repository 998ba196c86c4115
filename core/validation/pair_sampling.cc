#include "core/validation/pair_sampling.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <span>
#include <thread>

#include "core/common/threads.h"
#include "core/geodesic/vertex_geodesic.h"
#include "core/geometry/sample_spacing.h"

namespace geodex::validation {
namespace {

constexpr double kBinEdges[kNumScaleBins + 1] = {0, 1, 3, 10,
                                                 std::numeric_limits<double>::infinity()};

// `count` area-uniform random points of `faces` (cumulative: their running
// area sums).
mesh::SurfacePoint PointOnFaces(std::span<const int32_t> faces,
                                const std::vector<double>& cumulative, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  const size_t i =
      std::lower_bound(cumulative.begin(), cumulative.end(), u(rng) * cumulative.back()) -
      cumulative.begin();
  double a = u(rng), b = u(rng);
  if (a + b > 1) a = 1 - a, b = 1 - b;  // uniform on the triangle
  return {faces[std::min(i, faces.size() - 1)], {1 - a - b, a, b}};
}

std::vector<double> Cumulative(const mesh::Mesh& mesh, std::span<const int32_t> faces) {
  std::vector<double> cumulative;
  double total = 0;
  for (int32_t f : faces) cumulative.push_back(total += mesh.Area(f));
  return cumulative;
}

// Vertex v (referenced) as a surface point of one of its faces.
mesh::SurfacePoint AtVertex(const mesh::Mesh& mesh, int32_t v) {
  return *mesh::VertexPoint(mesh, v);
}

// What every source of DrawPairs shares.
struct PairContext {
  const mesh::Mesh& mesh;
  const PairOptions& options;
  double scale = 0;  // L
  double tiny = 0;   // pairs closer than this are left out
  std::vector<int32_t> all_faces;
  std::vector<double> all_cumulative;
  std::vector<int32_t> referenced;
};

// The generator of source `s`: its own, so that sources can be drawn in any
// order and on any thread.
std::mt19937_64 SourceGenerator(uint64_t seed, int32_t s) {
  std::seed_seq seq{static_cast<uint32_t>(seed), static_cast<uint32_t>(seed >> 32),
                    static_cast<uint32_t>(s)};
  return std::mt19937_64(seq);
}

// The pairs of source `s` as they are drawn.
struct SourcePairs {
  const PairContext& c;
  int32_t s;
  std::vector<ExactPair> pairs;

  // Adds (p, q) at distance `exact` unless it is too close or infinite;
  // returns whether it did.
  bool Add(const mesh::SurfacePoint& p, const mesh::SurfacePoint& q, double exact, bool vertices,
           bool uniform) {
    if (!(exact > c.tiny) || !std::isfinite(exact)) return false;
    pairs.push_back({p, q, exact, vertices, uniform, ScaleBinOf(exact, c.scale), s});
    return true;
  }
};

// A vertex paired with vertices: area-uniform ones, then in each bin.
std::vector<ExactPair> VertexSourcePairs(const PairContext& c,
                                         geodesic::VertexGeodesicSolver& solver, int32_t s,
                                         std::mt19937_64& rng) {
  const mesh::Mesh& mesh = c.mesh;
  const PairOptions& options = c.options;
  std::uniform_int_distribution<size_t> any_vertex(0, c.referenced.size() - 1);
  SourcePairs out{c, s, {}};
  const int32_t v = c.referenced[any_vertex(rng)];
  const mesh::SurfacePoint source = AtVertex(mesh, v);
  if (!solver.Propagate({v}).ok()) return {};
  const std::vector<double>& dist = solver.VertexDistances();
  for (int32_t k = 0; k < options.uniform_points; ++k) {
    const int32_t u = c.referenced[any_vertex(rng)];
    out.Add(source, AtVertex(mesh, u), dist[u], true, true);
  }
  for (int b = 0; b < kNumScaleBins; ++b) {
    const double lo = kBinEdges[b] * c.scale, hi = kBinEdges[b + 1] * c.scale;
    std::vector<int32_t> in_bin;
    for (int32_t u : c.referenced) {
      if (dist[u] >= lo && dist[u] < hi) in_bin.push_back(u);
    }
    if (in_bin.empty()) continue;
    std::uniform_int_distribution<size_t> pick(0, in_bin.size() - 1);
    for (int32_t k = 0; k < options.per_bin_points; ++k) {
      const int32_t u = in_bin[pick(rng)];
      out.Add(source, AtVertex(mesh, u), dist[u], true, false);
    }
  }
  return std::move(out.pairs);
}

// Candidate points of every bin for a source in face `source_face`, whose
// vertex distances are `dist`: drawn area-uniformly on the faces that reach
// into the bin.
struct Candidates {
  std::vector<mesh::SurfacePoint> points;
  std::vector<int> bin;
};

Candidates BinCandidates(const PairContext& c, int32_t source_face, const std::vector<double>& dist,
                         std::mt19937_64& rng) {
  const mesh::Mesh& mesh = c.mesh;
  Candidates out;
  for (int b = 0; b < kNumScaleBins; ++b) {
    const double lo = kBinEdges[b] * c.scale, hi = kBinEdges[b + 1] * c.scale;
    std::vector<int32_t> faces;
    for (int32_t f = 0; f < mesh.num_faces(); ++f) {
      const mesh::Triangle& t = mesh.face(f);
      const double d0 = dist[t[0]], d1 = dist[t[1]], d2 = dist[t[2]];
      if (f == source_face || (std::min({d0, d1, d2}) < hi && std::max({d0, d1, d2}) >= lo)) {
        faces.push_back(f);
      }
    }
    if (faces.empty()) continue;
    const std::vector<double> cumulative = Cumulative(mesh, faces);
    if (!(cumulative.back() > 0)) continue;
    for (int32_t k = 0; k < 8 * c.options.per_bin_points; ++k) {
      out.points.push_back(PointOnFaces(faces, cumulative, rng));
      out.bin.push_back(b);
    }
  }
  return out;
}

// A point inside a face paired with such points: one propagation for the
// vertex distances and the uniform points, a second for the candidates of
// every bin, drawn on the faces that reach into it (the first says which
// those are).
std::vector<ExactPair> FaceSourcePairs(const PairContext& c, geodesic::VertexGeodesicSolver& solver,
                                       int32_t s, std::mt19937_64& rng) {
  const PairOptions& options = c.options;
  SourcePairs out{c, s, {}};
  const mesh::SurfacePoint source = PointOnFaces(c.all_faces, c.all_cumulative, rng);
  std::vector<mesh::SurfacePoint> uniform(options.uniform_points);
  for (mesh::SurfacePoint& q : uniform) q = PointOnFaces(c.all_faces, c.all_cumulative, rng);
  geodesic::VertexGeodesicOptions first;
  first.targets = uniform;
  if (!solver.Propagate({source}, first).ok()) return {};
  for (size_t k = 0; k < uniform.size(); ++k) {
    out.Add(source, uniform[k], solver.TargetDistance(k), false, true);
  }
  const std::vector<double> dist = solver.VertexDistances();
  const Candidates candidates = BinCandidates(c, source.face, dist, rng);
  geodesic::VertexGeodesicOptions second;
  second.targets = candidates.points;
  if (candidates.points.empty() || !solver.Propagate({source}, second).ok()) {
    return std::move(out.pairs);
  }
  std::vector<int32_t> found(kNumScaleBins, 0);
  for (size_t k = 0; k < candidates.points.size(); ++k) {
    const int b = candidates.bin[k];
    const double exact = solver.TargetDistance(k);
    if (found[b] < options.per_bin_points && exact >= kBinEdges[b] * c.scale &&
        exact < kBinEdges[b + 1] * c.scale &&
        out.Add(source, candidates.points[k], exact, false, false)) {
      ++found[b];
    }
  }
  return std::move(out.pairs);
}

// The pairs of source `s`: a vertex paired with vertices for even s, a point
// inside a face paired with such points for odd s. Empty when the source's
// propagation fails.
std::vector<ExactPair> PairsOfSource(const PairContext& c, geodesic::VertexGeodesicSolver& solver,
                                     int32_t s) {
  std::mt19937_64 rng = SourceGenerator(c.options.seed, s);
  if (s % 2 == 0) return VertexSourcePairs(c, solver, s, rng);
  return FaceSourcePairs(c, solver, s, rng);
}

}  // namespace

const char* ScaleBinName(int bin) {
  static const char* const kNames[kNumScaleBins] = {"d<L", "L-3L", "3L-10L", ">=10L"};
  return kNames[bin];
}

int ScaleBinOf(double d, double scale_length) {
  int b = 0;
  while (b + 1 < kNumScaleBins && d >= kBinEdges[b + 1] * scale_length) ++b;
  return b;
}

double ScaleLength(double area, int32_t num_samples) {
  return geometry::SampleSpacing(area, num_samples);
}

const char* FixedBinName(int bin) {
  static const char* const kNames[kNumFixedBins] = {"0-0.5", "0.5-1", "1-2",  "2-4",
                                                    "4-8",   "8-16",  ">=16"};
  return kNames[bin];
}

double FixedBinLower(int bin) { return bin == 0 ? 0.0 : std::ldexp(1.0, bin - 2); }

int FixedBinOf(double d, double unit) {
  int b = 0;
  while (b + 1 < kNumFixedBins && d >= FixedBinLower(b + 1) * unit) ++b;
  return b;
}

std::vector<mesh::SurfacePoint> RandomSurfacePoints(const mesh::Mesh& mesh, int32_t count,
                                                    uint64_t seed) {
  std::vector<int32_t> faces(mesh.num_faces());
  std::iota(faces.begin(), faces.end(), 0);
  const std::vector<double> cumulative = Cumulative(mesh, faces);
  std::mt19937_64 rng(seed);
  std::vector<mesh::SurfacePoint> points;
  for (int32_t k = 0; k < count; ++k) points.push_back(PointOnFaces(faces, cumulative, rng));
  return points;
}

std::vector<ExactPair> DrawPairs(const mesh::Mesh& mesh, int32_t num_samples,
                                 const PairOptions& options) {
  PairContext c{mesh, options, 0, 0, {}, {}, {}};
  c.scale = ScaleLength(mesh.TotalArea(), num_samples);
  c.tiny = 1e-9 * mesh.BoundingBoxDiagonal();
  c.all_faces.resize(mesh.num_faces());
  std::iota(c.all_faces.begin(), c.all_faces.end(), 0);
  c.all_cumulative = Cumulative(mesh, c.all_faces);
  const int32_t vertices = options.vertex_limit > 0
                               ? std::min(options.vertex_limit, mesh.num_vertices())
                               : mesh.num_vertices();
  for (int32_t v = 0; v < vertices; ++v) {
    if (mesh.IsReferenced(v)) c.referenced.push_back(v);
  }
  if (c.referenced.empty() || options.num_sources <= 0) return {};
  std::vector<std::vector<ExactPair>> by_source(options.num_sources);
  std::atomic<int32_t> next{0};
  auto worker = [&] {
    // The wavefront engine: its memory follows the front (the window engine
    // keeps every window, gigabytes on a large mesh), and target points are
    // evaluated as the windows pass their faces.
    geodesic::VertexGeodesicSolver solver(mesh);
    for (int32_t s; (s = next.fetch_add(1)) < options.num_sources;) {
      by_source[s] = PairsOfSource(c, solver, options.first_source + s);
    }
  };
  const int threads = std::clamp(common::ThreadCount(options.threads), 1, options.num_sources);
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();
  std::vector<ExactPair> pairs;
  for (std::vector<ExactPair>& list : by_source) {
    pairs.insert(pairs.end(), list.begin(), list.end());
  }
  return pairs;
}

}  // namespace geodex::validation
