#pragma once

// The queries of one index, in the ids of the mesh file it was built from:
// the public face of core/query, with its value types (query_types.h) and
// scratch space (query_scratch.h). Everything under core/query/engine/internal/ is
// a part behind it.
//
// The index's internal mesh differs from the file's when the builder
// repaired it or split its long edges (engine/input_ids.h says how);
// InputQueries is the one layer that speaks the file's ids: every caller
// that takes points from a user or gives answers back (the server,
// geodex-query, the accuracy harness, the Python bindings) goes through it,
// and nothing else translates ids.
//
// Points enter once: Read validates a span of points in input ids and keeps
// them, translated, in an EnginePoints, which the queries take. Answers that
// name faces or vertices (paths, located points, fields, the triangulation)
// come back in input ids. A query that is a part of its own (a header of
// its own beside this one: core/query/README.md, "Adding a query") takes an
// InputQueries and its EnginePoints and answers in input ids too, through
// engine() and ids(), with no method here.
//
//   GEODEX_ASSIGN_OR_RETURN(auto queries, query::InputQueries::Open(path));
//   query::EnginePoints a, b;
//   GEODEX_RETURN_IF_ERROR(queries->Read(input_a, query::Named("a"), &a));
//   GEODEX_RETURN_IF_ERROR(queries->Read(input_b, query::Named("b"), &b));
//   std::vector<double> d(a.size());
//   GEODEX_RETURN_IF_ERROR(queries->DistanceBatch(a, b, d));
//
// Thread safety: immutable; every const method is thread-safe. Scratch space
// is the caller's (QueryScratch, one per thread).

#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "core/index/index.h"
#include "core/mesh/mesh.h"
#include "core/query/engine/query_scratch.h"
#include "core/query/engine/query_types.h"

namespace geodex::query {

class QueryEngine;
class InputIds;  // engine/input_ids.h: kept out of this public header

// Points read by InputQueries::Read: validated, in the engine's ids. Only
// InputQueries looks inside; callers keep them between calls (reusing one
// avoids an allocation per batch).
class EnginePoints {
 public:
  size_t size() const { return points_.size(); }
  bool empty() const { return points_.empty(); }
  // n copies of from's point i (a matrix row's source against its targets).
  void AssignRepeated(const EnginePoints& from, size_t i, size_t n) {
    points_.assign(n, from.points_.at(i));
    input_faces_.assign(n, from.input_faces_.at(i));
  }
  // Point i in the engine's ids, and its face as the caller gave it: for a
  // query that is a part of its own over InputQueries.
  const SurfacePoint& engine_point(size_t i) const { return points_.at(i); }
  int32_t input_face(size_t i) const { return input_faces_.at(i); }

 private:
  friend class InputQueries;
  std::vector<SurfacePoint> points_;  // in the engine's ids
  std::vector<int32_t> input_faces_;  // each point's face as the caller gave it
};

// How Read names the i-th point in an error message ("a[17]", "line 5").
using PointName = std::function<std::string(size_t)>;
// "name[i]".
PointName Named(std::string_view name);

class InputQueries {
 public:
  ~InputQueries();
  InputQueries(const InputQueries&) = delete;
  InputQueries& operator=(const InputQueries&) = delete;

  // Opens the index file at `path` and makes its queries. Errors: those of
  // index::Index::Open; InvalidArgument for a null index; FailedPrecondition
  // for an index without geodesic triangles or samples.
  static absl::StatusOr<std::shared_ptr<const InputQueries>> Open(const std::string& path,
                                                                  QueryOptions options = {});
  // Over a loaded index, sharing it. Errors: those of Open but the file's.
  static absl::StatusOr<std::shared_ptr<const InputQueries>> Create(
      std::shared_ptr<const index::Index> index, QueryOptions options = {});
  // Over an engine (engine/query_engine.h), sharing it: for an engine made
  // with test switches (engine/query_knobs.h). Errors: InvalidArgument for
  // a null engine.
  static absl::StatusOr<std::shared_ptr<const InputQueries>> Create(
      std::shared_ptr<const QueryEngine> engine);

  const index::Index& index() const;
  const QueryOptions& options() const;
  // True when the index carries its accuracy calibration (error bounds, and
  // so tolerances).
  bool has_error_bounds() const;
  // L = sqrt(2 A / (sqrt(3) m)): the edge of an equilateral geodesic
  // triangle when the index's m samples tile the surface's area A.
  double scale_length() const;

  // What a query that is a part of its own is lent: the engine
  // whose distances it takes (engine/query_engine.h), and the map between
  // the file's ids and the engine's (engine/input_ids.h).
  const QueryEngine& engine() const;
  const InputIds& ids() const;

  // The input mesh's counts: what face and vertex ids are checked against.
  int32_t num_vertices() const;
  int32_t num_faces() const;
  // True when the index answers on the file's own mesh (no repair, no
  // split): input ids are internal ids.
  bool identity() const;
  // The vertices of input face `f` (in [0, num_faces())), in the file's order.
  mesh::Triangle InputFace(int32_t f) const;

