#pragma once

// The geodesic Delaunay triangulation of a set of samples, as the dual of
// their geodesic Voronoi diagram at vertex resolution (paper §4.1, Xin & Wang
// 2010), with validity checks and repair by sample insertion.
//
// A face whose three vertices lie in three different Voronoi cells holds a
// Voronoi vertex and gives a Delaunay triangle, oriented like the face. The
// dual is a valid triangulation of the surface only when the samples are dense
// enough: CheckDual finds every way it can fail, and RepairTriangulation adds
// samples (the farthest vertex of an offending cell) until none is left. Once
// the dual is valid, RepairTriangulation can also trace its edges as exact
// geodesics (geodesic_edges.h) and repair edges that cross.
//
// Thread safety: the functions are reentrant.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/geodesic/exact_geodesic.h"
#include "core/mesh/mesh.h"
#include "core/sampling/farthest_point_sampling.h"
#include "core/triangulation/geodesic_edges.h"

namespace geodex::triangulation {

enum class ViolationKind {
  kRepeatedVoronoiVertex,  // three cells meet at more than one place
  kOrientation,            // a Voronoi vertex whose faces disagree on orientation
  kArcWithoutVertex,       // two cells touch along an arc that has no Voronoi vertex
  kEdgeInManyTriangles,    // two cells share more than one arc
  kOpenEdgeInside,         // a dual edge with one triangle away from the boundary
  kCellNotDisk,            // the triangles around a sample do not form one fan
  kCellDisconnected,       // a Voronoi cell in several pieces
  kEulerCharacteristic,    // right locally, wrong globally (e.g. a missed handle)
  kEdgesCross,             // two traced geodesic edges cross or touch (not CheckDual's)
};
inline constexpr int kNumViolationKinds = 9;

const char* ViolationName(ViolationKind kind);

struct Violation {
  ViolationKind kind;
  // Samples involved. A wrong Euler characteristic names the one, two or
  // three neighbouring cells whose union holds a loop the samples miss (a
  // handle, tunnel or pinch smaller than the cells), or every cell of the
  // component when no such union is found.
  std::vector<int32_t> cells;
  // Where RepairTriangulation placed its sample for it, when it placed one by
  // the loop it found: the two ends of the mesh edge that closes the loop, and
  // the loop's length (through the cells' samples, an upper bound on the
  // feature's size). Empty and 0 otherwise.
  std::vector<int32_t> vertices;
  double loop_length = 0;
};

struct DualComplex {
  // Oriented triangles (sample indices), sorted; for each side (corner i,
  // corner i+1) the neighbouring triangle or -1.
  std::vector<std::array<int32_t, 3>> triangles;
  std::vector<std::array<int32_t, 3>> neighbors;
  std::vector<Violation> violations;
  // The edges traced as exact geodesics, sorted by (a, b): filled by
  // RepairTriangulation when RepairOptions::check_edges is set, else empty.
  std::vector<GeodesicEdge> edges;
};

// Builds the dual of the Voronoi labels (`nearest` per vertex, sample count
// `num_samples`) and lists every violation.
DualComplex CheckDual(const mesh::Mesh& mesh, const std::vector<int32_t>& nearest,
                      int32_t num_samples);

struct RepairReport {
  int32_t rounds = 0;
  int32_t samples_added = 0;
  // How many samples were added for each kind of violation.
  std::array<int32_t, kNumViolationKinds> added_for = {};
  // Pairs of crossing geodesic edges found, summed over the rounds.
  int32_t crossings_found = 0;
  // The samples (indices into SampleSet::samples) added for a wrong Euler
  // characteristic, in the order added: where the handles, tunnels and
  // pinches the first samples missed lie.
  std::vector<int32_t> euler_samples;
  std::string Summary() const;
};

struct RepairOptions {
  int32_t max_rounds = 200;
  int32_t max_samples = 1 << 30;
  // Once CheckDual passes, trace every edge (TraceEdges) and treat edges that
  // cross (FindCrossings) as violations too; the final edges are returned in
  // DualComplex::edges.
  bool check_edges = false;
  int threads = 1;  // for tracing; 0: all hardware threads
  // For messages: the input file's id of each mesh vertex (kNone for a
  // vertex the file does not have, e.g. a midpoint of the long-edge split);
  // empty when the mesh's ids are the file's.
  std::vector<int32_t> input_vertex_ids = {};  // "= {}": designated initializers may leave it out
};

// Every refusal of the builder fits one line of this many characters.
inline constexpr size_t kMaxRefusalLength = 300;

// One line (at most kMaxRefusalLength characters) naming where `violation`
// lies: its kind, up to two vertices with positions (in the file's ids when
// `input_vertex_ids` is non-empty), a loop's length against the sample spacing
// L = sqrt(2 A / (sqrt(3) m)) of `num_samples` samples, and a few of its cells.
std::string DescribeViolation(const mesh::Mesh& mesh, const sampling::SampleSet& set,
                              const Violation& violation,
                              const std::vector<int32_t>& input_vertex_ids = {});

// Adds samples to `set` until CheckDual (and, with check_edges, FindCrossings)
// finds no violation, and returns the valid dual. The result does not depend
// on `threads`.
//
// Topology the samples miss. Where a component's dual has the wrong Euler
// characteristic although every local check passes, some cell, or the union
// of two or three neighbouring cells, is not a disk on the mesh: a handle,
// tunnel or pinch smaller than the cells lies inside it. Such a union is found
// by its own Euler characteristic at vertex resolution (below 1); its cells
// are grown from their samples (a spanning tree of its vertices in order of
// distance) and the mesh edge where they close on themselves is the end of
// the shortest loop the tree and its dual tree leave (Erickson & Whittlesey
// 2005's greedy loops). The next sample is that edge's farther end, so the
// cells shrink round the feature until the dual sees it: a few rounds, about
// ten samples a feature.
//
// Errors: FailedPrecondition when no valid triangulation is found within
// `max_rounds` rounds or once samples reach `max_samples`, naming the first
// violation's place in one line of at most kMaxRefusalLength characters
// (RefusalMessage); errors of TraceEdges / FindCrossings.
absl::StatusOr<DualComplex> RepairTriangulation(const mesh::Mesh& mesh, sampling::SampleSet* set,
                                                const RepairOptions& options, RepairReport* report);

}  // namespace geodex::triangulation
