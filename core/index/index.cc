#include "core/index/index.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>
#include <optional>
#include <random>
#include <type_traits>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "core/common/file_util.h"
#include "core/common/status_macros.h"
#include "core/index/derived_sections.h"
#include "core/index/face_bvh.h"
#include "core/index/index_sections.h"
#include "core/index/input_id_checks.h"

#define XXH_STATIC_LINKING_ONLY  // XXH64_state_t on the stack
#include "xxhash.h"

namespace geodex::index {

// The format is little-endian and the server uses the sections in place, so
// the host must be little-endian too (x86-64, arm64). Were this assert removed
// on a big-endian host, every file would still be rejected, not misread: the
// byte-order mark would read 0x04030201 (FailedPrecondition).
static_assert(std::endian::native == std::endian::little,
              "geodex index files are little-endian and used in place");

// The on-disk structs have no implicit padding (builders still memset them, so
// that a future field added with padding stays deterministic).
static_assert(sizeof(FileHeader) == 144);
static_assert(sizeof(SectionEntry) == 32);
static_assert(sizeof(BuildParams) == 24);
static_assert(std::is_trivially_copyable_v<FileHeader> &&
              std::is_trivially_copyable_v<SectionEntry> &&
              std::is_trivially_copyable_v<VertexRecord> &&
              std::is_trivially_copyable_v<VertexRecordWithCorners> &&
              std::is_trivially_copyable_v<GeodesicTriangle> &&
              std::is_trivially_copyable_v<BvhNode>);

using internal::AlignUp;
using internal::CheckAccuracy;
using internal::CheckContents;
using internal::CheckSpreadBounds;
using internal::Checksum;
using internal::Contents;
using internal::Counts;
using internal::DeriveTwins;
using internal::ExpectedCount;
using internal::HeaderChecksum;
using internal::kInt32Max;
using internal::kNumSpecs;
using internal::kSpecs;
using internal::SpecIndex;

namespace {

// A typed view of a present, validated section; empty when absent.
template <typename T>
std::span<const T> SectionView(const uint8_t* base, const std::optional<SectionEntry>& e) {
  if (!e.has_value() || e->size == 0) return {};
  return std::span<const T>(reinterpret_cast<const T*>(base + e->offset), e->size / sizeof(T));
}

absl::Status WithPath(const absl::Status& status, const std::string& path) {
  if (status.ok()) return status;
  return absl::Status(status.code(), absl::StrCat(path, ": ", status.message()));
}

bool IsMatrixSection(SectionId id) {
  return id == SectionId::kSampleDistances || id == SectionId::kSampleDistancesLower ||
         id == SectionId::kSampleDistancesCoded || id == SectionId::kDistanceCode;
}

// The matrix sections a file of major version `major` has.
std::vector<SectionId> MatrixSections(uint32_t major) {
  if (major >= kCodedFormatMajor) return {SectionId::kSampleDistancesCoded, SectionId::kDistanceCode};
  if (major >= kPackedFormatMajor) return {SectionId::kSampleDistancesLower};
  return {SectionId::kSampleDistances};
}

// Whether a file of major version `major` must have, may have or must not
// have a section: the matrix sections of its layout, the vertex records with
// corners before 6.0 and without from 6.0, the twins and the BVH optional
// from 6.0 (derived when absent); the others by their spec, and required
// whenever they must hold elements.
enum class Presence { kRequired, kOptional, kAbsent };
Presence PresenceIn(uint32_t major, size_t spec, const Counts& counts) {
  const SectionId id = kSpecs[spec].id;
  const bool derived_format = major >= kDerivedFormatMajor;
  if (IsMatrixSection(id)) {
    const std::vector<SectionId> layout = MatrixSections(major);
    return std::find(layout.begin(), layout.end(), id) != layout.end() ? Presence::kRequired
                                                                        : Presence::kAbsent;
  }
  switch (id) {
    case SectionId::kVertexRecords:
      return derived_format ? Presence::kAbsent : Presence::kRequired;
    case SectionId::kCompactVertexRecords:
      return derived_format ? Presence::kRequired : Presence::kAbsent;
    case SectionId::kSplitFaceCodes:
    case SectionId::kSplitPieceCodes:
      return derived_format ? Presence::kOptional : Presence::kAbsent;
    case SectionId::kTwins:
      return derived_format ? Presence::kOptional : Presence::kRequired;
    case SectionId::kFaceBvh:
    case SectionId::kBvhFaces:
      if (derived_format) return Presence::kOptional;
      break;
    default:
      break;
  }
  return kSpecs[spec].required || ExpectedCount(id, counts).value_or(0) > 0 ? Presence::kRequired
                                                                           : Presence::kOptional;
}

// Validate's steps. Every check happens before the bytes it guards are used;
// sizes are compared by subtraction so that no sum can overflow.

// The fixed header of an image of `n` bytes: magic, byte order, major
// version, header size and checksum, and the file size it records.
absl::StatusOr<FileHeader> ValidateHeader(const uint8_t* p, size_t n) {
  constexpr size_t kHeaderSize = sizeof(FileHeader);
  if (n < kHeaderSize) {
    const size_t k = std::min(n, sizeof(kMagic));
    if (k == 0 || std::memcmp(p, kMagic, k) == 0) {
      return absl::DataLossError(absl::StrFormat(
          "truncated: expected at least %d bytes (the header), found %d", kHeaderSize, n));
    }
    return absl::FailedPreconditionError("not a geodex index (bad magic)");
  }
  FileHeader h;
  std::memcpy(&h, p, sizeof(h));
  if (std::memcmp(h.magic, kMagic, sizeof(kMagic)) != 0) {
    return absl::FailedPreconditionError("not a geodex index (bad magic)");
  }
  if (h.byte_order_mark != kByteOrderMark) {
    if (h.byte_order_mark == __builtin_bswap32(kByteOrderMark)) {
      return absl::FailedPreconditionError(
          "byte order mismatch: the file was written on a host of the other byte order");
    }
    return absl::FailedPreconditionError(
        absl::StrFormat("bad byte order mark 0x%08x", h.byte_order_mark));
  }
  if (h.format_major != kFormatMajor && h.format_major != kSplitFormatMajor &&
      h.format_major != kPackedFormatMajor && h.format_major != kCodedFormatMajor &&
      h.format_major != kSparseSplitFormatMajor && h.format_major != kDerivedFormatMajor) {
    return absl::FailedPreconditionError(absl::StrFormat(
        "index format version %d.%d is not supported by this reader (version %d.%d)",
        h.format_major, h.format_minor, kDerivedFormatMajor, kDerivedFormatMinor));
  }
  if (h.header_size < kHeaderSize || h.header_size % 8 != 0) {
    return absl::DataLossError(absl::StrFormat("bad header size %d", h.header_size));
  }
  if (h.header_size > n) {
    return absl::DataLossError(absl::StrFormat(
        "truncated: expected at least %d bytes (the header), found %d", h.header_size, n));
  }
  if (HeaderChecksum(p, h.header_size) != h.header_checksum) {
    return absl::DataLossError("header checksum mismatch");
  }
  if (h.file_size != n) {
    if (h.file_size > n) {
      return absl::DataLossError(
          absl::StrFormat("truncated: expected %d bytes, found %d", h.file_size, n));
    }
    return absl::DataLossError(absl::StrFormat(
        "size mismatch: expected %d bytes, found %d (trailing data)", h.file_size, n));
  }
  return h;
}

// The header's element counts, within the int32 id range.
absl::StatusOr<Counts> HeaderCounts(const FileHeader& h) {
  Counts counts;
  counts.num_vertices = h.num_vertices;
  counts.num_faces = h.num_faces;
  counts.num_samples = h.num_samples;
  counts.num_triangles = h.num_triangles;
  counts.num_bvh_nodes = h.num_bvh_nodes;
  if (counts.num_vertices > kInt32Max || 3 * counts.num_faces > kInt32Max ||
      counts.num_samples > kInt32Max || counts.num_triangles > kInt32Max ||
      counts.num_bvh_nodes > kInt32Max) {
    return absl::DataLossError("header counts exceed the int32 id range");
  }
  if (h.params.num_samples != h.num_samples) {
    return absl::DataLossError(absl::StrFormat("header: params.num_samples %d != num_samples %d",
                                               h.params.num_samples, h.num_samples));
  }
  return counts;
}

// A byte range [first, first + second) of the image.
using ByteRange = std::pair<uint64_t, uint64_t>;

// The sections of the image, by kSpecs index (unknown ids of a later minor
// version are skipped). Each must fit, be aligned, match its checksum and
// hold the elements `counts` implies; the required ones must be there.
// Appends the byte ranges of the table and of every section to `used`.
absl::Status FindSections(const uint8_t* p, size_t n, const FileHeader& h, const Counts& counts,
                          std::optional<SectionEntry> (&found)[kNumSpecs],
                          std::vector<ByteRange>* used) {
  const uint64_t table_offset = h.section_table_offset;
  const uint64_t table_bytes = uint64_t{h.num_sections} * sizeof(SectionEntry);
  if (table_offset < h.header_size || table_offset % alignof(SectionEntry) != 0) {
    return absl::DataLossError(absl::StrFormat("bad section table offset %d", table_offset));
  }
  if (table_offset > n || table_bytes > n - table_offset) {
    return absl::DataLossError(
        absl::StrFormat("section table (%d entries at offset %d) does not fit in %d bytes",
                        h.num_sections, table_offset, n));
  }
  if (Checksum(p + table_offset, table_bytes) != h.table_checksum) {
    return absl::DataLossError("section table checksum mismatch");
  }
  std::vector<SectionEntry> entries(h.num_sections);
  if (table_bytes > 0) std::memcpy(entries.data(), p + table_offset, table_bytes);
  used->emplace_back(table_offset, table_bytes);

  for (size_t i = 0; i < entries.size(); ++i) {
    const SectionEntry& e = entries[i];
    const int spec = SpecIndex(e.id);
    const std::string name = spec >= 0 ? kSpecs[spec].name : absl::StrCat("with id ", e.id);
    if (e.offset % kAlignment != 0) {
      return absl::DataLossError(
          absl::StrFormat("section %s: offset %d is not 64-byte aligned", name, e.offset));
    }
    if (e.offset > n || e.size > n - e.offset) {
      return absl::DataLossError(
          absl::StrFormat("section %s: %d bytes at offset %d do not fit in the file (%d bytes)",
                          name, e.size, e.offset, n));
    }
    if (Checksum(p + e.offset, e.size) != e.checksum) {
      return absl::DataLossError(absl::StrFormat("section %s: checksum mismatch", name));
    }
    if (e.size > 0) used->emplace_back(e.offset, e.size);
    if (spec < 0) continue;  // from a later minor version: ignored
    if (found[spec].has_value()) {
      return absl::DataLossError(absl::StrFormat("section %s appears twice", name));
    }
    if (e.element_size != kSpecs[spec].element_size) {
      return absl::DataLossError(absl::StrFormat("section %s: element size %d, expected %d", name,
                                                 e.element_size, kSpecs[spec].element_size));
    }
    const std::optional<uint64_t> count = ExpectedCount(kSpecs[spec].id, counts);
    if (count.has_value() && e.size != *count * e.element_size) {
      return absl::DataLossError(
          absl::StrFormat("section %s: %d bytes, expected %d (%d elements of %d bytes)", name,
                          e.size, *count * e.element_size, *count, e.element_size));
    }
    found[spec] = e;
  }
  // The matrix: in full before 3.0, its lower triangle in 3.x, in codes
  // with their scale from 4.0; only the sections of the file's layout. The
  // vertex records of the file's version, and the derivable sections.
  for (size_t s = 0; s < kNumSpecs; ++s) {
    const Presence presence = PresenceIn(h.format_major, s, counts);
    if (!found[s].has_value() && presence == Presence::kRequired) {
      return absl::DataLossError(absl::StrFormat("missing section: %s", kSpecs[s].name));
    }
    if (found[s].has_value() && presence == Presence::kAbsent) {
      return absl::DataLossError(absl::StrFormat("a format %d.%d index with the section %s",
                                                 h.format_major, h.format_minor, kSpecs[s].name));
    }
  }
  return absl::OkStatus();
}

// Every byte of an image of `n` bytes outside the `used` ranges (which must
// not overlap) is zero padding.
absl::Status CheckPadding(const uint8_t* p, size_t n, std::vector<ByteRange> used) {
  std::sort(used.begin(), used.end());
  uint64_t end = 0;
  for (const auto& [offset, size] : used) {
    if (offset < end) {
      return absl::DataLossError(absl::StrFormat("overlapping sections at byte %d", offset));
    }
    for (uint64_t b = end; b < offset; ++b) {
      if (p[b] != 0) return absl::DataLossError(absl::StrFormat("non-zero padding at byte %d", b));
    }
    end = offset + size;
  }
  for (uint64_t b = end; b < n; ++b) {
    if (p[b] != 0) return absl::DataLossError(absl::StrFormat("non-zero padding at byte %d", b));
  }
  return absl::OkStatus();
}

// The sections FindSections found in the image at `base`, as typed views
// (empty when absent).
struct FoundSections {
  const uint8_t* base;
  const std::optional<SectionEntry> (&found)[kNumSpecs];