  // Validates `input` (in input ids) against the input's face count and the
  // engine's weight tolerance and keeps it in `out`. Errors: OutOfRange for
  // a face id past the end, InvalidArgument for NaN, infinite or negative
  // weights or weights not summing to 1, each prefixed by the point's name
  // ("a[17]: face id 99999 out of range [0, 5000)").
  absl::Status Read(std::span<const SurfacePoint> input, const PointName& name,
                    EnginePoints* out) const;
  // The same for points given as arrays: `faces` (N) and `weights` (3N, three
  // a point). InvalidArgument when the lengths do not match.
  absl::Status Read(std::span<const int32_t> faces, std::span<const double> weights,
                    const PointName& name, EnginePoints* out) const;
  // The same for points of which some or all are given as input vertex ids
  // (VertexPoint): with `vertices` alone (faces and weights empty), point i
  // is vertex vertices[i]; with all three, point i is vertex vertices[i]
  // when that is >= 0, else faces[i] and its weights. Errors: Read's and
  // VertexPoint's, prefixed by the point's name; InvalidArgument when the
  // lengths do not match.
  absl::Status Read(std::span<const int32_t> faces, std::span<const double> weights,
                    std::span<const int32_t> vertices, const PointName& name,
                    EnginePoints* out) const;
  // Input vertex `v` as a surface point in input ids: weight 1 on it, in
  // the lowest-numbered input face that holds it, so that a path or a field
  // from a vertex starts at the vertex and names that face. The first call
  // finds every vertex's face, in one pass over the faces. Errors:
  // OutOfRange for an id outside [0, num_vertices()); InvalidArgument for a
  // vertex that no face holds.
  absl::StatusOr<SurfacePoint> VertexPoint(int32_t v) const;

  // Distances of pairs (a[i], b[i]) as QueryEngine::DistanceBatch, with its
  // errors (the points are valid already).
  absl::Status DistanceBatch(const EnginePoints& a, const EnginePoints& b, std::span<double> out,
                             const DistanceOptions& options = {}, QueryScratch* scratch = nullptr,
                             std::span<double> bounds = {}) const;
  // One pair, a[i] to b[j], as QueryEngine::Distance.
  absl::StatusOr<double> Distance(const EnginePoints& a, size_t i, const EnginePoints& b, size_t j,
                                  const DistanceOptions& options = {},
                                  QueryScratch* scratch = nullptr, double* bound = nullptr) const;
  // The paper's linear-interpolation baseline (§6.3) for a[i] and b[j].
  double LinearInterpolationDistance(const EnginePoints& a, size_t i, const EnginePoints& b,
                                     size_t j) const;
  // The length of a near pair's surface path as the default refinement
  // finds it (QueryEngine::TracedDistance) for a[i] and b[j].
  absl::StatusOr<double> TracedDistance(const EnginePoints& a, size_t i, const EnginePoints& b,
                                        size_t j) const;

  // The geodesic path from a[i] to b[j] (QueryEngine::Path with this exact
  // corridor), its points in input faces. Errors: as QueryEngine::Path.
  absl::StatusOr<std::vector<PathPoint>> Path(const EnginePoints& a, size_t i,
                                              const EnginePoints& b, size_t j,
                                              int32_t exact_corridor) const;

  // The distance field of `sources` (QueryEngine::Field) per input vertex: at
  // a vertex the repair split, the smallest distance of its copies and that
  // copy's nearest source.
  absl::StatusOr<DistanceField> Field(const EnginePoints& sources) const;

  // The exact distance field of `sources` within options.radius
  // (QueryEngine::FieldWithin): only the input vertices within the radius,
  // ascending, each with its exact distance from its nearest source and that
  // source's index (at a vertex the repair split, the nearest of its copies
  // within the radius; midpoints of split long edges are no input vertices
  // and are left out). It costs what the propagation reaches, not O(n), and
  // is exact where Field is O(1) per vertex. `scratch` (optional) keeps the
  // exact solver between calls. Errors: InvalidArgument for no source or a
  // radius that is not finite and > 0 (the message gives the value);
  // ResourceExhausted when options.max_vertices > 0 and the propagation
  // reaches more vertices.
  absl::StatusOr<RadiusField> FieldWithin(const EnginePoints& sources,
                                          const FieldWithinOptions& options,
                                          QueryScratch* scratch = nullptr) const;

  // The closest surface point to `x`, in an input face.
  absl::StatusOr<LocatedPoint> Locate(const mesh::Vec3& x) const;

  // The samples of the geodesic triangulation as surface points in input
  // ids: each in the input face kept for the lowest-numbered face using its
  // vertex, weight 1 on that vertex (face -1 and zero weights for a sample
  // on no face, which the builder never makes).
  std::vector<SurfacePoint> SamplePoints() const;
  // The input vertex each sample is (mesh::kNone for a midpoint of the split).
  int32_t InputVertex(int32_t internal_vertex) const;
  // Per input vertex, its geodesic triangle; for a split vertex, the
  // smallest triangle id of its copies.
  std::vector<int32_t> VertexTriangles() const;

 private:
  explicit InputQueries(std::shared_ptr<const QueryEngine> engine);

  // Per input vertex, the lowest input face that holds it (-1: none), made
  // by the first VertexPoint.
  const std::vector<int32_t>& VertexFaces() const;

  std::shared_ptr<const QueryEngine> engine_;
  std::unique_ptr<const InputIds> ids_;  // never null
  mutable std::once_flag vertex_faces_once_;
  mutable std::vector<int32_t> vertex_faces_;
};

}  // namespace geodex::query
