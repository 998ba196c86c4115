#pragma once

// Plain value types of the geodex client API. They mirror geodex.v1 messages
// (proto/geodex/v1/geodex.proto) without exposing protobuf to callers.

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace geodex::client {

// A point on the model's mesh: a face id (as in the source mesh file, polygons
// fan-triangulated in order) and the barycentric weights of that face's three
// vertices in file order. Weights must be finite, >= 0 and sum to 1 (the
// server allows 1e-6 either way). Or a vertex of the mesh file by its id,
// SurfacePoint::Vertex(id): the server reads it as weight 1 on the vertex in
// the lowest-numbered face holding it, and a path from it starts there.
struct SurfacePoint {
  int32_t face = 0;
  std::array<double, 3> w = {1.0, 0.0, 0.0};
  // >= 0: the point is this vertex, and face and w are not read.
  int32_t vertex = -1;

  // Vertex `id` of the mesh file as a point.
  static SurfacePoint Vertex(int32_t id) {
    SurfacePoint p;
    p.vertex = id;
    return p;
  }

  friend bool operator==(const SurfacePoint&, const SurfacePoint&) = default;
};

// Two surface points whose geodesic distance (or path) is asked for.
struct PointPair {
  SurfacePoint a;
  SurfacePoint b;

  friend bool operator==(const PointPair&, const PointPair&) = default;
};

// A 3D position in the mesh's coordinates: {x, y, z}.
using Position = std::array<double, 3>;

// Names a model and, optionally, one of its versions. Version 0 means the
// newest version the server has loaded. Implicitly constructible from a name,
// so `client.Distance("torus", pairs)` works.
struct ModelRef {
  ModelRef() = default;
  ModelRef(std::string model_name, int64_t model_version = 0)  // NOLINT: implicit on purpose
      : name(std::move(model_name)), version(model_version) {}
  ModelRef(const char* model_name) : name(model_name) {}  // NOLINT: implicit on purpose

  std::string name;
  int64_t version = 0;
};

// How the server answers near pairs: in the same or adjacent geodesic
// triangles, or closer than three geodesic-triangle edges, where the O(1)
// unfolding errs most (geodex.v1.NearPairs). Other pairs are O(1) in every
// mode unless a tolerance refines them.
enum class NearPairs {
  kModelDefault,  // the model's configuration; unless it says otherwise, kPath
  kPath,          // the length of a traced, straightened path
  kUnfold,        // the pure O(1) unfolding: fastest, least accurate
  kExact,         // a local exact propagation: exact, slowest
};

// What one Distance call asks for.
struct DistanceQuery {
  NearPairs near_pairs = NearPairs::kModelDefault;
  // Relative error tolerance (e.g. 0.005): the server refines every pair
  // whose error bound exceeds tolerance x distance. 0: the model's.
  double tolerance = 0;
  // Return each distance's absolute error bound.
  bool error_bounds = false;
  // Also refine every pair that may be closer than this many L1000, the
  // spacing of 1,000 samples on the surface (a unit fixed by the surface):
  // raises the model's threshold (three of its spacings), never lowers it.
  // About 8 is the every-distance mode (geodex.v1.DistanceRequest). 0: the
  // model's.
  double refine_below = 0;
};

// Distances in input order, and with DistanceQuery::error_bounds their
// absolute error bounds (geodex.v1.DistanceResponse.bounds).
struct Distances {
  std::vector<double> distance;
  std::vector<double> bound;  // empty without error_bounds
};

// What the server knows about one model (geodex.v1.ModelInfo).
struct ModelInfo {
  enum class State { kUnspecified, kLoading, kServing, kFailed };

  std::string name;
  int64_t version = 0;  // the version described: the served one, or the newest seen
  std::vector<int64_t> available_versions;
  State state = State::kUnspecified;
  std::string reason;  // why loading failed (kFailed)
  int64_t num_vertices = 0;
  int64_t num_faces = 0;
  int64_t num_samples = 0;    // m, after repair insertions
  int64_t num_triangles = 0;  // geodesic triangles
  Position bbox_min = {0, 0, 0};
  Position bbox_max = {0, 0, 0};
  int64_t requested_samples = 0;
  uint64_t seed = 0;
  int64_t samples_added_by_repair = 0;
  std::string builder_version;
  std::map<std::string, std::string> build_report;  // the builder's "key = value" figures
  int64_t mapped_bytes = 0;
  uint64_t mesh_hash = 0;
  // The build report as one JSON object (keys: core/index/README.md, "The build
  // report"); empty from a server that does not send it.
  std::string report_json;
};

// "LOADING", "SERVING", ... as in the proto.
const char* StateName(ModelInfo::State state);

// All sources x targets distances, row-major: At(s, t) = values[s * cols + t].
struct DistanceMatrix {
  int64_t rows = 0;  // number of sources
  int64_t cols = 0;  // number of targets
  std::vector<double> values;
  int64_t version = 0;  // the model version that answered

  double At(int64_t source, int64_t target) const { return values[source * cols + target]; }
};

// A geodesic path: `points[0]` is the pair's `a`, `points.back()` its `b`;
// `positions[i]` is `points[i]` in 3D. `length` is in the mesh's units.
struct GeodesicPath {
  std::vector<SurfacePoint> points;
  std::vector<Position> positions;
  double length = 0;
};

// A distance field: distances[v] is the distance from the nearest source to
// mesh vertex v (+infinity when unreachable or unreferenced). nearest_source[v]
// is that source's index, or -1; empty unless asked for.
struct VertexDistances {
  std::vector<double> distances;
  std::vector<int32_t> nearest_source;
  int64_t version = 0;
};

// What one DistanceFieldWithin call asks for.
struct FieldWithinQuery {
  // Vertices farther than this from every source are left out; finite, > 0.
  double radius = 0;
  // Also the index of each vertex's nearest source.
  bool with_nearest_source = false;
};

// A distance field within a radius: entry i is mesh vertex vertices[i]
// (ascending), at exact geodesic distance distances[i] <= radius from its
// nearest source, whose index is nearest_source[i] (empty unless asked
// for). Vertices beyond the radius are left out.
struct VertexDistancesWithin {
  std::vector<int32_t> vertices;
  std::vector<double> distances;
  std::vector<int32_t> nearest_source;
  int64_t version = 0;  // the model version that answered
};

// A model's triangle mesh as its index holds it: vertex v is positions[v]
// (unreferenced vertices included), face f is faces[f], three vertex ids in
// the order of the source file. The ids are those of SurfacePoint::face and
// VertexDistances::distances.
struct Mesh {
  std::vector<Position> positions;             // #V
  std::vector<std::array<uint32_t, 3>> faces;  // #F, each id < positions.size()
  int64_t version = 0;                         // the model version whose mesh this is
};

// The discrete exponential map (geodesic polar coordinates) round a centre
// point: for each mesh vertex within the radius, `r` its geodesic distance
// from the centre and `theta` (radians, in (-pi, pi]) the angle at which the
// geodesic to it leaves the centre, measured from the reference direction in
// the centre's tangent plane, counter-clockwise about the face normal;
// (u, v) = r (cos theta, sin theta). Entry i is about mesh vertex
// vertices[i]; vertices ascend. Vertices beyond the radius are left out.
struct ExpMap {
  std::vector<int32_t> vertices;
  std::vector<double> r;
  std::vector<double> theta;
  std::vector<double> u;
  std::vector<double> v;
  int64_t version = 0;  // the model version that answered
};

// What one ExpMap call asks for.
struct ExpMapQuery {
  // Vertices farther than this from the centre are left out; > 0.
  double radius = 0;
  // theta = 0 along this direction, projected into the plane of the centre's
  // face; unset: along that face's first edge.
  std::optional<Position> reference_direction = std::nullopt;
  // How r is computed, as in DistanceQuery.
  NearPairs near_pairs = NearPairs::kModelDefault;
  double tolerance = 0;
};

// The closest surface point to a 3D position and the Euclidean distance to it.
struct LocatedPoint {
  SurfacePoint point;
  double distance = 0;
};

}  // namespace geodex::client
