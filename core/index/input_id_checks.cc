#include "core/index/input_id_checks.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "absl/strings/str_format.h"
#include "core/common/status_macros.h"

namespace geodex::index {
namespace {

bool InRange(int64_t x, int64_t lo, int64_t hi) { return x >= lo && x < hi; }

absl::Status Fail(absl::StatusCode code, std::string message) {
  return absl::Status(code, message);
}

// The split's coarse faces on coarse vertices, and its pieces: each a piece
// of a coarse face by valid weights, every coarse face with a piece.
// (SplitView::Dense and Sparse checked the records' sizes and order.)
absl::Status CheckSplit(const InputIdSections& c, int64_t num_coarse_vertices,
                        int64_t num_coarse_faces, absl::StatusCode code) {
  for (int32_t f = 0; f < num_coarse_faces; ++f) {
    const std::array<int32_t, 3> corners = c.split.CoarseFace(f);
    for (int32_t v : corners) {
      if (!InRange(v, 0, num_coarse_vertices)) {
        return Fail(code, absl::StrFormat("coarse face %d: vertex id %d out of range [0, %d)", f, v,
                                          num_coarse_vertices));
      }
    }
  }
  std::vector<uint8_t> has_piece(num_coarse_faces, 0);
  for (int32_t f = 0; f < c.num_faces; ++f) {
    const SplitFaceRecord r = c.split.Piece(f);
    bool ok = InRange(r.coarse_face, 0, num_coarse_faces);
    for (int i = 0; i < 3 && ok; ++i) {
      const float* w = r.weight[i];
      ok = std::isfinite(w[0]) && std::isfinite(w[1]) && std::isfinite(w[2]) &&
           std::min({w[0], w[1], w[2]}) >= -1e-6f && std::fabs(w[0] + w[1] + w[2] - 1) <= 1e-5f;
    }
    if (!ok) {
      return Fail(code,
                  absl::StrFormat("piece %d: coarse face %d (of %d) or corner weights invalid", f,
                                  r.coarse_face, num_coarse_faces));
    }
    has_piece[r.coarse_face] = 1;
  }
  for (int64_t f = 0; f < num_coarse_faces; ++f) {
    if (has_piece[f] == 0) return Fail(code, absl::StrFormat("coarse face %d has no piece", f));
  }
  return absl::OkStatus();
}

// Every coarse face is the one face of exactly one input face that was
// not dropped, so that answers have an input face to name.
absl::Status CheckInputFaces(const InputIdSections& c, int64_t num_coarse_faces,
                             absl::StatusCode code) {
  std::vector<uint8_t> kept(num_coarse_faces, 0);
  for (size_t i = 0; i < c.input_faces.size(); ++i) {
    const InputFaceRecord& r = c.input_faces[i];
    const bool permutation = r.corner[0] < 3 && r.corner[1] < 3 && r.corner[2] < 3 &&
                             r.corner[0] != r.corner[1] && r.corner[1] != r.corner[2] &&
                             r.corner[0] != r.corner[2];
    if (!InRange(r.face, 0, num_coarse_faces) || !permutation ||
        (r.flags & ~(kInputFaceDropped | kInputFaceReoriented)) != 0) {
      return Fail(code,
                  absl::StrFormat(
                      "input face %d: face %d (of %d), corners (%d %d %d) or flags %d invalid", i,
                      r.face, num_coarse_faces, r.corner[0], r.corner[1], r.corner[2], r.flags));
    }
    if ((r.flags & kInputFaceDropped) == 0 && kept[r.face]++ > 0) {
      return Fail(code, absl::StrFormat("input face %d: face %d is kept twice", i, r.face));
    }
  }
  for (int64_t f = 0; f < num_coarse_faces; ++f) {
    if (kept[f] == 0) return Fail(code, absl::StrFormat("face %d is no input face's", f));
  }
  return absl::OkStatus();
}

}  // namespace

absl::Status CheckInputIds(const InputIdSections& c, absl::StatusCode code) {
  auto fail = [code](std::string message) { return absl::Status(code, message); };
  const int64_t nv = c.num_vertices;
  const int64_t nf = c.num_faces;
  // Vertices: the input's, the copies, the midpoints. Copies copy an input
  // vertex; coarse faces use no midpoint.
  const int64_t num_coarse_vertices = nv - static_cast<int64_t>(c.split_vertices);
  const int64_t num_input_vertices =
      num_coarse_vertices - static_cast<int64_t>(c.vertex_copies.size());
  if (num_input_vertices < 0) {
    return fail(absl::StrFormat("%d vertex copies and %d midpoints but %d vertices",
                                c.vertex_copies.size(), c.split_vertices, nv));
  }
  for (size_t i = 0; i < c.vertex_copies.size(); ++i) {
    if (!InRange(c.vertex_copies[i], 0, num_input_vertices)) {
      return fail(absl::StrFormat("vertex copy %d: input vertex %d out of range [0, %d)", i,
                                  c.vertex_copies[i], num_input_vertices));
    }
  }
  // An index of a split mesh: every face is a piece of one coarse face,
  // given by weights in it, and every coarse face has a piece.
  const bool split = c.split.split();
  if (c.split_vertices > 0 && !split) {
    return fail(absl::StrFormat("split: no split records for %d midpoints", c.split_vertices));
  }
  const int64_t num_coarse_faces = split ? c.split.num_coarse_faces() : nf;
  if (split) {
    GEODEX_RETURN_IF_ERROR(CheckSplit(c, num_coarse_vertices, num_coarse_faces, code));
  }
  if (!c.input_faces.empty()) {
    GEODEX_RETURN_IF_ERROR(CheckInputFaces(c, num_coarse_faces, code));
  }
  return absl::OkStatus();
}

}  // namespace geodex::index
