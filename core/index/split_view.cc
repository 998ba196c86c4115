#include "core/index/split_view.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "absl/strings/str_format.h"
#include "core/common/status_macros.h"

namespace geodex::index {
namespace {

SplitFaceRecord Whole(int32_t f) {
  SplitFaceRecord r{f, {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
  return r;
}

bool IsWhole(const SplitFaceRecord& r, int32_t f) {
  if (r.coarse_face != f) return false;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (r.weight[i][j] != (i == j ? 1.0f : 0.0f)) return false;
    }
  }
  return true;
}

SplitFaceRecord Decode(const SplitFaceCode& c) {
  SplitFaceRecord r;
  r.coarse_face = c.coarse_face;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) r.weight[i][j] = c.weight[i][j] / float{kSplitWeightDenominator};
  }
  return r;
}

// The codes' own checks: each at most 128, reserved bytes 0.
absl::Status CheckCode(const SplitFaceCode& c, size_t k, const char* what, absl::StatusCode code) {
  bool ok = c.reserved[0] == 0 && c.reserved[1] == 0 && c.reserved[2] == 0;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) ok = ok && c.weight[i][j] <= kSplitWeightDenominator;
  }
  if (ok) return absl::OkStatus();
  return absl::Status(code, absl::StrFormat("%s %d: a weight code over %d or reserved bytes not 0",
                                            what, k, kSplitWeightDenominator));
}

}  // namespace

bool SplitView::Encode(const SplitFaceRecord& r, SplitFaceCode* out) {
  *out = SplitFaceCode{};
  out->coarse_face = r.coarse_face;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const float scaled = r.weight[i][j] * float{kSplitWeightDenominator};
      if (!(scaled >= 0 && scaled <= kSplitWeightDenominator) || scaled != std::floor(scaled)) {
        return false;
      }
      out->weight[i][j] = static_cast<uint8_t>(scaled);
      if (Decode(*out).weight[i][j] != r.weight[i][j]) return false;
    }
  }
  return true;
}

absl::StatusOr<SplitView> SplitView::Dense(std::span<const int32_t> coarse_faces,
                                           std::span<const SplitFaceCode> pieces,
                                           int64_t num_faces, absl::StatusCode code) {
  GEODEX_ASSIGN_OR_RETURN(SplitView v, DenseOf(coarse_faces, pieces.size(), num_faces, code));
  for (size_t k = 0; k < pieces.size(); ++k) {
    GEODEX_RETURN_IF_ERROR(CheckCode(pieces[k], k, "split piece", code));
  }
  v.dense_codes_ = pieces;
  return v;
}

absl::StatusOr<SplitView> SplitView::Sparse(std::span<const int32_t> faces,
                                            std::span<const SplitCoarseRecord> coarse,
                                            std::span<const SplitPieceCode> pieces,
                                            absl::StatusCode code) {
  // The checks of the records on the pieces decoded (a few per split face),
  // then the view over the codes.
  std::vector<SplitPieceRecord> decoded(pieces.size());
  for (size_t k = 0; k < pieces.size(); ++k) {
    GEODEX_RETURN_IF_ERROR(CheckCode(pieces[k].piece, k, "split piece record", code));
    decoded[k] = {pieces[k].face, Decode(pieces[k].piece)};
  }
  GEODEX_ASSIGN_OR_RETURN(SplitView v, Sparse(faces, coarse, decoded, code));
  v.pieces_ = {};
  v.piece_codes_ = pieces;
  return v;
}

absl::StatusOr<SplitView> SplitView::DenseOf(std::span<const int32_t> coarse_faces,
                                             size_t num_pieces, int64_t num_faces,
                                             absl::StatusCode code) {
  SplitView v;
  if (coarse_faces.empty() && num_pieces == 0) return v;
  if (coarse_faces.empty() || coarse_faces.size() % 3 != 0 ||
      static_cast<int64_t>(num_pieces) != num_faces) {
    return absl::Status(
        code, absl::StrFormat("split: %d piece records for %d faces, %d coarse face ids",
                              num_pieces, num_faces, coarse_faces.size()));
  }
  v.num_coarse_faces_ = static_cast<int32_t>(coarse_faces.size() / 3);
  v.num_faces_ = num_faces;
  v.dense_coarse_ = coarse_faces;
  return v;
}

absl::StatusOr<SplitView> SplitView::Dense(std::span<const int32_t> coarse_faces,
                                           std::span<const SplitFaceRecord> pieces,
                                           int64_t num_faces, absl::StatusCode code) {
  GEODEX_ASSIGN_OR_RETURN(SplitView v, DenseOf(coarse_faces, pieces.size(), num_faces, code));
  v.dense_pieces_ = pieces;
  return v;
}

