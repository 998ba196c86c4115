// Corner welding of the STL and glTF readers (mesh_weld.h).

#include "core/mesh/mesh_weld.h"

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>

#include "absl/container/flat_hash_map.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"

namespace geodex::mesh {

absl::Status ValidateWeldTolerance(double weld_tolerance) {
  // Above 1e-12 the grid cells of the tolerant weld stay countable in 64
  // bits (the bounding box spans at most 1 / tolerance cells).
  if (weld_tolerance == 0 || (weld_tolerance >= 1e-12 && weld_tolerance <= 1)) {
    return absl::OkStatus();
  }
  return absl::InvalidArgumentError(absl::StrFormat(
      "weld tolerance %g is out of range: 0 (exactly equal positions) or in [1e-12, 1], "
      "relative to the bounding-box diagonal",
      weld_tolerance));
}

namespace io_internal {
namespace {

// Exact positions as a key; -0 and +0 are the same position.
std::array<uint64_t, 3> ExactKey(const Vec3& p) {
  std::array<uint64_t, 3> key;
  for (int i = 0; i < 3; ++i) key[i] = std::bit_cast<uint64_t>(p[i] == 0 ? 0.0 : p[i]);
  return key;
}

// Whether one of the first c corners of `tri` is vertex v.
bool Taken(const Triangle& tri, int c, int32_t v) {
  for (int i = 0; i < c; ++i) {
    if (tri[i] == v) return true;
  }
  return false;
}

// The vertices of `raw` welded so far and the lookup that finds them.
class Welder {
 public:
  // Welds within `tolerance` (a distance) of positions; exactly equal
  // positions when it is 0 or not finite. `lo` is the corner of the
  // bounding box.
  Welder(const Vec3& lo, double tolerance, RawMesh& raw)
      : lo_(lo),
        tolerance_(tolerance),
        tolerance2_(tolerance * tolerance),
        exact_(!(tolerance > 0) || !std::isfinite(tolerance)),
        raw_(raw) {}

  // Sets corner c of `tri` (its earlier corners set), at `p`.
  void Weld(Triangle& tri, int c, const Vec3& p) {
    const Match match = exact_ ? FindExact(tri, c, p) : FindNear(tri, c, p);
    if (match.found != kNone) {
      tri[c] = match.found;
      ++raw_.weld.welded_corners;
      return;
    }
    // A vertex of its own: the first corner at this position, or one that
    // would join a vertex its own triangle already has (kept apart, so
    // that the triangle keeps three corners; it enters no lookup).
    tri[c] = static_cast<int32_t>(raw_.positions.size());
    raw_.positions.push_back(p);
    if (match.blocked) {
      ++raw_.weld.degenerate_corners;
    } else if (exact_) {
      exact_vertex_.emplace(ExactKey(p), tri[c]);
    } else {
      cell_vertices_[CellOf(p)].push_back(tri[c]);
    }
  }

 private:
  struct Match {
    int32_t found = kNone;
    bool blocked = false;  // a vertex within the tolerance is the triangle's already
  };

  Match FindExact(const Triangle& tri, int c, const Vec3& p) const {
    Match match;
    const auto it = exact_vertex_.find(ExactKey(p));
    if (it != exact_vertex_.end()) {
      if (Taken(tri, c, it->second)) {
        match.blocked = true;
      } else {
        match.found = it->second;
      }
    }
    return match;
  }

  // The nearest vertex within the tolerance, the lowest id among the
  // nearest.
  Match FindNear(const Triangle& tri, int c, const Vec3& p) const {
    Match match;
    const std::array<int64_t, 3> cell = CellOf(p);
    double best = tolerance2_;
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = cell_vertices_.find({cell[0] + dx, cell[1] + dy, cell[2] + dz});
          if (it == cell_vertices_.end()) continue;
          for (int32_t v : it->second) {
            const double d2 = (raw_.positions[v] - p).squaredNorm();
            if (Taken(tri, c, v)) {
              match.blocked = match.blocked || d2 <= tolerance2_;
              continue;
            }
            if (d2 < best || (d2 == best && (match.found == kNone || v < match.found))) {
              best = d2;
              match.found = v;
            }
          }
        }
      }
    }
    return match;
  }

  std::array<int64_t, 3> CellOf(const Vec3& p) const {
    std::array<int64_t, 3> cell;
    for (int i = 0; i < 3; ++i)
      cell[i] = static_cast<int64_t>(std::floor((p[i] - lo_[i]) / tolerance_));
    return cell;
  }

  const Vec3 lo_;
  const double tolerance_;
  const double tolerance2_;
  const bool exact_;
  RawMesh& raw_;
  absl::flat_hash_map<std::array<uint64_t, 3>, int32_t> exact_vertex_;
  // Tolerant weld: the vertices in each cube of side `tolerance` (cells
  // counted from lo), searched in the 27 cells round a corner's.
  absl::flat_hash_map<std::array<int64_t, 3>, std::vector<int32_t>> cell_vertices_;
};

}  // namespace

absl::StatusOr<RawMesh> WeldCorners(const std::vector<Vec3>& corners, const ReadOptions& options,
                                    const std::string& name) {
  if (absl::Status s = ValidateWeldTolerance(options.weld_tolerance); !s.ok()) {
    return absl::InvalidArgumentError(absl::StrCat(name, ": ", s.message()));
  }
  const size_t num_triangles = corners.size() / 3;
  if (num_triangles == 0) {
    return absl::InvalidArgumentError(absl::StrCat(name, ": the file has no triangles"));
  }
  if (num_triangles >= static_cast<size_t>(std::numeric_limits<int32_t>::max() / 3)) {
    return absl::InvalidArgumentError(
        absl::StrFormat("%s: %d triangles, more than a mesh holds", name, num_triangles));
  }
  RawMesh raw;
  raw.name = name;
  raw.weld.welded = true;
  raw.weld.tolerance = options.weld_tolerance;
  raw.triangles.resize(num_triangles);
  raw.input_face.resize(num_triangles);
  std::iota(raw.input_face.begin(), raw.input_face.end(), 0);

  // The tolerance as a distance; 0 welds exactly equal positions.
  Vec3 lo = corners[0], hi = corners[0];
  for (const Vec3& p : corners) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  Welder welder(lo, options.weld_tolerance * (hi - lo).norm(), raw);
  for (size_t t = 0; t < num_triangles; ++t) {
    for (int c = 0; c < 3; ++c) welder.Weld(raw.triangles[t], c, corners[3 * t + c]);
  }
  return raw;
}

}  // namespace io_internal
}  // namespace geodex::mesh
