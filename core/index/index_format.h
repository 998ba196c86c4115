#pragma once

// The geodex index file (.gdx): one file per mesh, written by the builder and
// memory-mapped read-only by the server, which uses every section in place.
//
// Layout (all integers and floats little-endian; every section starts at a
// multiple of 64 bytes):
//
//   FileHeader            fixed size, at offset 0
//   SectionEntry[n]       the section table, right after the header
//   sections...           each 64-byte aligned, in table order
//
// The header carries the fingerprint (magic, format version, byte-order mark,
// builder version, a hash of the source mesh, the build parameters) and a
// checksum of itself and of the section table; each section has its own
// checksum (XXH64 of its bytes).
//
// Version log (bump kFormatMinor for additive changes that old readers can
// ignore, kFormatMajor for anything else):
//   1.0  first version: mesh, samples, full float32 distance matrix, vertex
//        records, geodesic triangles with adjacency, face BVH, build report.
//   1.1  accuracy calibration (AccuracyRecord): absolute error bounds of the
//        answers by distance scale, measured against held-out exact
//        propagations. Optional; 1.0 readers ignore it.
//   1.2  input ids of a repaired mesh (core/mesh/mesh_repair.h): where each
//        input face went (InputFaceRecord) and which input vertex each split
//        vertex copies. Optional, written only when the mesh was repaired;
//        absent means identity maps. A 1.0/1.1 reader loads a repaired
//        index but answers in its internal ids.
//   2.0  long-edge split (core/mesh/long_edge_split.h): the builder split
//        long input edges at their midpoints, so the index's faces are pieces
//        of the (repaired) input's faces. CoarseFaces holds the faces before
//        the split, SplitFaceRecord says which of them each face lies in,
//        and params.split_vertices counts the midpoints (the last
//        vertices). A 1.x reader must refuse such a file (its face ids are
//        not the input's), hence the major version; an index without
//        split is still written as 1.2, so older readers keep reading it.
//   1.3 / 2.1  per-pair error bounds of O(1) answers (SpreadBoundRecord),
//        calibrated with the AccuracyRecord. Optional, written only with a
//        calibration; older readers ignore it and use the AccuracyRecord's
//        bounds.
//   3.0  the symmetric sample distance matrix stored once: its strictly
//        lower triangle (SampleDistancesLower, d(a, b) for a > b at
//        a (a - 1) / 2 + b; the diagonal is 0), half the bytes of the full
//        matrix, which a 3.x file does not have, hence the major version.
//        Otherwise as 2.1 (the split sections optional). Written when
//        IndexData::sample_matrix asks for MatrixLayout::kLower.
//   4.0  the lower triangle in 24-bit codes (SampleDistancesCoded, same
//        order; sample_matrix.h: at most 2.4e-7 of a distance off), with
//        the codes' scale (DistanceCodeRecord): 3/4 of the bytes of 3.0, what
//        the builder writes by default. A 3.x reader has no matrix to read
//        in it, hence the major version. This reader reads 1.x to 5.x
//        (Index::matrix() and SampleDistance read every layout).
//   5.0  a split index's split sections sparse: SplitCoarseRecord for
//        each coarse face that was split (the others are the index's face
//        of the same id) and SplitPieceRecord for each face that is not a
//        coarse face whole (every other face f is coarse face f, with
//        identity weights), instead of CoarseFaces and SplitFaces, which
//        held both for every face. A split that adds a few hundred
//        midpoints to a mesh of 70K faces stored 3.4 MiB of records for
//        them; now a few KiB. Written for a split index with the coded
//        matrix when it is the smaller (a split of a coarse mesh makes
//        pieces of nearly every face, and a piece record is 4 bytes more);
//        else, and for an index not split, 4.0. A 4.x reader would find no
//        split sections, hence the major version.
//   6.0  only what a reader cannot derive: vertex records without their
//        corners (VertexRecord, 16 bytes: the corners are those of the
//        record's geodesic triangle, which 1.x-5.x copied into a 32-byte
//        VertexRecordWithCorners), and the twins and the face BVH left
//        out when the reader's own derivation (DeriveTwins, BuildFaceBvh)
//        gives them back as they are; the reader then derives them at load.
//        The split sparse or dense, whichever is smaller, its weights in
//        128ths (SplitFaceCode, SplitPieceCode: 16 and 20 bytes for 40 and
//        44) when every weight is such a fraction, as a midpoint split's
//        are to seven halvings. What the builder
//        writes by default (the coded matrix); a 5.x reader would find no
//        vertex records, hence the major version. The default builds of
//        the shared meshes take 17-38% fewer bytes; the answers are the
//        same to the bit.

