#pragma once

// Reading and writing geodex index files (format: core/index/index_format.h).
//
// IndexData owns its arrays (the builder fills it); Index is a read-only view
// of a validated file image, either memory-mapped (the server) or held in
// memory (tests). Both expose the same spans, so code that queries an index
// never knows where the bytes live.
//
// Thread safety: Index is immutable after Open; every method is const and safe
// from any number of threads. Share it as std::shared_ptr<const Index>.

#include <algorithm>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/index/index_format.h"
#include "core/index/sample_matrix.h"
#include "core/index/split_view.h"

namespace geodex::index {

// Everything a builder writes into an index.
struct IndexData {
  std::string builder_version;
  uint64_t mesh_hash = 0;
  BuildParams params;
  std::vector<double> positions;        // 3 per vertex
  std::vector<int32_t> faces;           // 3 per face
  std::vector<int32_t> twins;           // 3 per face
  std::vector<int32_t> samples;         // vertex of each sample
  std::vector<float> sample_distances;  // num_samples^2, row-major
  // How the file stores the matrix: in full (1.x / 2.x), its lower triangle
  // (3.0) or that triangle in 24-bit codes (4.0). Stored once, the matrix
  // must be symmetric with a zero diagonal.
  MatrixLayout sample_matrix = MatrixLayout::kFull;
  // kCoded: the codes' scale (DistanceCode::ScaleFor); 0 chooses it from
  // the largest distance. A loaded index's is kept, so that writing it
  // again gives the same codes.
  double sample_distance_scale = 0;
  // kCoded is written as 6.0 (index_format.h); true writes it as older
  // builders did, 5.0 or 4.0 (the split sparse when that is smaller), so
  // that tests can check what this reader makes of their files.
  bool coded_as_version_5 = false;
  std::vector<VertexRecord> vertices;  // one per vertex
  std::vector<GeodesicTriangle> triangles;
  std::vector<BvhNode> bvh_nodes;
  std::vector<int32_t> bvh_faces;
  std::string report;
  std::vector<AccuracyRecord> accuracy;  // empty, or one record (format 1.1)
  // Empty, or one record (1.3 / 2.1), only beside an accuracy record.
  std::vector<SpreadBoundRecord> spread_bounds;
  // A repaired mesh's input ids (format 1.2): one record per input face, or
  // empty for identity; the input vertex of each split vertex copy (the last
  // vertex_copies.size() vertices), or empty.
  std::vector<InputFaceRecord> input_faces;
  std::vector<int32_t> vertex_copies;
  // A split mesh's pieces (format 2.0; see index_format.h): the faces
  // before the split (3 vertex ids each) and, per face, where it lies in
  // them; both empty when the mesh was not split. params.split_vertices
  // counts the midpoints.
  std::vector<int32_t> coarse_faces;
  std::vector<SplitFaceRecord> split_faces;
};

// XXH64 of the positions and faces: identifies the source mesh.
uint64_t MeshHash(std::span<const double> positions, std::span<const int32_t> faces);

// Serialises `data` to the exact bytes of an index file. Deterministic: the
// same data gives the same bytes. Errors: InvalidArgument if array sizes are
// inconsistent (e.g. sample_distances not num_samples^2, bvh_faces not one per
// face when there is a BVH, params.num_samples != samples.size()), if
// builder_version has 32 bytes or more, or if the contents fail the checks
// Index applies on reading (ids out of range, NaN or negative distances, ...):
// the writer never produces a file the reader rejects.
absl::StatusOr<std::string> SerializeIndex(const IndexData& data);

// The bytes SerializeIndex writes for `d`, from the arrays' sizes alone: the
// matrix counted as that of d.samples.size() samples in d.sample_matrix's
// layout, whether or not d.sample_distances holds it yet (a builder
// predicts a round's bytes before it computes the round's rows).
uint64_t PredictIndexBytes(const IndexData& d);

// Writes atomically: a temporary file in the same directory, fsync, rename,
// fsync of the directory. A reader never sees a half-written file. Errors:
// InvalidArgument as SerializeIndex; Internal / PermissionDenied / NotFound on
// I/O failures (naming the path).
absl::Status WriteIndexFile(const IndexData& data, const std::string& path);

class Index;
// A copy of a loaded index's contents, e.g. to write it again with a section
// added.
IndexData ToIndexData(const Index& index);

class Index {
 public:
  // Maps `path` read-only (MAP_SHARED, so processes share the page cache) and
  // validates it. Errors: NotFound (no file), PermissionDenied, FailedPrecondition
  // (not a regular file, wrong magic, byte order or major version), DataLoss
  // (checksum mismatch, truncation, counts, sizes or offsets that do not fit,
  // non-zero padding, indices out of range, NaN or negative distances).
  // An image shorter than the header is DataLoss ("truncated") when its bytes
  // are a prefix of the magic (including an empty file), FailedPrecondition
  // ("not a geodex index") otherwise. Messages name the path.
  static absl::StatusOr<std::shared_ptr<const Index>> Open(const std::string& path);
  // Validates an in-memory file image (copied into the Index). Same errors.
  static absl::StatusOr<std::shared_ptr<const Index>> FromBytes(std::string bytes);

