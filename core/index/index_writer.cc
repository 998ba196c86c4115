// The index file writer: IndexData -> the bytes of a file the reader
// (index.cc) accepts, with the same checks of the arrays.

#include <algorithm>
#include <cstring>
#include <string>
#include <vector>

#include "absl/strings/str_format.h"
#include "core/common/file_util.h"
#include "core/common/status_macros.h"
#include "core/index/derived_sections.h"
#include "core/index/face_bvh.h"
#include "core/index/index.h"
#include "core/index/index_sections.h"
#include "core/index/input_id_checks.h"
#include "core/index/split_view.h"

namespace geodex::index {

using internal::AlignUp;
using internal::CheckAccuracy;
using internal::CheckContents;
using internal::CheckSpreadBounds;
using internal::Checksum;
using internal::Contents;
using internal::Counts;
using internal::HeaderChecksum;
using internal::kInt32Max;
using internal::kNumSpecs;
using internal::kSpecs;

namespace {

struct Piece {
  const void* data;
  uint64_t size;
};

// How the split is written: sparse (5.0) for a split index with the coded
// matrix whose split the sparse records give back as it is, when that takes
// fewer bytes, else dense. A split of a coarse mesh makes pieces of nearly
// every face, and a piece record is 4 bytes more than a dense one. In 6.0
// either with the weights in 128ths (`coded`) when every weight is such a
// fraction: the smallest of the layouts that give the split back.
struct SplitLayout {
  bool sparse = false;
  bool coded = false;
  std::vector<SplitCoarseRecord> coarse;
  std::vector<SplitPieceRecord> pieces;
  std::vector<SplitFaceCode> dense_codes;
  std::vector<SplitPieceCode> piece_codes;
};

absl::StatusOr<SplitLayout> SplitLayoutOf(const IndexData& d) {
  const int64_t nf = static_cast<int64_t>(d.faces.size() / 3);
  GEODEX_ASSIGN_OR_RETURN(const SplitView dense,
                          SplitView::Dense(d.coarse_faces, d.split_faces, nf,
                                           absl::StatusCode::kInvalidArgument));
  SplitLayout out;
  if (d.sample_matrix != MatrixLayout::kCoded || !dense.split()) return out;
  SplitView::ToSparse(dense, d.faces, &out.coarse, &out.pieces);
  // A split the builder did not make (a part that does not keep its coarse
  // face's id) has no sparse form: it stays dense.
  const absl::StatusOr<SplitView> sparse =
      SplitView::Sparse(d.faces, out.coarse, out.pieces, absl::StatusCode::kInvalidArgument);
  const bool sparse_ok = sparse.ok() && sparse->num_coarse_faces() == dense.num_coarse_faces();
  bool coded_ok = !d.coded_as_version_5;
  std::vector<SplitFaceCode> codes(coded_ok ? d.split_faces.size() : 0);
  for (size_t f = 0; f < codes.size() && coded_ok; ++f) {
    coded_ok = SplitView::Encode(d.split_faces[f], &codes[f]);
  }
  const uint64_t coarse_bytes = d.coarse_faces.size() * sizeof(int32_t);
  const uint64_t sparse_coarse_bytes = out.coarse.size() * sizeof(SplitCoarseRecord);
  // (bytes, sparse, coded), in the order a tie keeps.
  struct Candidate {
    uint64_t bytes;
    bool sparse, coded, ok;
  };
  const Candidate candidates[] = {
      {coarse_bytes + d.split_faces.size() * sizeof(SplitFaceRecord), false, false, true},
      {sparse_coarse_bytes + out.pieces.size() * sizeof(SplitPieceRecord), true, false, sparse_ok},
      {coarse_bytes + d.split_faces.size() * sizeof(SplitFaceCode), false, true, coded_ok},
      {sparse_coarse_bytes + out.pieces.size() * sizeof(SplitPieceCode), true, true,
       sparse_ok && coded_ok},
  };
  const Candidate* best = &candidates[0];
  for (const Candidate& c : candidates) {
    if (c.ok && c.bytes < best->bytes) best = &c;
  }
  out.sparse = best->sparse;
  out.coded = best->coded;
  if (out.coded && out.sparse) {
    for (const SplitPieceRecord& p : out.pieces) {
      SplitPieceCode code{p.face, {}};
      SplitView::Encode(p.piece, &code.piece);
      out.piece_codes.push_back(code);
    }
    out.pieces.clear();
  } else if (out.coded) {
    out.dense_codes = std::move(codes);
  }
  if (!out.sparse) out.coarse.clear(), out.pieces.clear();
  return out;
}

// What a 6.0 file leaves out because the reader derives it as it is
// (derived_sections.h): the twins, the face BVH. Nothing before 6.0, which
// the builder writes for the coded matrix only.
struct Derivable {
  bool twins = false;
  bool bvh = false;
};

// Whether `d` is written as 6.0: the coded matrix, unless asked for the
// older layout.
bool Compact(const IndexData& d) {
  return d.sample_matrix == MatrixLayout::kCoded && !d.coded_as_version_5;
}

Derivable DerivableOf(const IndexData& d) {
  Derivable out;
  if (!Compact(d)) return out;
  const absl::StatusOr<std::vector<int32_t>> twins =
      internal::DeriveTwins(d.faces, absl::StatusCode::kInvalidArgument);
  out.twins = twins.ok() && *twins == d.twins;
  std::vector<BvhNode> nodes;
  std::vector<int32_t> faces;
  BuildFaceBvh(d.positions, d.faces, &nodes, &faces);
  out.bvh = faces == d.bvh_faces && nodes.size() == d.bvh_nodes.size() &&
            (nodes.empty() ||
             std::memcmp(nodes.data(), d.bvh_nodes.data(), nodes.size() * sizeof(BvhNode)) == 0);
  return out;
}

// The sections of `d` in kSpecs order, the matrix's from `matrix` (full,
// lower, coded, code), the vertex records from `with_corners` before 6.0.
void LayOut(const IndexData& d, const Piece (&matrix)[4], const SplitLayout& split,
            const Derivable& derivable, std::span<const VertexRecordWithCorners> with_corners,
            Piece (&pieces)[kNumSpecs]) {
  const bool dense = !split.sparse;
  const bool compact = Compact(d);
  const Piece all[kNumSpecs] = {
      {d.positions.data(), d.positions.size() * sizeof(double)},
      {d.faces.data(), d.faces.size() * sizeof(int32_t)},
      {d.twins.data(), derivable.twins ? 0 : d.twins.size() * sizeof(int32_t)},
      {d.samples.data(), d.samples.size() * sizeof(int32_t)},
      matrix[0],
      {with_corners.data(), compact ? 0 : d.vertices.size() * sizeof(VertexRecordWithCorners)},
      {d.triangles.data(), d.triangles.size() * sizeof(GeodesicTriangle)},
      {d.bvh_nodes.data(), derivable.bvh ? 0 : d.bvh_nodes.size() * sizeof(BvhNode)},
      {d.bvh_faces.data(), derivable.bvh ? 0 : d.bvh_faces.size() * sizeof(int32_t)},
      {d.report.data(), d.report.size()},
      {d.accuracy.data(), d.accuracy.size() * sizeof(AccuracyRecord)},
      {d.input_faces.data(), d.input_faces.size() * sizeof(InputFaceRecord)},
      {d.vertex_copies.data(), d.vertex_copies.size() * sizeof(int32_t)},
      {d.coarse_faces.data(), dense ? d.coarse_faces.size() * sizeof(int32_t) : 0},
      {d.split_faces.data(),
       dense && !split.coded ? d.split_faces.size() * sizeof(SplitFaceRecord) : 0},
      {d.spread_bounds.data(), d.spread_bounds.size() * sizeof(SpreadBoundRecord)},
      matrix[1],
      matrix[2],
      matrix[3],
      {split.coarse.data(), split.coarse.size() * sizeof(SplitCoarseRecord)},
      {split.pieces.data(), split.pieces.size() * sizeof(SplitPieceRecord)},
      {d.vertices.data(), compact ? d.vertices.size() * sizeof(VertexRecord) : 0},
      {split.dense_codes.data(), split.dense_codes.size() * sizeof(SplitFaceCode)},
      {split.piece_codes.data(), split.piece_codes.size() * sizeof(SplitPieceCode)},
  };
  std::copy(std::begin(all), std::end(all), std::begin(pieces));
}

// Whether section i is written. Every section is, empty ones with size 0,
// but the input-id sections (1.2, 2.0), written only when the mesh was
// repaired or split so that the index of a mesh that needed neither keeps
// the 1.1 layout, and the matrix sections of other layouts. The matrix
// sections of the layout written are, even when empty (no samples). The
// vertex records of one version only; the twins and the BVH not when
// derivable.
bool Written(size_t i, const Piece (&pieces)[kNumSpecs], MatrixLayout layout, bool compact,
             const Derivable& derivable) {
  const SectionId id = kSpecs[i].id;
  if (id == SectionId::kSampleDistances) return layout == MatrixLayout::kFull;
  if (id == SectionId::kSampleDistancesLower) return layout == MatrixLayout::kLower;
  if (id == SectionId::kSampleDistancesCoded || id == SectionId::kDistanceCode) {
    return layout == MatrixLayout::kCoded;
  }
  if (id == SectionId::kVertexRecords) return !compact;
  if (id == SectionId::kCompactVertexRecords) return compact;
  if (id == SectionId::kTwins) return !derivable.twins;
  if (id == SectionId::kFaceBvh || id == SectionId::kBvhFaces) return !derivable.bvh;
  return pieces[i].size > 0 || (id != SectionId::kInputFaces && id != SectionId::kVertexCopies &&
                                id != SectionId::kCoarseFaces && id != SectionId::kSplitFaces &&
                                id != SectionId::kSplitCoarseFaces &&
                                id != SectionId::kSplitPieces && id != SectionId::kSpreadBounds &&
                                id != SectionId::kSplitFaceCodes &&
                                id != SectionId::kSplitPieceCodes);
}

// The file's size: header, table and every written section aligned.
uint64_t FileSize(const Piece (&pieces)[kNumSpecs], MatrixLayout layout, bool compact,
                  const Derivable& derivable) {
  uint64_t sections = 0;
  for (size_t i = 0; i < kNumSpecs; ++i) {
    sections += Written(i, pieces, layout, compact, derivable) ? 1 : 0;
  }
  uint64_t cursor = sizeof(FileHeader) + sections * sizeof(SectionEntry);
  for (size_t i = 0; i < kNumSpecs; ++i) {
    if (Written(i, pieces, layout, compact, derivable)) cursor = AlignUp(cursor) + pieces[i].size;
  }
  return cursor;
}

}  // namespace

uint64_t PredictIndexBytes(const IndexData& d) {
  // A split SerializeIndex would refuse is predicted as written dense.
  const SplitLayout split = SplitLayoutOf(d).value_or(SplitLayout{});
  const uint64_t m = d.samples.size();
  const uint64_t lower = m * (m - std::min<uint64_t>(m, 1)) / 2;
  const MatrixLayout layout = d.sample_matrix;
  const Piece matrix[4] = {
      {nullptr, layout == MatrixLayout::kFull ? m * m * sizeof(float) : 0},
      {nullptr, layout == MatrixLayout::kLower ? lower * sizeof(float) : 0},
      {nullptr, layout == MatrixLayout::kCoded ? lower * sizeof(PackedCode) : 0},
      {nullptr, layout == MatrixLayout::kCoded ? sizeof(DistanceCodeRecord) : 0},
  };
  const Derivable derivable = DerivableOf(d);
  Piece pieces[kNumSpecs];
  LayOut(d, matrix, split, derivable, {}, pieces);
  return FileSize(pieces, layout, Compact(d), derivable);
}

namespace {

absl::Status Bad(std::string message) { return absl::InvalidArgumentError(message); }

// The element counts of `d`, checked to fit int32 ids and against the
// arrays whose sizes they fix first.
absl::StatusOr<Counts> CountsOf(const IndexData& d) {
  if (d.positions.size() % 3 != 0) {
    return Bad(absl::StrFormat("positions: %d values, not a multiple of 3", d.positions.size()));
  }
  if (d.faces.size() % 3 != 0) {
    return Bad(absl::StrFormat("faces: %d values, not a multiple of 3", d.faces.size()));
  }
  Counts counts;
  counts.num_vertices = d.positions.size() / 3;
  counts.num_faces = d.faces.size() / 3;
  counts.num_samples = d.samples.size();
  counts.num_triangles = d.triangles.size();
  counts.num_bvh_nodes = d.bvh_nodes.size();
  if (counts.num_vertices > kInt32Max || 3 * counts.num_faces > kInt32Max ||
      counts.num_samples > kInt32Max || counts.num_triangles > kInt32Max ||
      counts.num_bvh_nodes > kInt32Max) {
    return Bad("too many vertices, faces, samples, triangles or BVH nodes for int32 ids");
  }
  if (d.twins.size() != d.faces.size()) {
    return Bad(absl::StrFormat("twins: %d values, expected %d (3 per face)", d.twins.size(),
                               d.faces.size()));
  }
  if (d.sample_distances.size() != counts.num_samples * counts.num_samples) {
    return Bad(absl::StrFormat("sample_distances: %d values, expected %d (num_samples^2)",
                               d.sample_distances.size(), counts.num_samples * counts.num_samples));
  }
  return counts;
}

// The lower triangle of the m x m matrix `full`, row by row, checked
// symmetric with a zero diagonal.
absl::StatusOr<std::vector<float>> LowerTriangle(const std::vector<float>& full, size_t m) {
  std::vector<float> lower;
  lower.reserve(m * (m - std::min<size_t>(m, 1)) / 2);
  for (size_t a = 0; a < m; ++a) {
    if (full[a * m + a] != 0) {
      return Bad(absl::StrFormat("sample_distances: (%d, %d) is not 0", a, a));
    }
    for (size_t b = 0; b < a; ++b) {
      const float x = full[a * m + b];
      if (!(x == full[b * m + a]) && !(std::isnan(x))) {
        return Bad(absl::StrFormat("sample_distances: (%d, %d) and (%d, %d) differ", a, b, b, a));
      }
      lower.push_back(x);
    }
  }
  return lower;
}

// The matrix stored once (3.0, 4.0): its lower triangle, checked
// symmetric, as floats (`lower`) or codes (`coded` with its `code`); all
// empty for the full matrix.
struct StoredMatrix {
  std::vector<float> lower;
  std::vector<PackedCode> coded;
  std::vector<DistanceCodeRecord> code;
};

absl::StatusOr<StoredMatrix> StoreMatrix(const IndexData& d, size_t num_samples) {
  StoredMatrix out;
  if (d.sample_matrix == MatrixLayout::kFull) return out;
  GEODEX_ASSIGN_OR_RETURN(out.lower, LowerTriangle(d.sample_distances, num_samples));
  if (d.sample_matrix != MatrixLayout::kCoded) return out;
  // Checked as floats first: a NaN has no code.
  Contents floats;
  floats.sample_distances_lower = out.lower;
  GEODEX_RETURN_IF_ERROR(CheckContents(floats, absl::StatusCode::kInvalidArgument));
  double scale = d.sample_distance_scale;
  if (scale == 0) {
    double largest = 0;
    for (float x : out.lower) {
      if (std::isfinite(x)) largest = std::max(largest, static_cast<double>(x));
    }
    scale = DistanceCode::ScaleFor(largest);
  }
  out.code = {DistanceCodeRecord{scale}};
  out.coded.reserve(out.lower.size());
  for (float x : out.lower) out.coded.push_back(DistanceCode::Pack(DistanceCode::Encode(x, scale)));
  out.lower.clear();
  return out;
}

// The records whose number the counts fix, and the builder's version,
// which must fit the header.
absl::Status CheckRecordCounts(const IndexData& d, const Counts& counts) {
  if (d.vertices.size() != counts.num_vertices) {
    return Bad(absl::StrFormat("vertices: %d records, expected %d (one per vertex)",
                               d.vertices.size(), counts.num_vertices));
  }
  const uint64_t expected_bvh_faces = counts.num_bvh_nodes > 0 ? counts.num_faces : 0;
  if (d.bvh_faces.size() != expected_bvh_faces) {
    return Bad(absl::StrFormat("bvh_faces: %d values, expected %d", d.bvh_faces.size(),
                               expected_bvh_faces));
  }
  if (d.params.num_samples != counts.num_samples) {
    return Bad(absl::StrFormat("params.num_samples is %d but there are %d samples",
                               d.params.num_samples, counts.num_samples));
  }
  if (d.builder_version.size() >= sizeof(FileHeader::builder_version) ||
      d.builder_version.find('\0') != std::string::npos) {
    return Bad(absl::StrFormat("builder_version must be under %d bytes without NULs: \"%s\"",
                               sizeof(FileHeader::builder_version), d.builder_version));
  }
  return absl::OkStatus();
}

// The arrays' contents, checked as the reader checks them.
absl::Status CheckArrays(const IndexData& d, const Counts& counts,
                         std::span<const float> full_matrix, const StoredMatrix& matrix) {
  GEODEX_ASSIGN_OR_RETURN(const SplitView split_view,
                          SplitView::Dense(d.coarse_faces, d.split_faces, counts.num_faces,
                                           absl::StatusCode::kInvalidArgument));
  return CheckContents(
      Contents{counts, d.positions, d.faces, d.twins, d.samples, full_matrix, matrix.lower,
               matrix.code, d.vertices, d.triangles, d.bvh_nodes, d.bvh_faces, d.input_faces,
               d.vertex_copies, split_view, d.params.split_vertices},
      absl::StatusCode::kInvalidArgument);
}

// The section table: an entry for each written section, in kSpecs order,
// each aligned after the header and the table; piece_of[e] is the piece
// entry e describes.
struct SectionTable {
  SectionEntry entries[kNumSpecs];
  size_t piece_of[kNumSpecs];
  size_t num_sections = 0;
  uint64_t file_size = 0;

