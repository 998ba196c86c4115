#pragma once

// The section layout of the index file, shared by its reader (index.cc) and
// writer (index_writer.cc): what each section holds, how many elements it
// must have, the alignment and checksums, and the checks of the arrays that
// both apply (the writer with InvalidArgument, the reader with DataLoss), so
// that the writer never produces a file the reader rejects. Internal to
// core/index.

#include <cstddef>
#include <cstdint>
#include <iterator>
#include <limits>
#include <optional>
#include <span>

#include "absl/status/status.h"
#include "core/index/index_format.h"
#include "core/index/sample_matrix.h"
#include "core/index/split_view.h"

namespace geodex::index::internal {

constexpr uint64_t kInt32Max = std::numeric_limits<int32_t>::max();

// What a reader of this version knows about each section. Element sizes are
// those of the scalar or record type (positions: one double, not a vertex).
struct SectionSpec {
  SectionId id;
  uint32_t element_size;
  const char* name;
  // Must be present (possibly empty) in every file; the sections of some
  // versions only are required by version (SectionsOfVersion in index.cc).
  bool required;
};

constexpr SectionSpec kSpecs[] = {
    {SectionId::kPositions, sizeof(double), "positions", true},
    {SectionId::kFaces, sizeof(int32_t), "faces", true},
    // Required before 6.0; from 6.0 left out when derivable (derived_sections.h).
    {SectionId::kTwins, sizeof(int32_t), "twins", false},
    {SectionId::kSamples, sizeof(int32_t), "samples", true},
    // Required by version: the full matrix before 3.0, its lower triangle
    // from 3.0, in codes with their scale from 4.0.
    {SectionId::kSampleDistances, sizeof(float), "sample distances", false},
    // Required by version: with corners before 6.0, without from 6.0.
    {SectionId::kVertexRecords, sizeof(VertexRecordWithCorners), "vertex records", false},
    {SectionId::kTriangles, sizeof(GeodesicTriangle), "geodesic triangles", true},
    {SectionId::kFaceBvh, sizeof(BvhNode), "face BVH", false},
    {SectionId::kBvhFaces, sizeof(int32_t), "BVH faces", false},
    {SectionId::kReport, 1, "report", false},
    {SectionId::kAccuracy, sizeof(AccuracyRecord), "accuracy", false},
    {SectionId::kInputFaces, sizeof(InputFaceRecord), "input faces", false},
    {SectionId::kVertexCopies, sizeof(int32_t), "vertex copies", false},
    {SectionId::kCoarseFaces, sizeof(int32_t), "coarse faces", false},
    {SectionId::kSplitFaces, sizeof(SplitFaceRecord), "split faces", false},
    {SectionId::kSpreadBounds, sizeof(SpreadBoundRecord), "spread bounds", false},
    {SectionId::kSampleDistancesLower, sizeof(float), "sample distances (lower triangle)", false},
    {SectionId::kSampleDistancesCoded, sizeof(PackedCode), "sample distances (24-bit codes)", false},
    {SectionId::kDistanceCode, sizeof(DistanceCodeRecord), "distance code", false},
    {SectionId::kSplitCoarseFaces, sizeof(SplitCoarseRecord), "split coarse faces", false},
    {SectionId::kSplitPieces, sizeof(SplitPieceRecord), "split pieces", false},
    {SectionId::kCompactVertexRecords, sizeof(VertexRecord), "vertex records (6.0)", false},
    {SectionId::kSplitFaceCodes, sizeof(SplitFaceCode), "split face codes", false},
    {SectionId::kSplitPieceCodes, sizeof(SplitPieceCode), "split piece codes", false},
};
constexpr size_t kNumSpecs = std::size(kSpecs);

// Index of `id` in kSpecs, or -1 for an id this reader does not know.
int SpecIndex(uint32_t id);

struct Counts {
  uint64_t num_vertices = 0;
  uint64_t num_faces = 0;
  uint64_t num_samples = 0;
  uint64_t num_triangles = 0;
  uint64_t num_bvh_nodes = 0;
};
// Elements a known section must hold; nullopt when any number is fine. Every
// product fits in uint64_t (the counts are at most 2^31).
std::optional<uint64_t> ExpectedCount(SectionId id, const Counts& c);

// x rounded up to the section alignment.
uint64_t AlignUp(uint64_t x);
// XXH64 of a section.
uint64_t Checksum(const void* data, size_t size);
// XXH64 of the first `header_size` bytes with the header_checksum field read
// as zero. `header_size` >= sizeof(FileHeader) (a later minor version may
// append fields; they are covered too).
uint64_t HeaderChecksum(const uint8_t* p, size_t header_size);

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
  std::span<const DistanceCodeRecord> distance_code;  // 4.x: one record
  std::span<const VertexRecord> vertices;
  std::span<const GeodesicTriangle> triangles;
  std::span<const BvhNode> bvh_nodes;
  std::span<const int32_t> bvh_faces;
  std::span<const InputFaceRecord> input_faces;
  std::span<const int32_t> vertex_copies;
  SplitView split;  // dense or sparse, its layout's records checked
  uint64_t split_vertices = 0;
  // The records of a 1.x-5.x file, `vertices` with their corners: each
  // corner must be its triangle's (-1 without one).
  std::span<const VertexRecordWithCorners> vertices_with_corners = {};
};
// The accuracy records (at most one, finite, non-negative); errors with `code`.
absl::Status CheckAccuracy(std::span<const AccuracyRecord> records, absl::StatusCode code);
// The spread-bound records (at most one, only beside an accuracy record).
absl::Status CheckSpreadBounds(std::span<const SpreadBoundRecord> records, size_t num_accuracy,
                               absl::StatusCode code);
// Every id in range, every distance finite and non-negative; errors with
// `code`.
absl::Status CheckContents(const Contents& c, absl::StatusCode code);

}  // namespace geodex::index::internal
