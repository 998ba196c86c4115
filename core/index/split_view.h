#pragma once

// The long-edge split of an index (index_format.h, 2.0, 5.0 and 6.0) read
// the same way from either layout: dense (2.x-4.x files, and the builder's
// RepairRecord), a coarse face and a piece record for every face; or sparse
// (5.x), records only for the coarse faces that were split and the faces
// that are not a coarse face whole; either with the weights in 128ths (6.x:
// SplitFaceCode, SplitPieceCode). A view of arrays that live elsewhere
// (a mapped file, an IndexData): they must outlive it.
//
// Thread safety: immutable; every method is const.

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/index/index_format.h"

namespace geodex::index {

class SplitView {
 public:
  // No split.
  SplitView() = default;

  // Dense: `coarse_faces` (3 vertex ids a coarse face) and a piece record
  // for each of `num_faces` faces; both empty: no split. Errors (`code`):
  // sizes that do not match.
  static absl::StatusOr<SplitView> Dense(std::span<const int32_t> coarse_faces,
                                         std::span<const SplitFaceRecord> pieces,
                                         int64_t num_faces, absl::StatusCode code);
  // Sparse, over the index's `faces` (3 vertex ids a face): both record
  // lists empty means no split. Errors (`code`): records out of order or
  // naming faces out of range, a part that does not keep its coarse face's
  // id, or an appended piece that names no coarse face.
  static absl::StatusOr<SplitView> Sparse(std::span<const int32_t> faces,
                                          std::span<const SplitCoarseRecord> coarse,
                                          std::span<const SplitPieceRecord> pieces,
                                          absl::StatusCode code);
  // The same with the weights in 128ths; errors (`code`) also for a code
  // over 128 or reserved bytes that are not 0.
  static absl::StatusOr<SplitView> Dense(std::span<const int32_t> coarse_faces,
                                         std::span<const SplitFaceCode> pieces,
                                         int64_t num_faces, absl::StatusCode code);
  static absl::StatusOr<SplitView> Sparse(std::span<const int32_t> faces,
                                          std::span<const SplitCoarseRecord> coarse,
                                          std::span<const SplitPieceCode> pieces,
                                          absl::StatusCode code);

  // `r` with its weights in 128ths; false when a weight is no such fraction.
  static bool Encode(const SplitFaceRecord& r, SplitFaceCode* out);

  bool split() const { return num_coarse_faces_ > 0; }
  int32_t num_coarse_faces() const { return num_coarse_faces_; }
  // The corners of coarse face c in [0, num_coarse_faces()).
  std::array<int32_t, 3> CoarseFace(int32_t c) const;
  // Where face f lies, f in [0, num_faces).
  SplitFaceRecord Piece(int32_t f) const;

  // The sparse records of a dense split over `faces` (for the 5.0 writer):
  // exactly the coarse faces whose corners are not their face's, and the
  // faces that are not their own coarse face at identity weights.
  static void ToSparse(const SplitView& dense, std::span<const int32_t> faces,
                       std::vector<SplitCoarseRecord>* coarse,
                       std::vector<SplitPieceRecord>* pieces);

 private:
  // A dense view of `coarse_faces` whose pieces are still to be set, after
  // the checks of the sizes both kinds of pieces share.
  static absl::StatusOr<SplitView> DenseOf(std::span<const int32_t> coarse_faces,
                                           size_t num_pieces, int64_t num_faces,
                                           absl::StatusCode code);

  int32_t num_coarse_faces_ = 0;
  int64_t num_faces_ = 0;
  bool sparse_ = false;
  // Dense: the pieces as records or codes (one of the two).
  std::span<const int32_t> dense_coarse_;
  std::span<const SplitFaceRecord> dense_pieces_;
  std::span<const SplitFaceCode> dense_codes_;
  // Sparse: the same.
  std::span<const int32_t> faces_;
  std::span<const SplitCoarseRecord> coarse_;
  std::span<const SplitPieceRecord> pieces_;
  std::span<const SplitPieceCode> piece_codes_;
};

}  // namespace geodex::index