  ~Index();
  Index(const Index&) = delete;
  Index& operator=(const Index&) = delete;

  const FileHeader& header() const { return *header_; }
  std::string builder_version() const;
  int32_t num_vertices() const { return static_cast<int32_t>(header_->num_vertices); }
  int32_t num_faces() const { return static_cast<int32_t>(header_->num_faces); }
  int32_t num_samples() const { return static_cast<int32_t>(header_->num_samples); }
  int32_t num_triangles() const { return static_cast<int32_t>(header_->num_triangles); }

  std::span<const double> positions() const { return positions_; }
  std::span<const int32_t> faces() const { return faces_; }
  // Derived at load when a 6.x file leaves them out (index_format.h).
  std::span<const int32_t> twins() const { return twins_; }
  std::span<const int32_t> samples() const { return samples_; }
  // The sample distance matrix, in the file's layout: what queries read.
  const SampleMatrix& matrix() const { return matrix_; }
  // The full num_samples^2 matrix, row-major, of a 1.x / 2.x file; empty for
  // later files, which store it once. Prefer matrix().
  std::span<const float> sample_distances() const { return sample_distances_; }
  // The strictly lower triangle of a 3.x file (d(a, b), a > b, at
  // a (a - 1) / 2 + b); empty for other files.
  std::span<const float> sample_distances_lower() const { return sample_distances_lower_; }
  // The same triangle in 24-bit codes, of a 4.x file; empty for others.
  std::span<const PackedCode> sample_distances_coded() const { return sample_distances_coded_; }
  // One per vertex, in every version (the corners of 1.x-5.x's records left
  // out: they are those of the record's triangle).
  std::span<const VertexRecord> vertices() const { return vertices_; }
  std::span<const GeodesicTriangle> triangles() const { return triangles_; }
  // Derived at load when a 6.x file leaves it out (index_format.h).
  std::span<const BvhNode> bvh_nodes() const { return bvh_nodes_; }
  std::span<const int32_t> bvh_faces() const { return bvh_faces_; }
  std::string_view report() const { return report_; }
  // The accuracy calibration, or nullptr when the index has none (format 1.0,
  // or built without it).
  const AccuracyRecord* accuracy() const { return accuracy_.empty() ? nullptr : &accuracy_[0]; }
  // The per-pair bounds of O(1) answers, or nullptr (before 1.3 / 2.1, or
  // without calibration).
  const SpreadBoundRecord* spread_bounds() const {
    return spread_bounds_.empty() ? nullptr : &spread_bounds_[0];
  }

  // The input ids of a repaired mesh (format 1.2); both empty for an index
  // of a mesh that needed no repair, or one older than 1.2.
  std::span<const InputFaceRecord> input_faces() const { return input_faces_; }
  std::span<const int32_t> vertex_copies() const { return vertex_copies_; }
  // The long-edge split (format 2.0, sparse from 5.0); split() is false for
  // an index of a mesh not split.
  const SplitView& split() const { return split_; }
  int32_t split_vertices() const { return static_cast<int32_t>(header_->params.split_vertices); }

  // d(sample i, sample j) from the matrix, in any layout; i and j in
  // [0, num_samples()).
  double SampleDistance(int32_t i, int32_t j) const { return matrix_(i, j); }
  // Bytes of the file image (mapped or owned).
  size_t size_bytes() const { return size_; }
  // The file image itself (for naming the file a fault address falls in).
  std::span<const uint8_t> image() const { return {base_, size_}; }
  bool is_mapped() const { return mapped_; }

 private:
  Index() = default;
  absl::Status Validate();

  const uint8_t* base_ = nullptr;  // 64-byte aligned (page-aligned when mapped)
  size_t size_ = 0;
  bool mapped_ = false;
  // FromBytes: the image copied into an over-allocated buffer; base_ points
  // at its first 64-byte aligned byte (std::string only guarantees 16).
  std::unique_ptr<uint8_t[]> owned_;
  const FileHeader* header_ = nullptr;
  std::span<const double> positions_;
  std::span<const int32_t> faces_;
  std::span<const int32_t> twins_;
  std::span<const int32_t> samples_;
  std::span<const float> sample_distances_;
  std::span<const float> sample_distances_lower_;
  std::span<const PackedCode> sample_distances_coded_;
  SampleMatrix matrix_;
  std::span<const VertexRecord> vertices_;
  // What the reader derived (index_format.h, 6.0): the records of an older
  // file without their corners; the twins and the BVH of a 6.x file that
  // left them out. Empty otherwise; the spans above then view the image.
  std::vector<VertexRecord> derived_vertices_;
  std::vector<int32_t> derived_twins_;
  std::vector<BvhNode> derived_bvh_nodes_;
  std::vector<int32_t> derived_bvh_faces_;
  std::span<const GeodesicTriangle> triangles_;
  std::span<const BvhNode> bvh_nodes_;
  std::span<const int32_t> bvh_faces_;
  std::string_view report_;
  std::span<const AccuracyRecord> accuracy_;
  std::span<const SpreadBoundRecord> spread_bounds_;
  std::span<const InputFaceRecord> input_faces_;
  std::span<const int32_t> vertex_copies_;
  SplitView split_;
};

}  // namespace geodex::index
