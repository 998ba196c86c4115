#include "core/mesh/long_edge_split.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <string>
#include <utility>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "core/common/status_macros.h"

namespace geodex::mesh {
namespace {

using CornerWeights = std::array<std::array<double, 3>, 3>;

// Half-edge ids 3f+2 must fit in an int32.
constexpr int64_t kMaxFaces = std::numeric_limits<int32_t>::max() / 3;

struct QueuedEdge {
  double length;
  int32_t lo, hi;  // vertex ids, lo < hi
  int32_t edge;
};

// Longest first; equal lengths by vertex ids, so the order does not depend
// on edge numbering.
struct ShorterFirst {
  bool operator()(const QueuedEdge& x, const QueuedEdge& y) const {
    if (x.length != y.length) return x.length < y.length;
    return std::pair(x.lo, x.hi) > std::pair(y.lo, y.hi);
  }
};

// The mesh being split, with its own half-edge bookkeeping: half-edge
// 3f+i runs from faces[f][i] to faces[f][i+1], as in Mesh. An edge keeps its
// id (and so its queue entry) while its half-edges move between faces; a
// split edge is dead and never comes back, since every new edge has a new
// vertex at one end.
class LongEdgeSplitter {
 public:
  explicit LongEdgeSplitter(const Mesh& mesh)
      : positions_(mesh.positions()),
        faces_(mesh.faces()),
        he_edge_(mesh.num_halfedges(), kNone),
        parent_(mesh.num_faces()),
        weights_(mesh.num_faces(), CornerWeights{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}}) {
    for (int32_t f = 0; f < mesh.num_faces(); ++f) parent_[f] = f;
    for (int32_t h = 0; h < mesh.num_halfedges(); ++h) {
      const int32_t twin = mesh.Twin(h);
      if (twin != kNone && twin < h) continue;
      const int32_t e = NewEdge();
      AttachHalfedge(e, h);
      if (twin != kNone) AttachHalfedge(e, twin);
      Push(e);
    }
  }

  absl::Status Run(double max_edge_length, int32_t max_new_vertices) {
    while (new_vertices_ < max_new_vertices && !queue_.empty()) {
      const QueuedEdge top = queue_.top();
      queue_.pop();
      if (edge_he_[top.edge][0] == kNone) continue;  // split already
      if (top.length <= max_edge_length) break;
      const int64_t added_faces = edge_he_[top.edge][1] == kNone ? 1 : 2;
      if (static_cast<int64_t>(faces_.size()) + added_faces > kMaxFaces) {
        return absl::ResourceExhaustedError(
            absl::StrCat("SplitLongEdges: more than ", kMaxFaces, " faces"));
      }
      Split(top.edge);
    }
    return absl::OkStatus();
  }

  LongEdgeSplit Finish(Mesh mesh) && {
    return LongEdgeSplit{std::move(mesh), std::move(parent_), std::move(weights_), new_vertices_};
  }

  std::vector<Vec3>& positions() { return positions_; }
  std::vector<Triangle>& faces() { return faces_; }

 private:
  int32_t Origin(int32_t h) const { return faces_[h / 3][h % 3]; }
  int32_t Dest(int32_t h) const { return faces_[h / 3][(h % 3 + 1) % 3]; }

  int32_t NewEdge() {
    edge_he_.push_back({kNone, kNone});
    return static_cast<int32_t>(edge_he_.size()) - 1;
  }

  void AttachHalfedge(int32_t e, int32_t h) {
    he_edge_[h] = e;
    edge_he_[e][edge_he_[e][0] == kNone ? 0 : 1] = h;
  }

  // Half-edge h of edge e now lives at new_h.
  void MoveHalfedge(int32_t e, int32_t h, int32_t new_h) {
    edge_he_[e][edge_he_[e][0] == h ? 0 : 1] = new_h;
    he_edge_[new_h] = e;
  }

  void Push(int32_t e) {
    const int32_t h = edge_he_[e][0];
    const int32_t a = Origin(h), b = Dest(h);
    // The same expression as Mesh::Length, so that the split mesh's
    // lengths compare with max_edge_length exactly as they did here.
    const double length = (positions_[b] - positions_[a]).norm();
    queue_.push({length, std::min(a, b), std::max(a, b), e});
  }

