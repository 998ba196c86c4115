#include "core/query/engine/internal/locate/point_locator.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "absl/status/status.h"

namespace geodex::query {

namespace {

using Vec3 = Eigen::Vector3d;

Vec3 Vertex(std::span<const double> positions, int32_t v) {
  return Vec3(positions[3 * static_cast<size_t>(v)], positions[3 * static_cast<size_t>(v) + 1],
              positions[3 * static_cast<size_t>(v) + 2]);
}

// Squared distance from x to a node's box (0 inside).
double BoxDistanceSquared(const index::BvhNode& n, const Vec3& x) {
  double d2 = 0;
  for (int k = 0; k < 3; ++k) {
    const double lo = n.lo[k], hi = n.hi[k];
    const double d = x[k] < lo ? lo - x[k] : (x[k] > hi ? x[k] - hi : 0.0);
    d2 += d * d;
  }
  return d2;
}

// Closest point of segment [a, b] to p, as the weight of b.
double SegmentParameter(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double len2 = ab.squaredNorm();
  if (!(len2 > 0)) return 0;
  return std::clamp((p - a).dot(ab) / len2, 0.0, 1.0);
}

// Barycentric weights (of a, b, c) of the point of triangle abc closest to p:
// Ericson, Real-Time Collision Detection, §5.1.5, by Voronoi regions of the
// vertices, then the edges, then the interior.
std::array<double, 3> ClosestPointWeights(const Vec3& p, const Vec3& a, const Vec3& b,
                                          const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return {1, 0, 0};
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return {0, 1, 0};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return {1 - v, v, 0};
  }
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return {0, 0, 1};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    return {1 - w, 0, w};
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {0, 1 - w, w};
  }
  const double sum = va + vb + vc;
  if (va >= 0 && vb >= 0 && vc >= 0 && sum > 0) return {va / sum, vb / sum, vc / sum};
  // Only reached through rounding on (nearly) degenerate triangles: the
  // closest point then lies on an edge.
  std::array<double, 3> best = {1, 0, 0};
  double best_d2 = std::numeric_limits<double>::infinity();
  const Vec3* corners[3] = {&a, &b, &c};
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3;
    const double t = SegmentParameter(p, *corners[i], *corners[j]);
    const double d2e = (p - ((1 - t) * *corners[i] + t * *corners[j])).squaredNorm();
    if (d2e < best_d2) {
      best_d2 = d2e;
      best = {0, 0, 0};
      best[i] = 1 - t;
      best[j] = t;
    }
  }
  return best;
}

// A traversal stack that lives on the call stack unless the tree is unusually
// deep (median splits give depth ~log2(faces / 4)).
class NodeStack {
 public:
  bool empty() const { return size_ == 0; }
  void Push(int32_t node, double d2) {
    if (size_ < kInline) {
      inline_[size_] = {node, d2};
    } else {
      overflow_.push_back({node, d2});
    }
    ++size_;
  }
  std::pair<int32_t, double> Pop() {
    --size_;
    if (size_ < kInline) return inline_[size_];
    const auto top = overflow_.back();
    overflow_.pop_back();
    return top;
  }

 private:
  static constexpr size_t kInline = 64;
  std::array<std::pair<int32_t, double>, kInline> inline_;
  std::vector<std::pair<int32_t, double>> overflow_;
  size_t size_ = 0;
};

}  // namespace

PointLocator::PointLocator(std::span<const double> positions, std::span<const int32_t> faces,
                           std::span<const index::BvhNode> nodes,
                           std::span<const int32_t> leaf_faces)
    : positions_(positions), faces_(faces), nodes_(nodes), leaf_faces_(leaf_faces) {}

absl::StatusOr<LocatedPoint> PointLocator::Locate(const Eigen::Vector3d& x) const {
  if (!x.allFinite()) {
    return absl::InvalidArgumentError("PointLocator::Locate: the query point is not finite");
  }
  if (nodes_.empty()) {
    return absl::FailedPreconditionError("PointLocator::Locate: empty hierarchy (no faces)");
  }
  // Depth-first, nearer child first; a box is skipped only when it is strictly
  // farther than the best face so far, so equally close faces are all seen and
  // the lowest id wins. The slack guards the pruning against rounding in the
  // two distance computations.
  constexpr double kSlack = 1 - 1e-12;
  LocatedPoint best;
  double best_d2 = std::numeric_limits<double>::infinity();
  NodeStack stack;
  stack.Push(0, BoxDistanceSquared(nodes_[0], x));
  while (!stack.empty()) {
    const auto [node_id, node_d2] = stack.Pop();
    if (node_d2 * kSlack > best_d2) continue;
    const index::BvhNode& node = nodes_[node_id];
    if (node.count == 0) {
      const int32_t l = node.first, r = node.first + 1;
      assert(l > node_id && r < static_cast<int32_t>(nodes_.size()));
      const double dl = BoxDistanceSquared(nodes_[l], x);
      const double dr = BoxDistanceSquared(nodes_[r], x);
      // Pushed last = visited first.
      if (dl <= dr) {
        stack.Push(r, dr);
        stack.Push(l, dl);
      } else {
        stack.Push(l, dl);
        stack.Push(r, dr);
      }
      continue;
    }
    for (int32_t i = node.first; i < node.first + node.count; ++i) {
      const int32_t f = leaf_faces_[i];
      const Vec3 a = Vertex(positions_, faces_[3 * f]);
      const Vec3 b = Vertex(positions_, faces_[3 * f + 1]);
      const Vec3 c = Vertex(positions_, faces_[3 * f + 2]);
      const std::array<double, 3> w = ClosestPointWeights(x, a, b, c);
      // The distance is that of the point the weights describe, so a caller
      // that re-evaluates the weights finds exactly this distance.
      const double d2 = (x - (w[0] * a + w[1] * b + w[2] * c)).squaredNorm();
      if (d2 < best_d2 || (d2 == best_d2 && f < best.point.face)) {
        best_d2 = d2;
        best.point.face = f;
        best.point.w = w;
      }
    }
  }
  best.distance = std::sqrt(best_d2);
  return best;
}

}  // namespace geodex::query