#include <cstdint>

namespace geodex::index {

inline constexpr char kMagic[8] = {'G', 'E', 'O', 'D', 'E', 'X', 'I', 'X'};
// The version written when the mesh was not split, and when it was; a
// reader takes both majors, kPackedFormatMajor and kCodedFormatMajor.
inline constexpr uint32_t kFormatMajor = 1;
inline constexpr uint32_t kFormatMinor = 3;
inline constexpr uint32_t kSplitFormatMajor = 2;
inline constexpr uint32_t kRefinedFormatMinor = 1;
// The version of an index whose matrix is stored once (split or not).
inline constexpr uint32_t kPackedFormatMajor = 3;
inline constexpr uint32_t kPackedFormatMinor = 0;
// The version of an index whose matrix is stored once, in 24-bit codes.
inline constexpr uint32_t kCodedFormatMajor = 4;
inline constexpr uint32_t kCodedFormatMinor = 0;
// The version of a split index with the coded matrix: the split sparse.
inline constexpr uint32_t kSparseSplitFormatMajor = 5;
inline constexpr uint32_t kSparseSplitFormatMinor = 0;
// The version of an index with the coded matrix and only the sections a
// reader cannot derive: what the builder writes.
inline constexpr uint32_t kDerivedFormatMajor = 6;
inline constexpr uint32_t kDerivedFormatMinor = 0;
inline constexpr uint32_t kByteOrderMark = 0x01020304;  // reads 0x04030201 when swapped
inline constexpr uint64_t kAlignment = 64;

// Section ids. A reader ignores ids it does not know (minor-version additions).
enum class SectionId : uint32_t {
  kPositions = 1,        // double[num_vertices][3]
  kFaces = 2,            // int32[num_faces][3]
  kTwins = 3,            // int32[num_faces * 3]: twin half-edge or -1 (6.x: optional)
  kSamples = 4,          // int32[num_samples]: the vertex of each sample
  kSampleDistances = 5,  // float[num_samples][num_samples], row-major, symmetric (1.x, 2.x)
  kVertexRecords = 6,    // VertexRecordWithCorners[num_vertices] (1.x-5.x)
  kTriangles = 7,        // GeodesicTriangle[num_triangles]
  kFaceBvh = 8,          // BvhNode[num_bvh_nodes] (6.x: optional)
  kBvhFaces = 9,         // int32[num_faces]: faces in BVH leaf order (6.x: optional)
  kReport = 10,          // UTF-8 text: the builder's summary (key = value lines)
  kAccuracy = 11,        // AccuracyRecord[0 or 1] (1.1)
  kInputFaces = 12,      // InputFaceRecord[num_input_faces] (1.2); absent: identity
  kVertexCopies = 13,    // int32[k]: input vertex of the i-th copy (1.2; see InputFaceRecord)
  kCoarseFaces = 14,     // int32[num_coarse_faces][3]: the faces before the split (2.0)
  kSplitFaces = 15,      // SplitFaceRecord[num_faces] (2.0); absent: not split
  kSpreadBounds = 16,    // SpreadBoundRecord[0 or 1] (1.3 / 2.1); absent: constant bounds
  // float[num_samples (num_samples - 1) / 2]: the matrix's strictly lower
  // triangle, row by row (3.x, instead of kSampleDistances).
  kSampleDistancesLower = 17,
  // uint8[3][num_samples (num_samples - 1) / 2]: the same triangle in 24-bit
  // codes, little-endian (4.x, instead of the float sections; sample_matrix.h).
  kSampleDistancesCoded = 18,
  kDistanceCode = 19,  // DistanceCodeRecord[1] (4.x): the codes' scale
  // SplitCoarseRecord[k] (5.x), by increasing coarse_face: the coarse faces
  // that were split.
  kSplitCoarseFaces = 20,
  // SplitPieceRecord[k] (5.x), by increasing face: the faces that are not a
  // coarse face whole.
  kSplitPieces = 21,
  kCompactVertexRecords = 22,  // VertexRecord[num_vertices] (6.x, instead of kVertexRecords)
  kSplitFaceCodes = 23,        // SplitFaceCode[num_faces] (6.x, may replace kSplitFaces)
  kSplitPieceCodes = 24,       // SplitPieceCode[k] (6.x, may replace kSplitPieces)
};

// Build parameters recorded in the header.
struct BuildParams {
  uint32_t requested_samples = 0;
  uint32_t num_samples = 0;  // after repair insertions
  uint64_t seed = 0;
  uint32_t samples_added_by_repair = 0;
  // Midpoints the long-edge split added (2.0): the last vertices; 0 in 1.x.
  uint32_t split_vertices = 0;
};

struct FileHeader {
  char magic[8];
  uint32_t format_major;
  uint32_t format_minor;
  uint32_t byte_order_mark;
  uint32_t header_size;      // sizeof(FileHeader)
  char builder_version[32];  // NUL-padded
  uint64_t mesh_hash;        // XXH64 of positions and faces
  BuildParams params;
  uint32_t num_vertices;
  uint32_t num_faces;
  uint32_t num_samples;
  uint32_t num_triangles;
  uint32_t num_bvh_nodes;
  uint32_t num_sections;
  uint64_t section_table_offset;
  uint64_t file_size;
  uint64_t table_checksum;   // XXH64 of the section table
  uint64_t header_checksum;  // XXH64 of this header with header_checksum = 0
};

struct SectionEntry {
  uint32_t id;  // SectionId
  uint32_t element_size;
  uint64_t offset;
  uint64_t size;  // bytes
  uint64_t checksum;
};

// What the index stores for each mesh vertex: the geodesic triangle that
// contains it and the exact geodesic distances from the vertex to the
// triangle's corners, in the triangle's corner order. Unreferenced vertices
// have triangle = -1 (and distances +inf or 0).
struct VertexRecord {
  int32_t triangle;
  float distance[3];  // d(v, sample corner[i] of GeodesicTriangle `triangle`)
};
static_assert(sizeof(VertexRecord) == 16);

// The vertex record of 1.x-5.x: the triangle's corner samples copied in
// (-1 without a triangle), and a reserved word (0). A reader takes the
// records whose corners are their triangle's, in its order.
struct VertexRecordWithCorners {
  int32_t triangle;
  int32_t corner[3];
  float distance[3];
  uint32_t flags;
};
static_assert(sizeof(VertexRecordWithCorners) == 32);

// A geodesic triangle: three samples and, across each side (corner[i],
// corner[i+1]), the neighbouring triangle or -1.
struct GeodesicTriangle {
  int32_t corner[3];
  int32_t neighbor[3];
};
static_assert(sizeof(GeodesicTriangle) == 24);

// Where one face of the input mesh went when the builder repaired the mesh
// (1.2). Faces of the index are "internal"; requests name input faces.
struct InputFaceRecord {
  int32_t face;       // internal face; for a dropped duplicate, its twin's
  uint8_t corner[3];  // input corner i is corner corner[i] of the internal face
  uint8_t flags;      // kInputFaceDropped | kInputFaceReoriented
};
static_assert(sizeof(InputFaceRecord) == 8);
inline constexpr uint8_t kInputFaceDropped = 1;     // a duplicate, answered by its twin
inline constexpr uint8_t kInputFaceReoriented = 2;  // its corners 1 and 2 swapped
// Vertex ids: the input's vertices, then the repair's copies (kVertexCopies),
// then the split's midpoints (params.split_vertices). Without the
// split InputFaceRecord::face is a face of the index; with it, a coarse
// face (kCoarseFaces), whose pieces are the faces whose SplitFaceRecord
// names it.

// Where a face of a split index lies (2.0): in coarse face `coarse_face`,
// its corner i at barycentric weights weight[i] of that face's corners.
// Midpoint weights are dyadic fractions, exact in float.
struct SplitFaceRecord {
  int32_t coarse_face;
  float weight[3][3];
};
static_assert(sizeof(SplitFaceRecord) == 40);

// A coarse face that was split (5.0), and its corners; a coarse face c
// without one is the index's face c.
struct SplitCoarseRecord {
  int32_t coarse_face;
  int32_t corner[3];
};
static_assert(sizeof(SplitCoarseRecord) == 16);

// A face that is not a coarse face whole (5.0): a part of coarse face f
// that kept the id f, or a piece appended after the coarse faces. A face f
// without one is coarse face f, its corners at identity weights.
struct SplitPieceRecord {
  int32_t face;
  SplitFaceRecord piece;
};
static_assert(sizeof(SplitPieceRecord) == 44);

// A SplitFaceRecord with its weights in 128ths (6.0): weight[i][j] / 128,
// each at most 128; reserved bytes 0.
inline constexpr int kSplitWeightDenominator = 128;
struct SplitFaceCode {
  int32_t coarse_face;
  uint8_t weight[3][3];
  uint8_t reserved[3];
};
static_assert(sizeof(SplitFaceCode) == 16);

// A SplitPieceRecord with its weights in 128ths (6.0).
struct SplitPieceCode {
  int32_t face;
  SplitFaceCode piece;
};
static_assert(sizeof(SplitPieceCode) == 20);

// Axis-aligned bounding-box hierarchy over the mesh faces. A leaf has
// count > 0 and covers bvh_faces[first, first+count); an inner node has
// count == 0 and children at `first` and `first + 1`.
struct BvhNode {
  float lo[3];
  float hi[3];
  int32_t first;
  int32_t count;
};
static_assert(sizeof(BvhNode) == 32);

// Bins of the accuracy calibration, by approximate distance in units of the
// scale length L = sqrt(2 A / (sqrt(3) m)) (the edge of an equilateral
// geodesic triangle when the m samples tile the surface's area A).
inline constexpr int kAccuracyBins = 8;
inline constexpr float kAccuracyBinUpper[kAccuracyBins] = {0.5f, 1, 2, 3, 5, 10, 20, 1e30f};

// The accuracy of an index's answers, measured when it was built against
// exact propagations from held-out surface points (not samples). A bound is
// the absolute error that the answers of its kind and bin stayed within for
// all but a small share of the held-out pairs (see core/validation).
struct AccuracyRecord {
  float scale_length;                // L, in mesh units
  uint32_t num_sources;              // held-out exact propagations
  uint32_t num_pairs;                // held-out pairs measured
  uint32_t bound_quantile_permille;  // the bounds are this quantile of the errors (e.g. 995)
  // Absolute error bounds by bin of the answered distance (kAccuracyBinUpper):
  // the O(1) unfolding for pairs of mesh vertices [0] and other pairs [1];
  // the length of the straightened trace (a surface path: never short),
  // [2 * vertex pair + bends]: bends when it bends round a mesh vertex (else
  // it is a straight line through the faces it crosses, a local geodesic).
  float unfold_bound[2][kAccuracyBins];
  float trace_bound[4][kAccuracyBins];
  // Relative error of the default answer over the held-out pairs, by the
  // exact distance's bin d < L, L-3L, 3L-10L, >= 10L: RMS and p99; and over
  // area-uniform pairs: RMS, and p99 of those beyond 10L.
  float rms[4];
  float p99[4];
  float uniform_rms;
  float uniform_far_p99;
};
static_assert(sizeof(AccuracyRecord) == 16 + 4 * 6 * kAccuracyBins + 4 * 10);

// Per-pair error bounds of the O(1) answer (1.3 / 2.1). Within one distance
// bin the O(1) error is heavy-tailed, so a bound that is constant in the bin
// must sit far above most of its errors to cover the tail. What flags the
// tail is the disagreement of the two orders of the paper's case 3.2 (p's
// distances to q's corners, then q; or the other way round): the `spread`
// |d_pq - d_qp| of a pair (0 for points in one geodesic triangle). The bound
// of an O(1) answer d in bin b (kAccuracyBinUpper) is
//   factor[k][b] * (spread + epsilon[k][b] * d),
// k = 0 for pairs of mesh vertices, 1 for other pairs: factor is the
// calibration's quantile of |error| / (spread + epsilon * d), and epsilon is
// the value, among a fixed grid, that makes the bin's median bound smallest
// (core/validation/calibration.h). factor[k][b] = 0: the bin's constant
// bound (AccuracyRecord::unfold_bound), where the calibration found the
// per-pair bounds no tighter (a reader before 4.0 takes it for a bound of 0,
// and the builder writes it only since 4.0).
struct SpreadBoundRecord {
  float epsilon[2][kAccuracyBins];
  float factor[2][kAccuracyBins];
};
static_assert(sizeof(SpreadBoundRecord) == 4 * 4 * kAccuracyBins);

// The scale of the 24-bit distance codes (4.0): a code c stands for
// scale * (F(c) - 2^-8) (sample_matrix.h). Finite and > 0.
struct DistanceCodeRecord {
  double scale;
};
static_assert(sizeof(DistanceCodeRecord) == 8);

}  // namespace geodex::index
