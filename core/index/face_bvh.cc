#include "core/index/face_bvh.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

#include "Eigen/Core"

namespace geodex::index {

namespace {

using Vec3 = Eigen::Vector3d;

constexpr int32_t kLeafSize = 4;

Vec3 Vertex(std::span<const double> positions, int32_t v) {
  return Vec3(positions[3 * static_cast<size_t>(v)], positions[3 * static_cast<size_t>(v) + 1],
              positions[3 * static_cast<size_t>(v) + 2]);
}

// Float bounds that contain the double value.
float RoundDown(double x) {
  float f = static_cast<float>(x);
  if (static_cast<double>(f) > x) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
  return f;
}
float RoundUp(double x) {
  float f = static_cast<float>(x);
  if (static_cast<double>(f) < x) f = std::nextafter(f, std::numeric_limits<float>::infinity());
  return f;
}

struct Box {
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 hi = Vec3::Constant(-std::numeric_limits<double>::infinity());
  void Extend(const Vec3& x) {
    lo = lo.cwiseMin(x);
    hi = hi.cwiseMax(x);
  }
  void Extend(const Box& b) {
    lo = lo.cwiseMin(b.lo);
    hi = hi.cwiseMax(b.hi);
  }
};

class BvhBuilder {
 public:
  BvhBuilder(std::span<const double> positions, std::span<const int32_t> faces,
             std::vector<BvhNode>* nodes, std::vector<int32_t>* order)
      : nodes_(*nodes), order_(*order) {
    const int32_t nf = static_cast<int32_t>(faces.size() / 3);
    boxes_.resize(nf);
    centroids_.resize(nf);
    order_.resize(nf);
    for (int32_t f = 0; f < nf; ++f) {
      for (int k = 0; k < 3; ++k) boxes_[f].Extend(Vertex(positions, faces[3 * f + k]));
      centroids_[f] = (boxes_[f].lo + boxes_[f].hi) / 2;
      order_[f] = f;
    }
  }

  void Build() {
    nodes_.clear();
    if (order_.empty()) return;
    nodes_.emplace_back();
    Build(0, 0, static_cast<int32_t>(order_.size()));
  }

 private:
  // Fills node `node` with faces order_[begin, end). Children are appended as
  // a pair after their parent, so every child index exceeds its parent's.
  void Build(int32_t node, int32_t begin, int32_t end) {
    Box box, centroid_box;
    for (int32_t i = begin; i < end; ++i) {
      box.Extend(boxes_[order_[i]]);
      centroid_box.Extend(centroids_[order_[i]]);
    }
    BvhNode& n = nodes_[node];
    for (int k = 0; k < 3; ++k) {
      n.lo[k] = RoundDown(box.lo[k]);
      n.hi[k] = RoundUp(box.hi[k]);
    }
    if (end - begin <= kLeafSize) {
      // Leaf contents sorted by face id: the result does not depend on how the
      // standard library's nth_element orders the halves.
      std::sort(order_.begin() + begin, order_.begin() + end);
      n.first = begin;
      n.count = end - begin;
      return;
    }
    // Median split on the longest axis of the centroid bounds (first axis on
    // ties); face id breaks ties between equal centroids, so the split is a
    // function of the face set alone.
    const Vec3 extent = centroid_box.hi - centroid_box.lo;
    int axis = 0;
    if (extent[1] > extent[axis]) axis = 1;
    if (extent[2] > extent[axis]) axis = 2;
    const int32_t mid = begin + (end - begin) / 2;
    std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
                     [&](int32_t a, int32_t b) {
                       const double ca = centroids_[a][axis], cb = centroids_[b][axis];
                       return ca < cb || (ca == cb && a < b);
                     });
    const int32_t left = static_cast<int32_t>(nodes_.size());
    n.first = left;
    n.count = 0;
    nodes_.emplace_back();  // invalidates `n`
    nodes_.emplace_back();
    Build(left, begin, mid);
    Build(left + 1, mid, end);
  }

  std::vector<BvhNode>& nodes_;
  std::vector<int32_t>& order_;
  std::vector<Box> boxes_;
  std::vector<Vec3> centroids_;
};

}  // namespace

void BuildFaceBvh(std::span<const double> positions, std::span<const int32_t> faces,
                  std::vector<BvhNode>* nodes, std::vector<int32_t>* leaf_faces) {
  assert(faces.size() % 3 == 0);
  BvhBuilder(positions, faces, nodes, leaf_faces).Build();
}

}  // namespace geodex::index