  const std::optional<SectionEntry>& Entry(SectionId id) const {
    return found[SpecIndex(static_cast<uint32_t>(id))];
  }
  template <class T>
  std::span<const T> View(SectionId id) const {
    return SectionView<T>(base, Entry(id));
  }
  std::string_view Text(SectionId id) const {
    const std::span<const char> text = View<char>(id);
    return std::string_view(text.data(), text.size());
  }
};

// The sample matrix in the layout of the file's format version, of m
// samples.
SampleMatrix MatrixOf(const FileHeader& h, const FoundSections& s, int32_t m) {
  if (h.format_major >= kCodedFormatMajor) {
    return SampleMatrix::Coded(s.View<PackedCode>(SectionId::kSampleDistancesCoded), m,
                               s.View<DistanceCodeRecord>(SectionId::kDistanceCode)[0].scale);
  }
  if (h.format_major >= kPackedFormatMajor) {
    return SampleMatrix::Lower(s.View<float>(SectionId::kSampleDistancesLower), m);
  }
  return SampleMatrix::Full(s.View<float>(SectionId::kSampleDistances), m);
}

// The split of `faces` from its sections, dense or sparse, as records or
// codes, each only in the format versions that hold it.
absl::StatusOr<SplitView> ReadSplit(const FileHeader& h, const FoundSections& s,
                                    std::span<const int32_t> faces) {
  const auto coarse_faces = s.View<int32_t>(SectionId::kCoarseFaces);
  const auto split_faces = s.View<SplitFaceRecord>(SectionId::kSplitFaces);
  const auto split_coarse = s.View<SplitCoarseRecord>(SectionId::kSplitCoarseFaces);
  const auto split_pieces = s.View<SplitPieceRecord>(SectionId::kSplitPieces);
  const auto split_face_codes = s.View<SplitFaceCode>(SectionId::kSplitFaceCodes);
  const auto split_piece_codes = s.View<SplitPieceCode>(SectionId::kSplitPieceCodes);
  const bool dense_split =
      !split_faces.empty() || !coarse_faces.empty() || !split_face_codes.empty();
  const bool sparse_split =
      !split_coarse.empty() || !split_pieces.empty() || !split_piece_codes.empty();
  if ((!split_faces.empty() && !split_face_codes.empty()) ||
      (!split_pieces.empty() && !split_piece_codes.empty())) {
    return absl::DataLossError("an index with both the records and the codes of its split");
  }
  if (dense_split && sparse_split) {
    return absl::DataLossError("an index with both dense and sparse split sections");
  }
  if ((h.format_major < kSplitFormatMajor && (dense_split || h.params.split_vertices != 0)) ||
      (h.format_major < kSparseSplitFormatMajor && sparse_split) ||
      (h.format_major == kSparseSplitFormatMajor && dense_split)) {
    return absl::DataLossError(absl::StrFormat("a format %d.%d index with %s split sections",
                                               h.format_major, h.format_minor,
                                               sparse_split ? "sparse" : "dense"));
  }
  if (!split_piece_codes.empty()) {
    return SplitView::Sparse(faces, split_coarse, split_piece_codes, absl::StatusCode::kDataLoss);
  }
  if (sparse_split) {
    return SplitView::Sparse(faces, split_coarse, split_pieces, absl::StatusCode::kDataLoss);
  }
  if (!split_face_codes.empty()) {
    return SplitView::Dense(coarse_faces, split_face_codes, faces.size() / 3,
                            absl::StatusCode::kDataLoss);
  }
  return SplitView::Dense(coarse_faces, split_faces, faces.size() / 3, absl::StatusCode::kDataLoss);
}

}  // namespace

uint64_t MeshHash(std::span<const double> positions, std::span<const int32_t> faces) {
  XXH64_state_t state;
  XXH64_reset(&state, 0);
  XXH64_update(&state, positions.data(), positions.size_bytes());
  XXH64_update(&state, faces.data(), faces.size_bytes());
  return XXH64_digest(&state);
}

absl::StatusOr<std::shared_ptr<const Index>> Index::Open(const std::string& path) {
  struct stat st;
  GEODEX_ASSIGN_OR_RETURN(const int fd, OpenForReading(path, &st));
  if (!S_ISREG(st.st_mode)) {
    ::close(fd);
    return absl::FailedPreconditionError(absl::StrCat(path, ": not a regular file"));
  }
  std::shared_ptr<Index> index(new Index());
  index->size_ = static_cast<size_t>(st.st_size);
  if (index->size_ > 0) {  // mmap rejects length 0; an empty file fails validation below
    void* map = ::mmap(nullptr, index->size_, PROT_READ, MAP_SHARED, fd, 0);
    if (map == MAP_FAILED) {
      const int err = errno;
      ::close(fd);
      return ErrnoError(err, "cannot mmap", path);
    }
    index->base_ = static_cast<const uint8_t*>(map);
    index->mapped_ = true;
    ::madvise(map, index->size_, MADV_WILLNEED);  // advisory; failure is harmless
  }
  ::close(fd);  // the mapping keeps the file open
  GEODEX_RETURN_IF_ERROR(WithPath(index->Validate(), path));
  return std::shared_ptr<const Index>(std::move(index));
}

absl::StatusOr<std::shared_ptr<const Index>> Index::FromBytes(std::string bytes) {
  std::shared_ptr<Index> index(new Index());
  index->size_ = bytes.size();
  index->owned_.reset(new uint8_t[bytes.size() + kAlignment]);
  const uintptr_t raw = reinterpret_cast<uintptr_t>(index->owned_.get());
  uint8_t* aligned = index->owned_.get() + (AlignUp(raw) - raw);
  if (!bytes.empty()) std::memcpy(aligned, bytes.data(), bytes.size());
  index->base_ = aligned;
  GEODEX_RETURN_IF_ERROR(index->Validate());
  return std::shared_ptr<const Index>(std::move(index));
}

Index::~Index() {
  if (mapped_) ::munmap(const_cast<uint8_t*>(base_), size_);
}

std::string Index::builder_version() const {
  const char* v = header_->builder_version;
  return std::string(v, strnlen(v, sizeof(header_->builder_version)));
}

// Every byte of a valid file is covered by a checksum or must be zero
// padding, so any corruption is seen.
absl::Status Index::Validate() {
  const uint8_t* p = base_;
  const size_t n = size_;
  GEODEX_ASSIGN_OR_RETURN(const FileHeader h, ValidateHeader(p, n));
  GEODEX_ASSIGN_OR_RETURN(const Counts counts, HeaderCounts(h));
  std::optional<SectionEntry> found[kNumSpecs];
  std::vector<ByteRange> used = {{0, h.header_size}};
  GEODEX_RETURN_IF_ERROR(FindSections(p, n, h, counts, found, &used));
  GEODEX_RETURN_IF_ERROR(CheckPadding(p, n, std::move(used)));

  // Sections are 64-byte aligned in a 64-byte aligned image: typed views are
  // properly aligned.
  const FoundSections s{p, found};
  header_ = reinterpret_cast<const FileHeader*>(p);
  positions_ = s.View<double>(SectionId::kPositions);
  faces_ = s.View<int32_t>(SectionId::kFaces);
  twins_ = s.View<int32_t>(SectionId::kTwins);
  samples_ = s.View<int32_t>(SectionId::kSamples);
  sample_distances_ = s.View<float>(SectionId::kSampleDistances);
  sample_distances_lower_ = s.View<float>(SectionId::kSampleDistancesLower);
  sample_distances_coded_ = s.View<PackedCode>(SectionId::kSampleDistancesCoded);
  const auto distance_code = s.View<DistanceCodeRecord>(SectionId::kDistanceCode);
  triangles_ = s.View<GeodesicTriangle>(SectionId::kTriangles);
  const bool derived_format = h.format_major >= kDerivedFormatMajor;
  std::span<const VertexRecordWithCorners> legacy_vertices;
  if (derived_format) {
    vertices_ = s.View<VertexRecord>(SectionId::kCompactVertexRecords);
  } else {
    // 1.x-5.x copied each record's corners in: checked against its
    // triangle's and left out, so that every version answers from one kind
    // of record.
    legacy_vertices = s.View<VertexRecordWithCorners>(SectionId::kVertexRecords);
    derived_vertices_ = internal::WithoutCorners(legacy_vertices);
    vertices_ = derived_vertices_;
  }
  // From 6.0 the twins and the BVH may be left out, to be derived here (the
  // BVH below, once the positions and faces it reads are checked).
  const bool derive_bvh = derived_format && !s.Entry(SectionId::kFaceBvh).has_value();
  if (derived_format &&
      s.Entry(SectionId::kFaceBvh).has_value() != s.Entry(SectionId::kBvhFaces).has_value()) {
    return absl::DataLossError("a format 6 index with one of the two BVH sections");
  }
  if (derived_format && !s.Entry(SectionId::kTwins).has_value()) {
    GEODEX_ASSIGN_OR_RETURN(derived_twins_, DeriveTwins(faces_, absl::StatusCode::kDataLoss));
    twins_ = derived_twins_;
  }
  bvh_nodes_ = s.View<BvhNode>(SectionId::kFaceBvh);
  bvh_faces_ = s.View<int32_t>(SectionId::kBvhFaces);
  report_ = s.Text(SectionId::kReport);
  accuracy_ = s.View<AccuracyRecord>(SectionId::kAccuracy);
  input_faces_ = s.View<InputFaceRecord>(SectionId::kInputFaces);
  vertex_copies_ = s.View<int32_t>(SectionId::kVertexCopies);
  spread_bounds_ = s.View<SpreadBoundRecord>(SectionId::kSpreadBounds);
  GEODEX_ASSIGN_OR_RETURN(split_, ReadSplit(h, s, faces_));
  GEODEX_RETURN_IF_ERROR(CheckAccuracy(accuracy_, absl::StatusCode::kDataLoss));
  GEODEX_RETURN_IF_ERROR(
      CheckSpreadBounds(spread_bounds_, accuracy_.size(), absl::StatusCode::kDataLoss));

  if (h.format_major >= kCodedFormatMajor && distance_code.size() != 1) {
    return absl::DataLossError("section distance code: expected one record");
  }
  GEODEX_RETURN_IF_ERROR(CheckContents(
      Contents{counts, positions_, faces_, twins_, samples_, sample_distances_,
               sample_distances_lower_, distance_code, vertices_, triangles_, bvh_nodes_,
               bvh_faces_, input_faces_, vertex_copies_, split_,
               h.params.split_vertices, legacy_vertices},
      absl::StatusCode::kDataLoss));
  if (derive_bvh) {
    BuildFaceBvh(positions_, faces_, &derived_bvh_nodes_, &derived_bvh_faces_);
    if (derived_bvh_nodes_.size() != counts.num_bvh_nodes) {
      return absl::DataLossError(absl::StrFormat(
          "face BVH: the header counts %d nodes, the BVH derived from the faces has %d",
          counts.num_bvh_nodes, derived_bvh_nodes_.size()));
    }
    bvh_nodes_ = derived_bvh_nodes_;
    bvh_faces_ = derived_bvh_faces_;
  }
  matrix_ = MatrixOf(h, s, num_samples());
  return absl::OkStatus();
}

IndexData ToIndexData(const Index& index) {
  IndexData d;
  d.builder_version = index.builder_version();
  d.mesh_hash = index.header().mesh_hash;
  d.params = index.header().params;
  auto copy = [](auto span) { return std::vector(span.begin(), span.end()); };
  d.positions = copy(index.positions());
  d.faces = copy(index.faces());
  d.twins = copy(index.twins());
  d.samples = copy(index.samples());
  d.sample_matrix = index.matrix().layout();
  d.coded_as_version_5 = index.header().format_major < kDerivedFormatMajor;
  d.sample_distance_scale = index.matrix().scale();
  if (d.sample_matrix == MatrixLayout::kFull) {
    d.sample_distances = copy(index.sample_distances());
  } else {
    const int32_t m = index.num_samples();
    d.sample_distances.resize(static_cast<size_t>(m) * m);
    for (int32_t a = 0; a < m; ++a) {
      for (int32_t b = 0; b < m; ++b) {
        d.sample_distances[static_cast<size_t>(a) * m + b] =
            static_cast<float>(index.SampleDistance(a, b));
      }
    }
  }
  d.vertices = copy(index.vertices());
  d.triangles = copy(index.triangles());
  d.bvh_nodes = copy(index.bvh_nodes());
  d.bvh_faces = copy(index.bvh_faces());
  d.report = std::string(index.report());
  if (index.accuracy() != nullptr) d.accuracy = {*index.accuracy()};
  if (index.spread_bounds() != nullptr) d.spread_bounds = {*index.spread_bounds()};
  d.input_faces = copy(index.input_faces());
  d.vertex_copies = copy(index.vertex_copies());
  // IndexData holds the split dense, whichever layout the file has.
  const SplitView& split = index.split();
  for (int32_t c = 0; c < split.num_coarse_faces(); ++c) {
    for (int32_t v : split.CoarseFace(c)) d.coarse_faces.push_back(v);
  }
  for (int32_t f = 0; split.split() && f < index.num_faces(); ++f) {
    d.split_faces.push_back(split.Piece(f));
  }
  return d;
}

}  // namespace geodex::index