absl::StatusOr<SplitView> SplitView::Sparse(std::span<const int32_t> faces,
                                            std::span<const SplitCoarseRecord> coarse,
                                            std::span<const SplitPieceRecord> pieces,
                                            absl::StatusCode code) {
  SplitView v;
  if (coarse.empty() && pieces.empty()) return v;
  auto fail = [code](std::string message) { return absl::Status(code, message); };
  const int64_t nf = static_cast<int64_t>(faces.size() / 3);
  // Pieces appended after the coarse faces name another face than their own.
  int64_t appended = 0;
  for (size_t k = 0; k < pieces.size(); ++k) {
    const SplitPieceRecord& p = pieces[k];
    if (p.face < 0 || p.face >= nf || (k > 0 && p.face <= pieces[k - 1].face)) {
      return fail(absl::StrFormat("split piece record %d: face %d out of order or of range [0, %d)",
                                  k, p.face, nf));
    }
    appended += p.piece.coarse_face != p.face ? 1 : 0;
  }
  const int64_t num_coarse = nf - appended;
  if (num_coarse <= 0 || pieces.empty()) {
    return fail(absl::StrFormat("split: %d piece records and %d coarse records for %d faces",
                                pieces.size(), coarse.size(), nf));
  }
  for (size_t k = 0; k < pieces.size(); ++k) {
    const SplitPieceRecord& p = pieces[k];
    const bool part = p.piece.coarse_face == p.face && p.face < num_coarse;
    const bool added =
        p.face >= num_coarse && p.piece.coarse_face >= 0 && p.piece.coarse_face < num_coarse;
    if (!part && !added) {
      return fail(absl::StrFormat("split piece record %d: face %d in coarse face %d (of %d)", k,
                                  p.face, p.piece.coarse_face, num_coarse));
    }
  }
  for (size_t k = 0; k < coarse.size(); ++k) {
    const int32_t c = coarse[k].coarse_face;
    if (c < 0 || c >= num_coarse || (k > 0 && c <= coarse[k - 1].coarse_face)) {
      return fail(absl::StrFormat(
          "split coarse record %d: coarse face %d out of order or of range [0, %d)", k, c,
          num_coarse));
    }
  }
  v.num_coarse_faces_ = static_cast<int32_t>(num_coarse);
  v.num_faces_ = nf;
  v.sparse_ = true;
  v.faces_ = faces;
  v.coarse_ = coarse;
  v.pieces_ = pieces;
  return v;
}

std::array<int32_t, 3> SplitView::CoarseFace(int32_t c) const {
  if (!sparse_) return {dense_coarse_[3 * c], dense_coarse_[3 * c + 1], dense_coarse_[3 * c + 2]};
  const auto it = std::lower_bound(
      coarse_.begin(), coarse_.end(), c,
      [](const SplitCoarseRecord& r, int32_t id) { return r.coarse_face < id; });
  if (it != coarse_.end() && it->coarse_face == c) {
    return {it->corner[0], it->corner[1], it->corner[2]};
  }
  return {faces_[3 * c], faces_[3 * c + 1], faces_[3 * c + 2]};
}

SplitFaceRecord SplitView::Piece(int32_t f) const {
  if (!sparse_) return dense_codes_.empty() ? dense_pieces_[f] : Decode(dense_codes_[f]);
  if (!piece_codes_.empty()) {
    const auto it =
        std::lower_bound(piece_codes_.begin(), piece_codes_.end(), f,
                         [](const SplitPieceCode& r, int32_t id) { return r.face < id; });
    if (it != piece_codes_.end() && it->face == f) return Decode(it->piece);
    return Whole(f);
  }
  const auto it =
      std::lower_bound(pieces_.begin(), pieces_.end(), f,
                       [](const SplitPieceRecord& r, int32_t id) { return r.face < id; });
  if (it != pieces_.end() && it->face == f) return it->piece;
  return Whole(f);
}

void SplitView::ToSparse(const SplitView& dense, std::span<const int32_t> faces,
                         std::vector<SplitCoarseRecord>* coarse,
                         std::vector<SplitPieceRecord>* pieces) {
  coarse->clear();
  pieces->clear();
  if (!dense.split()) return;
  const int64_t nf = static_cast<int64_t>(faces.size() / 3);
  for (int32_t c = 0; c < dense.num_coarse_faces(); ++c) {
    const std::array<int32_t, 3> corners = dense.CoarseFace(c);
    if (c >= nf || corners[0] != faces[3 * c] || corners[1] != faces[3 * c + 1] ||
        corners[2] != faces[3 * c + 2]) {
      coarse->push_back({c, {corners[0], corners[1], corners[2]}});
    }
  }
  for (int32_t f = 0; f < nf; ++f) {
    const SplitFaceRecord r = dense.Piece(f);
    if (!IsWhole(r, f)) pieces->push_back({f, r});
  }
}

}  // namespace geodex::index
