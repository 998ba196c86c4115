#include "core/validation/pair_sampling.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <span>

#include "core/geodesic/exact_geodesic.h"

namespace geodex::validation {
namespace {

constexpr double kBinEdges[kNumScaleBins + 1] = {0, 1, 3, 10, std::numeric_limits<double>::infinity()};

// `count` area-uniform random points of `faces` (cumulative: their running
// area sums).
mesh::SurfacePoint PointOnFaces(std::span<const int32_t> faces,
                                const std::vector<double>& cumulative, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  const size_t i = std::lower_bound(cumulative.begin(), cumulative.end(),
                                    u(rng) * cumulative.back()) -
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
mesh::SurfacePoint AtVertex(const mesh::Mesh& mesh, int32_t v) { return *mesh::VertexPoint(mesh, v); }

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
  return std::sqrt(2 * area / (std::sqrt(3.0) * num_samples));
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
  const double scale = ScaleLength(mesh.TotalArea(), num_samples);
  const double tiny = 1e-9 * mesh.BoundingBoxDiagonal();
  std::mt19937_64 rng(options.seed);
  std::vector<int32_t> all_faces(mesh.num_faces());
  std::iota(all_faces.begin(), all_faces.end(), 0);
  const std::vector<double> all_cumulative = Cumulative(mesh, all_faces);
  std::vector<int32_t> referenced;
  for (int32_t v = 0; v < mesh.num_vertices(); ++v) {
    if (mesh.IsReferenced(v)) referenced.push_back(v);
  }
  std::uniform_int_distribution<size_t> any_vertex(0, referenced.size() - 1);
  geodesic::ExactGeodesicSolver solver(mesh);
  std::vector<ExactPair> pairs;
  auto add = [&](const mesh::SurfacePoint& p, const mesh::SurfacePoint& q, double exact,
                 bool vertices, bool uniform) {
    if (!(exact > tiny) || !std::isfinite(exact)) return false;
    pairs.push_back({p, q, exact, vertices, uniform, ScaleBinOf(exact, scale)});
    return true;
  };
  for (int32_t s = 0; s < options.num_sources; ++s) {
    const bool vertices = s % 2 == 0;
    const mesh::SurfacePoint source = vertices
                                          ? AtVertex(mesh, referenced[any_vertex(rng)])
                                          : PointOnFaces(all_faces, all_cumulative, rng);
    if (!solver.Propagate({source}).ok()) continue;
    const std::vector<double>& dist = solver.VertexDistances();
    for (int32_t k = 0; k < options.uniform_points; ++k) {
      if (vertices) {
        const int32_t v = referenced[any_vertex(rng)];
        add(source, AtVertex(mesh, v), dist[v], true, true);
      } else {
        const mesh::SurfacePoint q = PointOnFaces(all_faces, all_cumulative, rng);
        add(source, q, solver.DistanceAt(q), false, true);
      }
    }
    for (int b = 0; b < kNumScaleBins; ++b) {
      const double lo = kBinEdges[b] * scale, hi = kBinEdges[b + 1] * scale;
      if (vertices) {
        std::vector<int32_t> in_bin;
        for (int32_t v : referenced) {
          if (dist[v] >= lo && dist[v] < hi) in_bin.push_back(v);
        }
        if (in_bin.empty()) continue;
        std::uniform_int_distribution<size_t> pick(0, in_bin.size() - 1);
        for (int32_t k = 0; k < options.per_bin_points; ++k) {
          const int32_t v = in_bin[pick(rng)];
          add(source, AtVertex(mesh, v), dist[v], true, false);
        }
        continue;
      }
      // Faces that reach into the bin; points drawn on them until enough
      // land inside it.
      std::vector<int32_t> faces;
      for (int32_t f = 0; f < mesh.num_faces(); ++f) {
        const mesh::Triangle& t = mesh.face(f);
        const double d0 = dist[t[0]], d1 = dist[t[1]], d2 = dist[t[2]];
        if (f == source.face ||
            (std::min({d0, d1, d2}) < hi && std::max({d0, d1, d2}) >= lo)) {
          faces.push_back(f);
        }
      }
      if (faces.empty()) continue;
      const std::vector<double> cumulative = Cumulative(mesh, faces);
      if (!(cumulative.back() > 0)) continue;
      int32_t found = 0;
      for (int32_t tries = 0; tries < 8 * options.per_bin_points && found < options.per_bin_points;
           ++tries) {
        const mesh::SurfacePoint q = PointOnFaces(faces, cumulative, rng);
        const double exact = solver.DistanceAt(q);
        if (exact >= lo && exact < hi && add(source, q, exact, false, false)) ++found;
      }
    }
  }
  return pairs;
}

}  // namespace geodex::validation