  // Splits edge e at its midpoint v. Each face (x, y, c) with half-edge x->y
  // on e becomes (x, v, c) in place, and (v, y, c) is appended: the
  // orientation is kept, and edge c->x keeps its half-edge.
  void Split(int32_t e) {
    const std::array<int32_t, 2> halfedges = edge_he_[e];
    edge_he_[e] = {kNone, kNone};
    const int32_t a = Origin(halfedges[0]), b = Dest(halfedges[0]);
    const int32_t v = static_cast<int32_t>(positions_.size());
    const Vec3 midpoint = 0.5 * (positions_[a] + positions_[b]);
    positions_.push_back(midpoint);
    ++new_vertices_;
    const int32_t e_av = NewEdge(), e_vb = NewEdge();
    for (const int32_t h : halfedges) {
      if (h == kNone) continue;
      const int32_t f = h / 3, i = h % 3, j = (i + 1) % 3, k = (i + 2) % 3;
      const int32_t x = faces_[f][i], y = faces_[f][j], c = faces_[f][k];
      const int32_t g = static_cast<int32_t>(faces_.size());
      const int32_t e_yc = he_edge_[3 * f + j];
      const int32_t e_vc = NewEdge();

      faces_[f][j] = v;
      faces_.push_back({v, y, c});
      he_edge_.resize(3 * faces_.size(), kNone);
      // The midpoint's weights in this face's parent: the two faces of e may
      // have different parents, so weights are per face, not per vertex.
      const CornerWeights w = weights_[f];
      std::array<double, 3> wv;
      for (int t = 0; t < 3; ++t) wv[t] = 0.5 * (w[i][t] + w[j][t]);
      weights_.push_back({wv, w[j], w[k]});
      weights_[f][j] = wv;
      parent_.push_back(parent_[f]);

      AttachHalfedge(x == a ? e_av : e_vb, 3 * f + i);  // x->v
      AttachHalfedge(x == a ? e_vb : e_av, 3 * g);      // v->y
      MoveHalfedge(e_yc, 3 * f + j, 3 * g + 1);         // y->c
      he_edge_[3 * f + j] = kNone;
      AttachHalfedge(e_vc, 3 * f + j);  // v->c
      AttachHalfedge(e_vc, 3 * g + 2);  // c->v
      Push(e_vc);
    }
    Push(e_av);
    Push(e_vb);
  }

  std::vector<Vec3> positions_;
  std::vector<Triangle> faces_;
  std::vector<int32_t> he_edge_;                 // per half-edge: its edge
  std::vector<std::array<int32_t, 2>> edge_he_;  // per edge: its half-edges, kNone if dead/absent
  std::vector<int32_t> parent_;
  std::vector<CornerWeights> weights_;
  int32_t new_vertices_ = 0;
  std::priority_queue<QueuedEdge, std::vector<QueuedEdge>, ShorterFirst> queue_;
};

}  // namespace

absl::StatusOr<LongEdgeSplit> SplitLongEdges(const Mesh& mesh, double max_edge_length,
                                             int32_t max_new_vertices) {
  if (!std::isfinite(max_edge_length) || max_edge_length <= 0) {
    return absl::InvalidArgumentError(absl::StrCat(
        "SplitLongEdges: max_edge_length must be positive and finite, got ", max_edge_length));
  }
  if (max_new_vertices < 0) {
    return absl::InvalidArgumentError(
        absl::StrCat("SplitLongEdges: max_new_vertices must be >= 0, got ", max_new_vertices));
  }
  LongEdgeSplitter splitter(mesh);
  GEODEX_RETURN_IF_ERROR(splitter.Run(max_edge_length, max_new_vertices));
  // Zero-area faces allowed: see the header.
  GEODEX_ASSIGN_OR_RETURN(Mesh split,
                          Mesh::Create(std::move(splitter.positions()), std::move(splitter.faces()),
                                       mesh.name(), MeshOptions{.allow_zero_area_faces = true}));
  return std::move(splitter).Finish(std::move(split));
}

}  // namespace geodex::mesh