  uint64_t offset() const { return sizeof(FileHeader); }
  uint64_t bytes() const { return num_sections * sizeof(SectionEntry); }
};

SectionTable TableOf(const Piece (&pieces)[kNumSpecs], MatrixLayout layout, bool compact,
                     const Derivable& derivable) {
  auto written = [&](size_t i) { return Written(i, pieces, layout, compact, derivable); };
  SectionTable t;
  for (size_t i = 0; i < kNumSpecs; ++i) t.num_sections += written(i) ? 1 : 0;
  std::memset(t.entries, 0, sizeof(t.entries));
  uint64_t cursor = t.offset() + t.bytes();
  for (size_t i = 0, e = 0; i < kNumSpecs; ++i) {
    if (!written(i)) continue;
    cursor = AlignUp(cursor);
    t.piece_of[e] = i;
    t.entries[e].id = static_cast<uint32_t>(kSpecs[i].id);
    t.entries[e].element_size = kSpecs[i].element_size;
    t.entries[e].offset = cursor;
    t.entries[e].size = pieces[i].size;
    t.entries[e].checksum = Checksum(pieces[i].data, pieces[i].size);
    cursor += pieces[i].size;
    ++e;
  }
  t.file_size = cursor;
  return t;
}

// The format version a file of `d` is written in.
void SetFormatVersion(const IndexData& d, bool sparse_split, FileHeader& h) {
  const bool refined = !d.split_faces.empty();
  switch (d.sample_matrix) {
    case MatrixLayout::kCoded:
      if (Compact(d)) {
        h.format_major = kDerivedFormatMajor;
        h.format_minor = kDerivedFormatMinor;
      } else {
        h.format_major = sparse_split ? kSparseSplitFormatMajor : kCodedFormatMajor;
        h.format_minor = sparse_split ? kSparseSplitFormatMinor : kCodedFormatMinor;
      }
      break;
    case MatrixLayout::kLower:
      h.format_major = kPackedFormatMajor;
      h.format_minor = kPackedFormatMinor;
      break;
    case MatrixLayout::kFull:
      h.format_major = refined ? kSplitFormatMajor : kFormatMajor;
      h.format_minor = refined ? kRefinedFormatMinor : kFormatMinor;
      break;
  }
}

// The file: header, section table and the written pieces, zero padding
// everywhere.
std::string FileBytes(const IndexData& d, const Counts& counts, bool sparse_split,
                      const Piece (&pieces)[kNumSpecs], const SectionTable& table) {
  FileHeader h;
  std::memset(static_cast<void*>(&h), 0, sizeof(h));  // padding included
  std::memcpy(h.magic, kMagic, sizeof(kMagic));
  SetFormatVersion(d, sparse_split, h);
  h.byte_order_mark = kByteOrderMark;
  h.header_size = sizeof(FileHeader);
  std::memcpy(h.builder_version, d.builder_version.data(), d.builder_version.size());
  h.mesh_hash = d.mesh_hash;
  h.params = d.params;
  h.num_vertices = static_cast<uint32_t>(counts.num_vertices);
  h.num_faces = static_cast<uint32_t>(counts.num_faces);
  h.num_samples = static_cast<uint32_t>(counts.num_samples);
  h.num_triangles = static_cast<uint32_t>(counts.num_triangles);
  h.num_bvh_nodes = static_cast<uint32_t>(counts.num_bvh_nodes);
  h.num_sections = static_cast<uint32_t>(table.num_sections);
  h.section_table_offset = table.offset();
  h.file_size = table.file_size;
  h.table_checksum = Checksum(table.entries, table.bytes());
  h.header_checksum = 0;
  h.header_checksum = HeaderChecksum(reinterpret_cast<const uint8_t*>(&h), sizeof(h));

  std::string out(table.file_size, '\0');  // zero padding everywhere
  std::memcpy(out.data(), &h, sizeof(h));
  std::memcpy(out.data() + table.offset(), table.entries, table.bytes());
  for (size_t e = 0; e < table.num_sections; ++e) {
    const Piece& piece = pieces[table.piece_of[e]];
    if (piece.size > 0) std::memcpy(out.data() + table.entries[e].offset, piece.data, piece.size);
  }
  return out;
}

}  // namespace

absl::StatusOr<std::string> SerializeIndex(const IndexData& d) {
  GEODEX_ASSIGN_OR_RETURN(const Counts counts, CountsOf(d));
  GEODEX_ASSIGN_OR_RETURN(const StoredMatrix stored, StoreMatrix(d, counts.num_samples));
  const MatrixLayout layout = d.sample_matrix;
  const std::span<const float> full_matrix = layout == MatrixLayout::kFull
                                                 ? std::span<const float>(d.sample_distances)
                                                 : std::span<const float>();
  GEODEX_RETURN_IF_ERROR(CheckRecordCounts(d, counts));
  GEODEX_RETURN_IF_ERROR(CheckArrays(d, counts, full_matrix, stored));
  GEODEX_ASSIGN_OR_RETURN(const SplitLayout split, SplitLayoutOf(d));
  GEODEX_RETURN_IF_ERROR(CheckAccuracy(d.accuracy, absl::StatusCode::kInvalidArgument));
  GEODEX_RETURN_IF_ERROR(
      CheckSpreadBounds(d.spread_bounds, d.accuracy.size(), absl::StatusCode::kInvalidArgument));

  const Piece matrix[4] = {
      {full_matrix.data(), full_matrix.size() * sizeof(float)},
      {stored.lower.data(), stored.lower.size() * sizeof(float)},
      {stored.coded.data(), stored.coded.size() * sizeof(PackedCode)},
      {stored.code.data(), stored.code.size() * sizeof(DistanceCodeRecord)},
  };
  const Derivable derivable = DerivableOf(d);
  const bool compact = Compact(d);
  const std::vector<VertexRecordWithCorners> with_corners =
      compact ? std::vector<VertexRecordWithCorners>()
              : internal::WithCorners(d.vertices, d.triangles);
  Piece pieces[kNumSpecs];
  LayOut(d, matrix, split, derivable, with_corners, pieces);
  const SectionTable table = TableOf(pieces, layout, compact, derivable);
  return FileBytes(d, counts, split.sparse, pieces, table);
}

absl::Status WriteIndexFile(const IndexData& data, const std::string& path) {
  GEODEX_ASSIGN_OR_RETURN(const std::string bytes, SerializeIndex(data));
  return AtomicWriteFile(path, bytes);
}

// The file must not shrink while mapped (SIGBUS): writers replace files by
// rename (WriteIndexFile), which leaves this mapping on the old inode.

}  // namespace geodex::index
