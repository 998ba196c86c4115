#include "tests/bench/flat_sheet_index.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <unordered_map>
#include <utility>

#include "absl/strings/str_format.h"
#include "core/index/face_bvh.h"

namespace geodex::bench {
namespace {

// The fine grid: n x n vertices (n = cells * fine + 1), two CCW faces per
// fine cell, split by the diagonal from (i, j) to (i + 1, j + 1).
void AddSheetMesh(int n, int fine, index::IndexData* d) {
  auto vid = [n](int i, int j) { return j * n + i; };
  d->positions.reserve(3 * n * n);
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      d->positions.insert(d->positions.end(), {double(i) / fine, double(j) / fine, 0.0});
    }
  }
  for (int j = 0; j + 1 < n; ++j) {
    for (int i = 0; i + 1 < n; ++i) {
      d->faces.insert(d->faces.end(), {vid(i, j), vid(i + 1, j), vid(i + 1, j + 1)});
      d->faces.insert(d->faces.end(), {vid(i, j), vid(i + 1, j + 1), vid(i, j + 1)});
    }
  }
}

// Half-edge twins of d->faces (-1 on the border).
void AddTwins(index::IndexData* d) {
  std::unordered_map<uint64_t, int32_t> half_edges;
  auto key = [](int32_t a, int32_t b) { return (uint64_t(uint32_t(a)) << 32) | uint32_t(b); };
  const std::vector<int32_t>& faces = d->faces;
  const int32_t num_faces = static_cast<int32_t>(faces.size() / 3);
  for (int32_t f = 0; f < num_faces; ++f) {
    for (int e = 0; e < 3; ++e)
      half_edges[key(faces[3 * f + e], faces[3 * f + (e + 1) % 3])] = 3 * f + e;
  }
  d->twins.resize(faces.size());
  for (int32_t h = 0; h < 3 * num_faces; ++h) {
    const int32_t f = h / 3, e = h % 3;
    auto it = half_edges.find(key(faces[3 * f + (e + 1) % 3], faces[3 * f + e]));
    d->twins[h] = it == half_edges.end() ? -1 : it->second;
  }
}

// The samples, at the coarse grid points (m x m, m = cells + 1), and their
// Euclidean distance matrix.
void AddSamples(int cells, int fine, int n, index::IndexData* d) {
  const int m = cells + 1;
  for (int j = 0; j < m; ++j) {
    for (int i = 0; i < m; ++i) d->samples.push_back(j * fine * n + i * fine);
  }
  const int32_t num_samples = m * m;
  d->sample_distances.resize(size_t(num_samples) * num_samples);
  for (int32_t a = 0; a < num_samples; ++a) {
    const double ax = a % m, ay = a / m;
    for (int32_t b = 0; b < num_samples; ++b) {
      d->sample_distances[size_t(a) * num_samples + b] =
          static_cast<float>(std::hypot(ax - b % m, ay - b / m));
    }
  }
}

// Geodesic triangles laid out like the faces, over the coarse grid, and
// their neighbours across each side.
void AddTriangles(int cells, index::IndexData* d) {
  const int m = cells + 1;
  auto sid = [m](int i, int j) { return j * m + i; };
  for (int j = 0; j < cells; ++j) {
    for (int i = 0; i < cells; ++i) {
      d->triangles.push_back({{sid(i, j), sid(i + 1, j), sid(i + 1, j + 1)}, {-1, -1, -1}});
      d->triangles.push_back({{sid(i, j), sid(i + 1, j + 1), sid(i, j + 1)}, {-1, -1, -1}});
    }
  }
  std::map<std::pair<int32_t, int32_t>, int32_t> sides;
  for (int32_t t = 0; t < static_cast<int32_t>(d->triangles.size()); ++t) {
    for (int e = 0; e < 3; ++e)
      sides[{d->triangles[t].corner[e], d->triangles[t].corner[(e + 1) % 3]}] = t;
  }
  for (auto& t : d->triangles) {
    for (int e = 0; e < 3; ++e) {
      auto it = sides.find({t.corner[(e + 1) % 3], t.corner[e]});
      t.neighbor[e] = it == sides.end() ? -1 : it->second;
    }
  }
}

// Each vertex in the geodesic triangle of its coarse cell, with its
// Euclidean distances to the triangle's corners.
void AddVertexRecords(int cells, int fine, int n, index::IndexData* d) {
  const int m = cells + 1;
  d->vertices.resize(size_t(n) * n);
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const int ci = std::min(i / fine, cells - 1), cj = std::min(j / fine, cells - 1);
      const double x = double(i) / fine - ci, y = double(j) / fine - cj;  // within the cell
      const int32_t t = 2 * (cj * cells + ci) + (y > x ? 1 : 0);
      index::VertexRecord& r = d->vertices[j * n + i];
      r.triangle = t;
      for (int c = 0; c < 3; ++c) {
        const int32_t s = d->triangles[t].corner[c];
        r.distance[c] =
            static_cast<float>(std::hypot(double(i) / fine - s % m, double(j) / fine - s / m));
      }
    }
  }
}

}  // namespace

index::IndexData FlatSheetIndex(int cells, int fine) {
  index::IndexData d;
  const int n = cells * fine + 1;  // fine vertices per side
  AddSheetMesh(n, fine, &d);
  AddTwins(&d);
  AddSamples(cells, fine, n, &d);
  AddTriangles(cells, &d);
  AddVertexRecords(cells, fine, n, &d);
  index::BuildFaceBvh(d.positions, d.faces, &d.bvh_nodes, &d.bvh_faces);
  const int32_t num_samples = static_cast<int32_t>(d.samples.size());
  d.builder_version = "server_bench flat sheet";
  d.mesh_hash = index::MeshHash(d.positions, d.faces);
  d.params.requested_samples = num_samples;
  d.params.num_samples = num_samples;
  d.report = absl::StrFormat("synthetic = flat sheet %dx%d cells, %d fine\n", cells, cells, fine);
  return d;
}

}  // namespace geodex::bench
