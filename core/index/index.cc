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
              std::is_trivially_copyable_v<GeodesicTriangle> &&
              std::is_trivially_copyable_v<BvhNode>);

namespace {

constexpr uint64_t kInt32Max = std::numeric_limits<int32_t>::max();

// What a reader of this version knows about each section. Element sizes are
// those of the scalar or record type (positions: one double, not a vertex).
struct SectionSpec {
  SectionId id;
  uint32_t element_size;
  const char* name;
  bool required;  // must be present (possibly empty) in every file
};

constexpr SectionSpec kSpecs[] = {
    {SectionId::kPositions, sizeof(double), "positions", true},
    {SectionId::kFaces, sizeof(int32_t), "faces", true},
    {SectionId::kTwins, sizeof(int32_t), "twins", true},
    {SectionId::kSamples, sizeof(int32_t), "samples", true},
    // Required by version: the full matrix before 3.0, its lower triangle from 3.0.
    {SectionId::kSampleDistances, sizeof(float), "sample distances", false},
    {SectionId::kVertexRecords, sizeof(VertexRecord), "vertex records", true},
    {SectionId::kTriangles, sizeof(GeodesicTriangle), "geodesic triangles", true},
    {SectionId::kFaceBvh, sizeof(BvhNode), "face BVH", false},
    {SectionId::kBvhFaces, sizeof(int32_t), "BVH faces", false},
    {SectionId::kReport, 1, "report", false},
    {SectionId::kAccuracy, sizeof(AccuracyRecord), "accuracy", false},
    {SectionId::kInputFaces, sizeof(InputFaceRecord), "input faces", false},
    {SectionId::kVertexCopies, sizeof(int32_t), "vertex copies", false},
    {SectionId::kCoarseFaces, sizeof(int32_t), "coarse faces", false},
    {SectionId::kRefinedFaces, sizeof(RefinedFaceRecord), "refined faces", false},
    {SectionId::kSpreadBounds, sizeof(SpreadBoundRecord), "spread bounds", false},
    {SectionId::kSampleDistancesLower, sizeof(float), "sample distances (lower triangle)", false},
};
constexpr size_t kNumSpecs = std::size(kSpecs);

// Index of `id` in kSpecs, or -1 for an id this reader does not know.
int SpecIndex(uint32_t id) {
  for (size_t i = 0; i < kNumSpecs; ++i) {
    if (static_cast<uint32_t>(kSpecs[i].id) == id) return static_cast<int>(i);
  }
  return -1;
}

struct Counts {
  uint64_t num_vertices = 0;
  uint64_t num_faces = 0;
  uint64_t num_samples = 0;
  uint64_t num_triangles = 0;
  uint64_t num_bvh_nodes = 0;
};

// Elements a known section must hold; nullopt when any number is fine. Every
// product fits in uint64_t (the counts are at most 2^31).
std::optional<uint64_t> ExpectedCount(SectionId id, const Counts& c) {
  switch (id) {
    case SectionId::kPositions:
      return 3 * c.num_vertices;
    case SectionId::kFaces:
    case SectionId::kTwins:
      return 3 * c.num_faces;
    case SectionId::kSamples:
      return c.num_samples;
    case SectionId::kSampleDistances:
      return c.num_samples * c.num_samples;
    case SectionId::kSampleDistancesLower:
      return c.num_samples * (c.num_samples - std::min<uint64_t>(c.num_samples, 1)) / 2;
    case SectionId::kVertexRecords:
      return c.num_vertices;
    case SectionId::kTriangles:
      return c.num_triangles;
    case SectionId::kFaceBvh:
      return c.num_bvh_nodes;
    case SectionId::kBvhFaces:
      return c.num_bvh_nodes > 0 ? c.num_faces : 0;
    case SectionId::kReport:
    case SectionId::kAccuracy:
    case SectionId::kInputFaces:
    case SectionId::kVertexCopies:
    case SectionId::kCoarseFaces:
    case SectionId::kRefinedFaces:
    case SectionId::kSpreadBounds:
      return std::nullopt;
  }
  return std::nullopt;
}

uint64_t AlignUp(uint64_t x) { return (x + kAlignment - 1) / kAlignment * kAlignment; }

uint64_t Checksum(const void* data, size_t size) { return XXH64(data, size, 0); }

// XXH64 of the first `header_size` bytes with the header_checksum field read
// as zero. `header_size` >= sizeof(FileHeader) (a later minor version may
// append fields; they are covered too).
uint64_t HeaderChecksum(const uint8_t* p, size_t header_size) {
  constexpr size_t kField = offsetof(FileHeader, header_checksum);
  constexpr uint64_t kZero = 0;
  XXH64_state_t state;
  XXH64_reset(&state, 0);
  XXH64_update(&state, p, kField);
  XXH64_update(&state, &kZero, sizeof(kZero));
  XXH64_update(&state, p + kField + sizeof(kZero), header_size - kField - sizeof(kZero));
  return XXH64_digest(&state);
}

// The arrays of an index, wherever they live: checked the same way by the
// writer (InvalidArgument) and the reader (DataLoss), so that the writer never
// produces a file the reader rejects. Sizes are already consistent.
struct Contents {
  Counts counts;
  std::span<const double> positions;
  std::span<const int32_t> faces;
  std::span<const int32_t> twins;
  std::span<const int32_t> samples;
  std::span<const float> sample_distances;
  std::span<const float> sample_distances_lower;
  std::span<const VertexRecord> vertices;
  std::span<const GeodesicTriangle> triangles;
  std::span<const BvhNode> bvh_nodes;
  std::span<const int32_t> bvh_faces;
  std::span<const InputFaceRecord> input_faces;
  std::span<const int32_t> vertex_copies;
  std::span<const int32_t> coarse_faces;
  std::span<const RefinedFaceRecord> refined_faces;
  uint64_t refinement_vertices = 0;
};

bool InRange(int64_t x, int64_t lo, int64_t hi) { return x >= lo && x < hi; }
// Non-negative and not NaN; +inf allowed.
bool NonNegative(float x) { return x >= 0; }

// The accuracy section: absent or one record of finite, non-negative figures.
absl::Status CheckAccuracy(std::span<const AccuracyRecord> records, absl::StatusCode code) {
  if (records.empty()) return absl::OkStatus();
  if (records.size() > 1) {
    return absl::Status(code, absl::StrFormat("accuracy: %d records, expected 1", records.size()));
  }
  const AccuracyRecord& r = records[0];
  std::vector<float> values = {r.scale_length, r.uniform_rms, r.uniform_far_p99};
  for (int b = 0; b < kAccuracyBins; ++b) {
    values.insert(values.end(), {r.unfold_bound[0][b], r.unfold_bound[1][b]});
    for (int k = 0; k < 4; ++k) values.push_back(r.trace_bound[k][b]);
  }
  for (int b = 0; b < 4; ++b) values.insert(values.end(), {r.rms[b], r.p99[b]});
  for (float v : values) {
    if (!(v >= 0) || !std::isfinite(v)) {
      return absl::Status(code, "accuracy: a figure is negative, NaN or infinite");
    }
  }
  if (!(r.scale_length > 0) || r.bound_quantile_permille > 1000) {
    return absl::Status(code, "accuracy: bad scale length or quantile");
  }
  return absl::OkStatus();
}

// The spread-bound section: absent, or one record of finite, non-negative
// figures beside an accuracy record.
absl::Status CheckSpreadBounds(std::span<const SpreadBoundRecord> records, size_t num_accuracy,
                               absl::StatusCode code) {
  if (records.empty()) return absl::OkStatus();
  if (records.size() > 1 || num_accuracy != 1) {
    return absl::Status(code,
                        absl::StrFormat("spread bounds: %d records beside %d accuracy records",
                                        records.size(), num_accuracy));
  }
  for (int k = 0; k < 2; ++k) {
    for (int b = 0; b < kAccuracyBins; ++b) {
      for (float v : {records[0].epsilon[k][b], records[0].factor[k][b]}) {
        if (!(v >= 0) || !std::isfinite(v)) {
          return absl::Status(code, "spread bounds: a figure is negative, NaN or infinite");
        }
      }
    }
  }
  return absl::OkStatus();
}

absl::Status CheckContents(const Contents& c, absl::StatusCode code) {
  auto fail = [code](std::string message) { return absl::Status(code, message); };
  const int64_t nv = static_cast<int64_t>(c.counts.num_vertices);
  const int64_t nf = static_cast<int64_t>(c.counts.num_faces);
  const int64_t m = static_cast<int64_t>(c.counts.num_samples);
  const int64_t nt = static_cast<int64_t>(c.counts.num_triangles);
  const int64_t nb = static_cast<int64_t>(c.bvh_nodes.size());

  for (size_t i = 0; i < c.positions.size(); ++i) {
    if (!std::isfinite(c.positions[i])) {
      return fail(absl::StrFormat("vertex %d: coordinate %d is not finite (%g)", i / 3, i % 3,
                                  c.positions[i]));
    }
  }
  for (size_t i = 0; i < c.faces.size(); ++i) {
    if (!InRange(c.faces[i], 0, nv)) {
      return fail(
          absl::StrFormat("face %d: vertex id %d out of range [0, %d)", i / 3, c.faces[i], nv));
    }
  }
  for (size_t i = 0; i < c.twins.size(); ++i) {
    if (!InRange(c.twins[i], -1, 3 * nf)) {
      return fail(
          absl::StrFormat("half-edge %d: twin %d out of range [-1, %d)", i, c.twins[i], 3 * nf));
    }
  }
  for (size_t i = 0; i < c.samples.size(); ++i) {
    if (!InRange(c.samples[i], 0, nv)) {
      return fail(
          absl::StrFormat("sample %d: vertex id %d out of range [0, %d)", i, c.samples[i], nv));
    }
  }
  // +inf is a legitimate distance between samples on different components.
  for (size_t i = 0; i < c.sample_distances.size(); ++i) {
    if (!NonNegative(c.sample_distances[i])) {
      return fail(absl::StrFormat("sample distance (%d, %d) is negative or NaN (%g)", i / m, i % m,
                                  c.sample_distances[i]));
    }
  }
  for (size_t i = 0; i < c.sample_distances_lower.size(); ++i) {
    if (!NonNegative(c.sample_distances_lower[i])) {
      return fail(
          absl::StrFormat("sample distance %d of the lower triangle is negative or NaN (%g)", i,
                          c.sample_distances_lower[i]));
    }
  }
  for (size_t v = 0; v < c.vertices.size(); ++v) {
    const VertexRecord& r = c.vertices[v];
    if (!InRange(r.triangle, -1, nt)) {
      return fail(absl::StrFormat("vertex record %d: geodesic triangle %d out of range [-1, %d)", v,
                                  r.triangle, nt));
    }
    for (int k = 0; k < 3; ++k) {
      if (r.triangle == -1 ? r.corner[k] != -1 : !InRange(r.corner[k], 0, m)) {
        return fail(absl::StrFormat(
            "vertex record %d: corner %d is %d, expected %s", v, k, r.corner[k],
            r.triangle == -1 ? "-1 (no triangle)" : absl::StrFormat("a sample in [0, %d)", m)));
      }
      // Vertices without a triangle may carry +inf; the others need real values.
      const bool ok = r.triangle == -1 ? NonNegative(r.distance[k])
                                       : std::isfinite(r.distance[k]) && r.distance[k] >= 0;
      if (!ok) {
        return fail(
            absl::StrFormat("vertex record %d: distance %d is invalid (%g)", v, k, r.distance[k]));
      }
    }
  }
  for (size_t t = 0; t < c.triangles.size(); ++t) {
    const GeodesicTriangle& g = c.triangles[t];
    for (int k = 0; k < 3; ++k) {
      if (!InRange(g.corner[k], 0, m)) {
        return fail(absl::StrFormat("geodesic triangle %d: corner %d is %d, out of range [0, %d)",
                                    t, k, g.corner[k], m));
      }
      if (!InRange(g.neighbor[k], -1, nt)) {
        return fail(
            absl::StrFormat("geodesic triangle %d: neighbour %d is %d, out of range [-1, %d)", t, k,
                            g.neighbor[k], nt));
      }
    }
  }
  // Children after their parent: every traversal terminates.
  for (int64_t i = 0; i < nb; ++i) {
    const BvhNode& b = c.bvh_nodes[i];
    for (int k = 0; k < 3; ++k) {
      if (!(b.lo[k] <= b.hi[k])) {
        return fail(
            absl::StrFormat("BVH node %d: bad box on axis %d [%g, %g]", i, k, b.lo[k], b.hi[k]));
      }
    }
    const bool ok = b.count > 0 ? b.first >= 0 && int64_t{b.first} + b.count <= nf
                                : b.count == 0 && b.first > i && int64_t{b.first} + 1 < nb;
    if (!ok) {
      return fail(
          absl::StrFormat("BVH node %d: first %d, count %d out of range (%d nodes, %d "
                          "faces)",
                          i, b.first, b.count, nb, nf));
    }
  }
  GEODEX_RETURN_IF_ERROR(CheckInputIds({nv, nf, c.input_faces, c.vertex_copies, c.coarse_faces,
                                        c.refined_faces, c.refinement_vertices},
                                       code));
  if (!c.bvh_faces.empty()) {
    std::vector<bool> seen(nf, false);
    for (size_t i = 0; i < c.bvh_faces.size(); ++i) {
      const int32_t f = c.bvh_faces[i];
      if (!InRange(f, 0, nf) || seen[f]) {
        return fail(
            absl::StrFormat("BVH face %d: face %d out of range [0, %d) or repeated", i, f, nf));
      }
      seen[f] = true;
    }
  }
  return absl::OkStatus();
}

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
  if (h.format_major != kFormatMajor && h.format_major != kRefinedFormatMajor &&
      h.format_major != kPackedFormatMajor) {
    return absl::FailedPreconditionError(absl::StrFormat(
        "index format version %d.%d is not supported by this reader (version %d.%d)",
        h.format_major, h.format_minor, kPackedFormatMajor, kPackedFormatMinor));
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
  // The matrix: in full before 3.0, its lower triangle from 3.0, never both.
  const SectionId matrix = h.format_major >= kPackedFormatMajor ? SectionId::kSampleDistancesLower
                                                                : SectionId::kSampleDistances;
  const SectionId other = h.format_major >= kPackedFormatMajor ? SectionId::kSampleDistances
                                                               : SectionId::kSampleDistancesLower;
  for (size_t s = 0; s < kNumSpecs; ++s) {
    const std::optional<uint64_t> count = ExpectedCount(kSpecs[s].id, counts);
    if (!found[s].has_value() &&
        (kSpecs[s].required || kSpecs[s].id == matrix || count.value_or(0) > 0) &&
        kSpecs[s].id != other) {
      return absl::DataLossError(absl::StrFormat("missing section: %s", kSpecs[s].name));
    }
    if (found[s].has_value() && kSpecs[s].id == other) {
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

}  // namespace

uint64_t MeshHash(std::span<const double> positions, std::span<const int32_t> faces) {
  XXH64_state_t state;
  XXH64_reset(&state, 0);
  XXH64_update(&state, positions.data(), positions.size_bytes());
  XXH64_update(&state, faces.data(), faces.size_bytes());
  return XXH64_digest(&state);
}

absl::StatusOr<std::string> SerializeIndex(const IndexData& d) {
  auto bad = [](std::string message) { return absl::InvalidArgumentError(message); };
  if (d.positions.size() % 3 != 0) {
    return bad(absl::StrFormat("positions: %d values, not a multiple of 3", d.positions.size()));
  }
  if (d.faces.size() % 3 != 0) {
    return bad(absl::StrFormat("faces: %d values, not a multiple of 3", d.faces.size()));
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
    return bad("too many vertices, faces, samples, triangles or BVH nodes for int32 ids");
  }
  if (d.twins.size() != d.faces.size()) {
    return bad(absl::StrFormat("twins: %d values, expected %d (3 per face)", d.twins.size(),
                               d.faces.size()));
  }
  if (d.sample_distances.size() != counts.num_samples * counts.num_samples) {
    return bad(absl::StrFormat("sample_distances: %d values, expected %d (num_samples^2)",
                               d.sample_distances.size(), counts.num_samples * counts.num_samples));
  }
  // The matrix stored once (3.0): its lower triangle, checked symmetric.
  std::vector<float> lower;
  if (d.pack_sample_distances) {
    const size_t m = counts.num_samples;
    lower.reserve(m * (m - std::min<size_t>(m, 1)) / 2);
    for (size_t a = 0; a < m; ++a) {
      if (d.sample_distances[a * m + a] != 0) {
        return bad(absl::StrFormat("sample_distances: (%d, %d) is not 0", a, a));
      }
      for (size_t b = 0; b < a; ++b) {
        const float x = d.sample_distances[a * m + b];
        if (!(x == d.sample_distances[b * m + a]) && !(std::isnan(x))) {
          return bad(absl::StrFormat("sample_distances: (%d, %d) and (%d, %d) differ", a, b, b, a));
        }
        lower.push_back(x);
      }
    }
  }
  const std::span<const float> full_matrix = d.pack_sample_distances
                                                 ? std::span<const float>()
                                                 : std::span<const float>(d.sample_distances);
  if (d.vertices.size() != counts.num_vertices) {
    return bad(absl::StrFormat("vertices: %d records, expected %d (one per vertex)",
                               d.vertices.size(), counts.num_vertices));
  }
  const uint64_t expected_bvh_faces = counts.num_bvh_nodes > 0 ? counts.num_faces : 0;
  if (d.bvh_faces.size() != expected_bvh_faces) {
    return bad(absl::StrFormat("bvh_faces: %d values, expected %d", d.bvh_faces.size(),
                               expected_bvh_faces));
  }
  if (d.params.num_samples != counts.num_samples) {
    return bad(absl::StrFormat("params.num_samples is %d but there are %d samples",
                               d.params.num_samples, counts.num_samples));
  }
  if (d.builder_version.size() >= sizeof(FileHeader::builder_version) ||
      d.builder_version.find('\0') != std::string::npos) {
    return bad(absl::StrFormat("builder_version must be under %d bytes without NULs: \"%s\"",
                               sizeof(FileHeader::builder_version), d.builder_version));
  }
  GEODEX_RETURN_IF_ERROR(CheckContents(
      Contents{counts, d.positions, d.faces, d.twins, d.samples, d.sample_distances, lower,
               d.vertices, d.triangles, d.bvh_nodes, d.bvh_faces, d.input_faces, d.vertex_copies,
               d.coarse_faces, d.refined_faces, d.params.refinement_vertices},
      absl::StatusCode::kInvalidArgument));
  GEODEX_RETURN_IF_ERROR(CheckAccuracy(d.accuracy, absl::StatusCode::kInvalidArgument));
  GEODEX_RETURN_IF_ERROR(
      CheckSpreadBounds(d.spread_bounds, d.accuracy.size(), absl::StatusCode::kInvalidArgument));

  // Every section is written, empty ones with size 0, in kSpecs order (but the
  // input-id sections, below).
  struct Piece {
    const void* data;
    uint64_t size;
  };
  const Piece pieces[kNumSpecs] = {
      {d.positions.data(), d.positions.size() * sizeof(double)},
      {d.faces.data(), d.faces.size() * sizeof(int32_t)},
      {d.twins.data(), d.twins.size() * sizeof(int32_t)},
      {d.samples.data(), d.samples.size() * sizeof(int32_t)},
      {full_matrix.data(), full_matrix.size() * sizeof(float)},
      {d.vertices.data(), d.vertices.size() * sizeof(VertexRecord)},
      {d.triangles.data(), d.triangles.size() * sizeof(GeodesicTriangle)},
      {d.bvh_nodes.data(), d.bvh_nodes.size() * sizeof(BvhNode)},
      {d.bvh_faces.data(), d.bvh_faces.size() * sizeof(int32_t)},
      {d.report.data(), d.report.size()},
      {d.accuracy.data(), d.accuracy.size() * sizeof(AccuracyRecord)},
      {d.input_faces.data(), d.input_faces.size() * sizeof(InputFaceRecord)},
      {d.vertex_copies.data(), d.vertex_copies.size() * sizeof(int32_t)},
      {d.coarse_faces.data(), d.coarse_faces.size() * sizeof(int32_t)},
      {d.refined_faces.data(), d.refined_faces.size() * sizeof(RefinedFaceRecord)},
      {d.spread_bounds.data(), d.spread_bounds.size() * sizeof(SpreadBoundRecord)},
      {lower.data(), lower.size() * sizeof(float)},
  };
  // The input-id sections (1.2, 2.0) are written only when the mesh was
  // repaired or refined, so that the index of a mesh that needed neither
  // keeps the 1.1 layout.
  // The matrix section of the layout written, even when empty (no samples).
  const bool packed = d.pack_sample_distances;
  auto written = [&pieces, packed](size_t i) {
    const SectionId id = kSpecs[i].id;
    if (id == SectionId::kSampleDistances) return !packed;
    if (id == SectionId::kSampleDistancesLower) return packed;
    return pieces[i].size > 0 || (id != SectionId::kInputFaces && id != SectionId::kVertexCopies &&
                                  id != SectionId::kCoarseFaces && id != SectionId::kRefinedFaces &&
                                  id != SectionId::kSpreadBounds);
  };
  const bool refined = !d.refined_faces.empty();
  size_t num_sections = 0;
  for (size_t i = 0; i < kNumSpecs; ++i) num_sections += written(i) ? 1 : 0;
  SectionEntry entries[kNumSpecs];
  std::memset(entries, 0, sizeof(entries));
  const uint64_t table_offset = sizeof(FileHeader);
  const uint64_t table_bytes = num_sections * sizeof(SectionEntry);
  uint64_t cursor = table_offset + table_bytes;
  size_t piece_of[kNumSpecs];
  for (size_t i = 0, e = 0; i < kNumSpecs; ++i) {
    if (!written(i)) continue;
    cursor = AlignUp(cursor);
    piece_of[e] = i;
    entries[e].id = static_cast<uint32_t>(kSpecs[i].id);
    entries[e].element_size = kSpecs[i].element_size;
    entries[e].offset = cursor;
    entries[e].size = pieces[i].size;
    entries[e].checksum = Checksum(pieces[i].data, pieces[i].size);
    cursor += pieces[i].size;
    ++e;
  }
  const uint64_t file_size = cursor;

  FileHeader h;
  std::memset(static_cast<void*>(&h), 0, sizeof(h));  // padding included
  std::memcpy(h.magic, kMagic, sizeof(kMagic));
  h.format_major = packed ? kPackedFormatMajor : refined ? kRefinedFormatMajor : kFormatMajor;
  h.format_minor = packed ? kPackedFormatMinor : refined ? kRefinedFormatMinor : kFormatMinor;
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
  h.num_sections = static_cast<uint32_t>(num_sections);
  h.section_table_offset = table_offset;
  h.file_size = file_size;
  h.table_checksum = Checksum(entries, table_bytes);
  h.header_checksum = 0;
  h.header_checksum = HeaderChecksum(reinterpret_cast<const uint8_t*>(&h), sizeof(h));

  std::string out(file_size, '\0');  // zero padding everywhere
  std::memcpy(out.data(), &h, sizeof(h));
  std::memcpy(out.data() + table_offset, entries, table_bytes);
  for (size_t e = 0; e < num_sections; ++e) {
    const Piece& piece = pieces[piece_of[e]];
    if (piece.size > 0) std::memcpy(out.data() + entries[e].offset, piece.data, piece.size);
  }
  return out;
}

absl::Status WriteIndexFile(const IndexData& data, const std::string& path) {
  GEODEX_ASSIGN_OR_RETURN(const std::string bytes, SerializeIndex(data));
  return AtomicWriteFile(path, bytes);
}

// The file must not shrink while mapped (SIGBUS): writers replace files by
// rename (WriteIndexFile), which leaves this mapping on the old inode.
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
  auto entry = [&found](SectionId id) -> const std::optional<SectionEntry>& {
    return found[SpecIndex(static_cast<uint32_t>(id))];
  };
  header_ = reinterpret_cast<const FileHeader*>(p);
  positions_ = SectionView<double>(p, entry(SectionId::kPositions));
  faces_ = SectionView<int32_t>(p, entry(SectionId::kFaces));
  twins_ = SectionView<int32_t>(p, entry(SectionId::kTwins));
  samples_ = SectionView<int32_t>(p, entry(SectionId::kSamples));
  sample_distances_ = SectionView<float>(p, entry(SectionId::kSampleDistances));
  sample_distances_lower_ = SectionView<float>(p, entry(SectionId::kSampleDistancesLower));
  packed_ = h.format_major >= kPackedFormatMajor;
  vertices_ = SectionView<VertexRecord>(p, entry(SectionId::kVertexRecords));
  triangles_ = SectionView<GeodesicTriangle>(p, entry(SectionId::kTriangles));
  bvh_nodes_ = SectionView<BvhNode>(p, entry(SectionId::kFaceBvh));
  bvh_faces_ = SectionView<int32_t>(p, entry(SectionId::kBvhFaces));
  const std::span<const char> report = SectionView<char>(p, entry(SectionId::kReport));
  report_ = std::string_view(report.data(), report.size());
  accuracy_ = SectionView<AccuracyRecord>(p, entry(SectionId::kAccuracy));
  input_faces_ = SectionView<InputFaceRecord>(p, entry(SectionId::kInputFaces));
  vertex_copies_ = SectionView<int32_t>(p, entry(SectionId::kVertexCopies));
  coarse_faces_ = SectionView<int32_t>(p, entry(SectionId::kCoarseFaces));
  refined_faces_ = SectionView<RefinedFaceRecord>(p, entry(SectionId::kRefinedFaces));
  spread_bounds_ = SectionView<SpreadBoundRecord>(p, entry(SectionId::kSpreadBounds));
  if (h.format_major < kRefinedFormatMajor &&
      (!refined_faces_.empty() || !coarse_faces_.empty() || h.params.refinement_vertices != 0)) {
    return absl::DataLossError(absl::StrFormat("a format %d.%d index with refinement sections",
                                               h.format_major, h.format_minor));
  }
  GEODEX_RETURN_IF_ERROR(CheckAccuracy(accuracy_, absl::StatusCode::kDataLoss));
  GEODEX_RETURN_IF_ERROR(
      CheckSpreadBounds(spread_bounds_, accuracy_.size(), absl::StatusCode::kDataLoss));

  return CheckContents(
      Contents{counts, positions_, faces_, twins_, samples_, sample_distances_,
               sample_distances_lower_, vertices_, triangles_, bvh_nodes_, bvh_faces_, input_faces_,
               vertex_copies_, coarse_faces_, refined_faces_, h.params.refinement_vertices},
      absl::StatusCode::kDataLoss);
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
  if (index.packed_sample_distances()) {
    const int32_t m = index.num_samples();
    d.sample_distances.resize(static_cast<size_t>(m) * m);
    for (int32_t a = 0; a < m; ++a) {
      for (int32_t b = 0; b < m; ++b) {
        d.sample_distances[static_cast<size_t>(a) * m + b] = index.SampleDistance(a, b);
      }
    }
    d.pack_sample_distances = true;
  } else {
    d.sample_distances = copy(index.sample_distances());
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
  d.coarse_faces = copy(index.coarse_faces());
  d.refined_faces = copy(index.refined_faces());
  return d;
}

}  // namespace geodex::index
