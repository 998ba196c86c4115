#include "core/index/index.h"

// Files that are truncated, flipped, of another format, or corrupt behind
// valid checksums: each is refused with the right code, none is read.

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "core/index/index_testing.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::index {
namespace {

using namespace testing_util;  // NOLINT: the shared fixtures of the index tests
using ::testing::AnyOf;
using ::testing::HasSubstr;

TEST(IndexTest, EveryTruncationIsRejected) {
  const std::string bytes = Serialize(MakeSphereIndex());
  // Every prefix of a valid file starts with (a prefix of) the magic, so each
  // is reported as truncated, including the empty file.
  for (size_t n = 0; n < bytes.size(); ++n) {
    const absl::Status status = Index::FromBytes(bytes.substr(0, n)).status();
    ASSERT_EQ(status.code(), absl::StatusCode::kDataLoss) << n << ": " << status;
    ASSERT_THAT(status.message(), HasSubstr("truncated")) << n;
  }
  EXPECT_THAT(
      Index::FromBytes(bytes.substr(0, bytes.size() - 1)).status().message(),
      HasSubstr(absl::StrCat("expected ", bytes.size(), " bytes, found ", bytes.size() - 1)));
}

TEST(IndexTest, TrailingBytesAreRejected) {
  const std::string bytes = Serialize(MakeSphereIndex());
  EXPECT_EQ(CodeOf(bytes + std::string(1, '\0')), absl::StatusCode::kDataLoss);
  EXPECT_EQ(CodeOf(bytes + std::string(64, 'x')), absl::StatusCode::kDataLoss);
}

// Every byte is covered by a checksum or must be zero padding.
void ExpectFlipRejected(const std::string& bytes, size_t position, uint8_t mask) {
  std::string corrupt = bytes;
  corrupt[position] = static_cast<char>(corrupt[position] ^ mask);
  const absl::Status status = Index::FromBytes(std::move(corrupt)).status();
  EXPECT_THAT(status.code(),
              AnyOf(absl::StatusCode::kDataLoss, absl::StatusCode::kFailedPrecondition))
      << "byte " << position << " ^ " << int{mask} << ": " << status;
}

TEST(IndexTest, RandomByteFlipsAreRejected) {
  const std::string bytes = Serialize(MakeSphereIndex());
  std::mt19937_64 random(20240611);
  std::uniform_int_distribution<size_t> position(0, bytes.size() - 1);
  std::uniform_int_distribution<int> mask(1, 255);
  for (int trial = 0; trial < 2000; ++trial) {
    ExpectFlipRejected(bytes, position(random), static_cast<uint8_t>(mask(random)));
  }
}

TEST(IndexTest, EveryBitOfEveryByteIsProtected) {
  const std::string bytes = Serialize(MakeSphereIndex());
  for (size_t i = 0; i < bytes.size(); ++i) ExpectFlipRejected(bytes, i, uint8_t{1} << (i % 8));
}

TEST(IndexTest, WrongMagicIsFailedPrecondition) {
  std::string bytes = Serialize(MakeSphereIndex());
  bytes[0] = 'X';
  const absl::Status status = Index::FromBytes(bytes).status();
  EXPECT_EQ(status.code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(status.message(), HasSubstr("not a geodex index"));
  EXPECT_EQ(CodeOf("hello"), absl::StatusCode::kFailedPrecondition);
  EXPECT_EQ(CodeOf(std::string(1000, '\0')), absl::StatusCode::kFailedPrecondition);
}

TEST(IndexTest, WrongMajorVersionIsFailedPrecondition) {
  Image image = Image::Parse(Serialize(MakeSphereIndex()));
  image.header.format_major = kDerivedFormatMajor + 1;
  image.header.format_minor = 3;
  const absl::Status status = Index::FromBytes(image.Layout()).status();
  EXPECT_EQ(status.code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(status.message(), HasSubstr(absl::StrCat(kDerivedFormatMajor + 1, ".3")));
  EXPECT_THAT(status.message(),
              HasSubstr(absl::StrCat(kDerivedFormatMajor, ".", kDerivedFormatMinor)));
}

// A 4.x file has the coded triangle and its scale, a 3.x file the float
// triangle, an older one the full matrix; none has another's sections.
TEST(IndexTest, MatrixLayoutMustMatchTheVersion) {
  IndexData d = MakeSphereIndex();
  Image full = Image::Parse(Serialize(d));
  full.header.format_major = kPackedFormatMajor;
  full.header.format_minor = kPackedFormatMinor;
  absl::Status status = Index::FromBytes(full.Layout()).status();
  EXPECT_EQ(status.code(), absl::StatusCode::kDataLoss);
  EXPECT_THAT(status.message(), HasSubstr("sample distances"));
  d.sample_matrix = MatrixLayout::kLower;
  Image packed = Image::Parse(Serialize(d));
  packed.header.format_major = kFormatMajor;
  packed.header.format_minor = kFormatMinor;
  status = Index::FromBytes(packed.Layout()).status();
  EXPECT_EQ(status.code(), absl::StatusCode::kDataLoss);
  EXPECT_THAT(status.message(), HasSubstr("sample distances"));
  packed.header.format_major = kCodedFormatMajor;
  status = Index::FromBytes(packed.Layout()).status();
  EXPECT_EQ(status.code(), absl::StatusCode::kDataLoss);
  EXPECT_THAT(status.message(), HasSubstr("sample distances"));
  d.sample_matrix = MatrixLayout::kCoded;
  d.coded_as_version_5 = true;  // 4.0: otherwise as the packed file
  Image coded = Image::Parse(Serialize(d));
  coded.header.format_major = kPackedFormatMajor;
  status = Index::FromBytes(coded.Layout()).status();
  EXPECT_EQ(status.code(), absl::StatusCode::kDataLoss);
  EXPECT_THAT(status.message(), HasSubstr("sample distances"));
}

// The codes' scale is the one figure of a 4.x matrix that can be wrong.
TEST(IndexTest, CodedMatrixNeedsOneFiniteScale) {
  IndexData d = MakeSphereIndex();
  d.sample_matrix = MatrixLayout::kCoded;
  for (double scale : {0.0, -1.0, std::numeric_limits<double>::quiet_NaN(),
                       std::numeric_limits<double>::infinity()}) {
    Image image = Image::Parse(Serialize(d));
    std::memcpy(image.Payload(SectionId::kDistanceCode).data(), &scale, sizeof(scale));
    const absl::Status status = Index::FromBytes(image.Layout()).status();
    EXPECT_EQ(status.code(), absl::StatusCode::kDataLoss) << scale;
    EXPECT_THAT(status.message(), HasSubstr("distance code")) << scale;
  }
}

TEST(IndexTest, SwappedByteOrderIsFailedPrecondition) {
  Image image = Image::Parse(Serialize(MakeSphereIndex()));
  image.header.byte_order_mark = 0x04030201;
  const absl::Status status = Index::FromBytes(image.Layout()).status();
  EXPECT_EQ(status.code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(status.message(), HasSubstr("byte order"));
}

TEST(IndexTest, FutureMinorVersionWithUnknownSectionIsAccepted) {
  const IndexData d = MakeSphereIndex();
  Image image = Image::Parse(Serialize(d));
  image.header.format_minor = kFormatMinor + 1;
  // A new section in the middle of the table and one at the end.
  image.entries.insert(image.entries.begin() + 3, UnknownEntry(77, 8));
  image.payloads.insert(image.payloads.begin() + 3, std::string(200, '\x5a'));
  image.entries.push_back(UnknownEntry(1000, 1));
  image.payloads.push_back("future data");
  absl::StatusOr<std::shared_ptr<const Index>> index = Index::FromBytes(image.Layout());
  ASSERT_TRUE(index.ok()) << index.status();
  ExpectSameData(**index, d);
  EXPECT_EQ((*index)->header().format_minor, kFormatMinor + 1);
}

// A corruption of an index image (checksums recomputed) and what the
// DataLoss error must say.
struct Case {
  std::string name;
  std::function<void(Image&)> corrupt;
  std::string message;
};

// Each case applied to `bytes` alone is DataLoss naming its message.
void ExpectDataLoss(const std::string& bytes, const std::vector<Case>& cases) {
  for (const Case& c : cases) {
    Image image = Image::Parse(bytes);
    c.corrupt(image);
    const absl::Status status = Index::FromBytes(image.Layout()).status();
    EXPECT_EQ(status.code(), absl::StatusCode::kDataLoss) << c.name << ": " << status;
    EXPECT_THAT(status.message(), HasSubstr(c.message)) << c.name;
  }
}

// The sphere index with valid checksums, and its counts, for the semantic
// corruptions below.
struct SphereFile {
  IndexData d = MakeSphereIndex();
  std::string bytes = Serialize(d);
  int32_t nv = static_cast<int32_t>(d.positions.size() / 3);
  int32_t nf = static_cast<int32_t>(d.faces.size() / 3);
  int32_t m = static_cast<int32_t>(d.samples.size());
  int32_t nt = static_cast<int32_t>(d.triangles.size());
  int32_t nb = static_cast<int32_t>(d.bvh_nodes.size());
};

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

TEST(IndexTest, SemanticCorruptionOfTheMeshIsDataLoss) {
  const SphereFile f;
  const int32_t nv = f.nv;
  const int32_t nf = f.nf;
  const std::vector<Case> cases = {
      {"face vertex out of range", [&](Image& i) { i.Set<int32_t>(SectionId::kFaces, 7, nv); },
       "face 2"},
      {"negative face vertex", [&](Image& i) { i.Set<int32_t>(SectionId::kFaces, 0, -1); },
       "face 0"},
      {"twin out of range", [&](Image& i) { i.Set<int32_t>(SectionId::kTwins, 5, 3 * nf); },
       "twin"},
      {"twin below -1", [&](Image& i) { i.Set<int32_t>(SectionId::kTwins, 5, -2); }, "twin"},
      {"sample out of range", [&](Image& i) { i.Set<int32_t>(SectionId::kSamples, 3, nv); },
       "sample 3"},
      {"NaN position", [&](Image& i) { i.Set<double>(SectionId::kPositions, 4, std::nan("")); },
       "vertex 1"},
      {"infinite position",
       [&](Image& i) {
         i.Set<double>(SectionId::kPositions, 4, std::numeric_limits<double>::infinity());
       },
       "vertex 1"},
  };
  ExpectDataLoss(f.bytes, cases);
}

TEST(IndexTest, SemanticCorruptionOfSampleDistancesIsDataLoss) {
  const SphereFile f;
  const int32_t m = f.m;
  const std::vector<Case> cases = {
      {"NaN sample distance", [&](Image& i) { i.Set<float>(SectionId::kSampleDistances, 1, kNaN); },
       "sample distance"},
      {"negative sample distance",
       [&](Image& i) { i.Set<float>(SectionId::kSampleDistances, m + 2, -0.5f); },
       "sample distance (1, 2)"},
  };
  ExpectDataLoss(f.bytes, cases);
}

TEST(IndexTest, SemanticCorruptionOfVertexRecordsIsDataLoss) {
  const SphereFile f;
  const int32_t nv = f.nv;
  const int32_t m = f.m;
  const int32_t nt = f.nt;
  const std::vector<Case> cases = {
      {"vertex triangle out of range",
       [&](Image& i) {
         VertexRecordWithCorners r = i.Get<VertexRecordWithCorners>(SectionId::kVertexRecords, 9);
         r.triangle = nt;
         i.Set(SectionId::kVertexRecords, 9, r);
       },
       "vertex record 9"},
      {"vertex corner out of range",
       [&](Image& i) {
         VertexRecordWithCorners r = i.Get<VertexRecordWithCorners>(SectionId::kVertexRecords, 9);
         r.corner[2] = m;
         i.Set(SectionId::kVertexRecords, 9, r);
       },
       "vertex record 9"},
      {"corner of a vertex without triangle",
       [&](Image& i) {
         VertexRecordWithCorners r = i.Get<VertexRecordWithCorners>(SectionId::kVertexRecords, nv - 1);
         r.corner[0] = 0;
         i.Set(SectionId::kVertexRecords, nv - 1, r);
       },
       "vertex record"},
      {"infinite vertex distance",
       [&](Image& i) {
         VertexRecordWithCorners r = i.Get<VertexRecordWithCorners>(SectionId::kVertexRecords, 9);
         r.distance[1] = kInf;
         i.Set(SectionId::kVertexRecords, 9, r);
       },
       "vertex record 9"},
      {"negative vertex distance",
       [&](Image& i) {
         VertexRecordWithCorners r = i.Get<VertexRecordWithCorners>(SectionId::kVertexRecords, 9);
         r.distance[1] = -1e-3f;
         i.Set(SectionId::kVertexRecords, 9, r);
       },
       "vertex record 9"},
  };
  ExpectDataLoss(f.bytes, cases);
}

TEST(IndexTest, SemanticCorruptionOfTrianglesIsDataLoss) {
  const SphereFile f;
  const int32_t nt = f.nt;
  const std::vector<Case> cases = {
      {"triangle corner out of range",
       [&](Image& i) {
         GeodesicTriangle g = i.Get<GeodesicTriangle>(SectionId::kTriangles, 4);
         g.corner[1] = -1;
         i.Set(SectionId::kTriangles, 4, g);
       },
       "geodesic triangle 4"},
      {"triangle neighbour out of range",
       [&](Image& i) {
         GeodesicTriangle g = i.Get<GeodesicTriangle>(SectionId::kTriangles, 4);
         g.neighbor[0] = nt;
         i.Set(SectionId::kTriangles, 4, g);
       },
       "geodesic triangle 4"},
  };
  ExpectDataLoss(f.bytes, cases);
}

TEST(IndexTest, SemanticCorruptionOfTheBvhIsDataLoss) {
  const SphereFile f;
  const int32_t nf = f.nf;
  const int32_t nb = f.nb;
  const std::vector<Case> cases = {
      {"BVH child out of range",
       [&](Image& i) {
         BvhNode n = i.Get<BvhNode>(SectionId::kFaceBvh, 0);
         n.first = nb - 1;
         i.Set(SectionId::kFaceBvh, 0, n);
       },
       "BVH node 0"},
      {"BVH cycle",
       [&](Image& i) {
         BvhNode n = i.Get<BvhNode>(SectionId::kFaceBvh, 0);
         n.first = 0;
         i.Set(SectionId::kFaceBvh, 0, n);
       },
       "BVH node 0"},
      {"BVH leaf beyond the faces",
       [&](Image& i) {
         BvhNode n = i.Get<BvhNode>(SectionId::kFaceBvh, nb - 1);
         n.first = nf - 1;
         n.count = 2;
         i.Set(SectionId::kFaceBvh, nb - 1, n);
       },
       "BVH node"},
      {"BVH negative count",
       [&](Image& i) {
         BvhNode n = i.Get<BvhNode>(SectionId::kFaceBvh, nb - 1);
         n.count = -1;
         i.Set(SectionId::kFaceBvh, nb - 1, n);
       },
       "BVH node"},
      {"BVH NaN box",
       [&](Image& i) {
         BvhNode n = i.Get<BvhNode>(SectionId::kFaceBvh, 1);
         n.lo[2] = kNaN;
         i.Set(SectionId::kFaceBvh, 1, n);
       },
       "BVH node 1"},
      {"BVH face out of range", [&](Image& i) { i.Set<int32_t>(SectionId::kBvhFaces, 0, nf); },
       "BVH face 0"},
      {"BVH face repeated",
       [&](Image& i) {
         i.Set<int32_t>(SectionId::kBvhFaces, 1, i.Get<int32_t>(SectionId::kBvhFaces, 0));
       },
       "BVH face 1"},
  };
  ExpectDataLoss(f.bytes, cases);
}

// The sphere index as if it were refined (format 2.0): every face its own
// coarse face, and the unreferenced last vertex counted as a midpoint.
IndexData MakeRefinedSphereIndex() {
  IndexData d = MakeSphereIndex();
  d.coarse_faces = d.faces;
  for (size_t f = 0; f < d.faces.size() / 3; ++f) {
    SplitFaceRecord r{};
    r.coarse_face = static_cast<int32_t>(f);
    for (int i = 0; i < 3; ++i) r.weight[i][i] = 1;
    d.split_faces.push_back(r);
  }
  d.params.split_vertices = 1;
  return d;
}

TEST(IndexTest, RefinedIndexIsWrittenAsVersion2AndReadBack) {
  absl::StatusOr<std::shared_ptr<const Index>> index =
      Index::FromBytes(Serialize(MakeRefinedSphereIndex()));
  ASSERT_TRUE(index.ok()) << index.status();
  EXPECT_EQ((*index)->header().format_major, kSplitFormatMajor);
  EXPECT_EQ((*index)->split_vertices(), 1);
  EXPECT_TRUE((*index)->split().split());
  EXPECT_EQ((*index)->split().num_coarse_faces(), 80);
  // Written again, the same bytes.
  EXPECT_EQ(Serialize(ToIndexData(**index)), Serialize(MakeRefinedSphereIndex()));
  // Without refinement, still the 1.x layout older readers take.
  absl::StatusOr<std::shared_ptr<const Index>> plain =
      Index::FromBytes(Serialize(MakeSphereIndex()));
  ASSERT_TRUE(plain.ok());
  EXPECT_EQ((*plain)->header().format_major, kFormatMajor);
}

// The sphere index as if its last face were a piece split off coarse face 0
// (79 coarse faces, the first of them with another corner), with the coded
// matrix: written sparse, as 5.0.
IndexData MakeSparseSplitSphereIndex() {
  IndexData d = MakeSphereIndex();
  d.sample_matrix = MatrixLayout::kCoded;
  const int32_t nf = static_cast<int32_t>(d.faces.size() / 3);
  d.coarse_faces.assign(d.faces.begin(), d.faces.end() - 3);
  d.coarse_faces[2] = (d.faces[2] + 1) % 42;  // a corner that is no corner of face 0
  for (int32_t f = 0; f < nf; ++f) {
    SplitFaceRecord r{};
    r.coarse_face = f == nf - 1 ? 0 : f;
    for (int i = 0; i < 3; ++i) r.weight[i][i] = 1;
    d.split_faces.push_back(r);
  }
  d.split_faces[0].weight[2][0] = d.split_faces[0].weight[2][2] = 0.5f;
  d.split_faces[nf - 1].weight[0][0] = d.split_faces[nf - 1].weight[0][2] = 0.5f;
  d.params.split_vertices = 1;
  return d;
}

TEST(IndexTest, SplitWithCodedMatrixIsWrittenSparseAsVersion5AndReadBack) {
  IndexData d = MakeSparseSplitSphereIndex();
  d.coded_as_version_5 = true;
  const std::string bytes = Serialize(d);
  absl::StatusOr<std::shared_ptr<const Index>> index = Index::FromBytes(bytes);
  ASSERT_TRUE(index.ok()) << index.status();
  EXPECT_EQ((*index)->header().format_major, kSparseSplitFormatMajor);
  const SplitView& split = (*index)->split();
  ASSERT_TRUE(split.split());
  EXPECT_EQ(split.num_coarse_faces(), 79);
  EXPECT_EQ(split.CoarseFace(0)[2], d.coarse_faces[2]);
  EXPECT_EQ(split.CoarseFace(5)[1], d.faces[3 * 5 + 1]);
  EXPECT_EQ(split.Piece(79).coarse_face, 0);
  EXPECT_EQ(split.Piece(0).weight[2][2], 0.5f);
  EXPECT_EQ(split.Piece(7).coarse_face, 7);
  EXPECT_EQ(split.Piece(7).weight[1][1], 1.0f);
  // Two piece records and one coarse record, not one of each per face.
  Image image = Image::Parse(bytes);
  EXPECT_EQ(image.Payload(SectionId::kSplitPieces).size(), 2 * sizeof(SplitPieceRecord));
  EXPECT_EQ(image.Payload(SectionId::kSplitCoarseFaces).size(), sizeof(SplitCoarseRecord));
  for (const SectionEntry& e : image.entries) {
    EXPECT_NE(e.id, static_cast<uint32_t>(SectionId::kSplitFaces));
    EXPECT_NE(e.id, static_cast<uint32_t>(SectionId::kCoarseFaces));
  }
  // Read back dense, the same split; written again, the same bytes.
  const IndexData again = ToIndexData(**index);
  EXPECT_EQ(again.coarse_faces, d.coarse_faces);
  ASSERT_EQ(again.split_faces.size(), d.split_faces.size());
  EXPECT_EQ(std::memcmp(again.split_faces.data(), d.split_faces.data(),
                        d.split_faces.size() * sizeof(SplitFaceRecord)),
            0);
  EXPECT_EQ(Serialize(again), bytes);
  EXPECT_EQ(PredictIndexBytes(d), bytes.size());
  // Corrupt records (valid checksums) are DataLoss naming the record.
  const std::vector<Case> cases = {
      {"pieces out of order",
       [&](Image& i) { i.Set<int32_t>(SectionId::kSplitPieces, 11, 0); }, "split piece record 1"},
      {"a coarse record out of range",
       [&](Image& i) { i.Set<int32_t>(SectionId::kSplitCoarseFaces, 0, 79); },
       "split coarse record 0"},
      {"an appended piece of no coarse face",
       [&](Image& i) { i.Set<int32_t>(SectionId::kSplitPieces, 11 + 1, 100); },
       "split piece record 1"},
  };
  ExpectDataLoss(bytes, cases);
}

// Format 6.0, what the builder writes: the vertex records without their
// corners, the twins and the BVH left out and derived at load, the split as
// in 5.0. It reads back to the spans the 5.0 file of the same index gives,
// in fewer bytes, and is written again to the same bytes.
TEST(IndexTest, Version6LeavesOutWhatTheReaderDerives) {
  const IndexData d = MakeSparseSplitSphereIndex();
  const std::string bytes = Serialize(d);
  IndexData v5 = d;
  v5.coded_as_version_5 = true;
  const std::string bytes5 = Serialize(v5);
  EXPECT_LT(bytes.size(), bytes5.size());
  Image image = Image::Parse(bytes);
  EXPECT_EQ(image.header.format_major, kDerivedFormatMajor);
  for (const SectionEntry& e : image.entries) {
    for (SectionId absent : {SectionId::kTwins, SectionId::kFaceBvh, SectionId::kBvhFaces,
                             SectionId::kVertexRecords}) {
      EXPECT_NE(e.id, static_cast<uint32_t>(absent));
    }
  }
  EXPECT_EQ(image.Payload(SectionId::kCompactVertexRecords).size(),
            d.vertices.size() * sizeof(VertexRecord));
  absl::StatusOr<std::shared_ptr<const Index>> index = Index::FromBytes(bytes);
  absl::StatusOr<std::shared_ptr<const Index>> index5 = Index::FromBytes(bytes5);
  ASSERT_TRUE(index.ok()) << index.status();
  ASSERT_TRUE(index5.ok()) << index5.status();
  EXPECT_EQ((*index5)->header().format_major, kSparseSplitFormatMajor);
  auto same = [](auto a, auto b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size_bytes()) == 0;
  };
  EXPECT_TRUE(same((*index)->twins(), std::span<const int32_t>(d.twins)));
  EXPECT_TRUE(same((*index)->bvh_nodes(), std::span<const BvhNode>(d.bvh_nodes)));
  EXPECT_TRUE(same((*index)->bvh_faces(), std::span<const int32_t>(d.bvh_faces)));
  EXPECT_TRUE(same((*index)->vertices(), std::span<const VertexRecord>(d.vertices)));
  EXPECT_TRUE(same((*index5)->vertices(), (*index)->vertices()));
  EXPECT_TRUE(same((*index5)->twins(), (*index)->twins()));
  EXPECT_EQ(Serialize(ToIndexData(**index)), bytes);
  EXPECT_EQ(Serialize(ToIndexData(**index5)), bytes5);
  EXPECT_EQ(PredictIndexBytes(d), bytes.size());
  EXPECT_EQ(PredictIndexBytes(v5), bytes5.size());

  // Twins the reader would not derive so (here a seam left open) are stored,
  // and read as stored.
  IndexData seam = d;
  const int32_t h = 0, twin = seam.twins[0];
  seam.twins[h] = seam.twins[twin] = -1;
  const std::string seam_bytes = Serialize(seam);
  absl::StatusOr<std::shared_ptr<const Index>> seamed = Index::FromBytes(seam_bytes);
  ASSERT_TRUE(seamed.ok()) << seamed.status();
  EXPECT_TRUE(same((*seamed)->twins(), std::span<const int32_t>(seam.twins)));
  EXPECT_EQ(PredictIndexBytes(seam), seam_bytes.size());

  // What the derivations refuse is DataLoss naming it; a 6.0 file with an
  // older version's records, or relabelled older, is refused.
  const std::vector<Case> cases = {
      {"a face repeated: edges run the same way",
       [&](Image& i) {
         for (int k = 0; k < 3; ++k) i.Set<int32_t>(SectionId::kFaces, 3 + k, d.faces[k]);
       },
       "twins: "},
      {"a BVH of another size than the header's",
       [&](Image& i) { i.header.num_bvh_nodes += 1; }, "face BVH"},
      {"a record's triangle out of range",
       [&](Image& i) {
         VertexRecord r = i.Get<VertexRecord>(SectionId::kCompactVertexRecords, 3);
         r.triangle = static_cast<int32_t>(d.triangles.size());
         i.Set(SectionId::kCompactVertexRecords, 3, r);
       },
       "vertex record 3"},
      {"relabelled 5.0", [&](Image& i) { i.header.format_major = kSparseSplitFormatMajor; },
       "missing section: twins"},
  };
  ExpectDataLoss(bytes, cases);
  Image relabelled = Image::Parse(bytes5);
  relabelled.header.format_major = kDerivedFormatMajor;
  const absl::Status status = Index::FromBytes(relabelled.Layout()).status();
  EXPECT_EQ(status.code(), absl::StatusCode::kDataLoss);
  EXPECT_THAT(status.message(), HasSubstr("the section vertex records"));
}

// A split whose weights are all 128ths (a midpoint split's, to seven
// halvings) is written in 6.0 with codes: 16 bytes a face dense, 20 a piece
// sparse, for 40 and 44; other weights keep the float records. Either reads
// back to the same pieces and is written again to the same bytes.
TEST(IndexTest, SplitWeightsIn128thsAreWrittenAsCodes) {
  // 20 coarse faces, each cut into four pieces at weight w along an edge.
  auto make = [](float w) {
    IndexData d = MakeSphereIndex();
    d.sample_matrix = MatrixLayout::kCoded;
    d.coarse_faces.assign(d.faces.begin(), d.faces.begin() + 3 * 20);
    for (int32_t f = 0; f < static_cast<int32_t>(d.faces.size() / 3); ++f) {
      SplitFaceRecord r{};
      r.coarse_face = f % 20;
      for (int i = 0; i < 3; ++i) r.weight[i][i] = 1;
      r.weight[0][0] = 1 - w;
      r.weight[0][1] = w;
      d.split_faces.push_back(r);
    }
    d.params.split_vertices = 1;
    return d;
  };
  auto has = [](const Image& image, SectionId id) {
    return std::any_of(image.entries.begin(), image.entries.end(),
                       [id](const SectionEntry& e) { return e.id == static_cast<uint32_t>(id); });
  };
  struct Expected {
    IndexData data;
    SectionId section;
  };
  const Expected cases[] = {{make(0.5f), SectionId::kSplitFaceCodes},
                            {make(1.0f / 3), SectionId::kSplitFaces},
                            {MakeSparseSplitSphereIndex(), SectionId::kSplitPieceCodes}};
  for (const Expected& c : cases) {
    const std::string bytes = Serialize(c.data);
    const Image image = Image::Parse(bytes);
    EXPECT_TRUE(has(image, c.section)) << static_cast<int>(c.section);
    int split_sections = 0;
    for (SectionId id : {SectionId::kSplitFaces, SectionId::kSplitFaceCodes,
                         SectionId::kSplitPieces, SectionId::kSplitPieceCodes}) {
      split_sections += has(image, id);
    }
    EXPECT_EQ(split_sections, 1);
    absl::StatusOr<std::shared_ptr<const Index>> index = Index::FromBytes(bytes);
    ASSERT_TRUE(index.ok()) << index.status();
    for (int32_t f = 0; f < (*index)->num_faces(); ++f) {
      const SplitFaceRecord r = (*index)->split().Piece(f);
      EXPECT_EQ(std::memcmp(&r, &c.data.split_faces[f], sizeof(r)), 0) << f;
    }
    EXPECT_EQ(Serialize(ToIndexData(**index)), bytes);
    EXPECT_EQ(PredictIndexBytes(c.data), bytes.size());
  }
  // 16 bytes a face for 40.
  EXPECT_EQ(Image::Parse(Serialize(make(0.5f))).Payload(SectionId::kSplitFaceCodes).size(),
            80 * sizeof(SplitFaceCode));
  const std::vector<Case> corrupt = {
      {"a code over 128",
       [&](Image& i) {
         SplitFaceCode code = i.Get<SplitFaceCode>(SectionId::kSplitFaceCodes, 3);
         code.weight[1][1] = 129;
         i.Set(SectionId::kSplitFaceCodes, 3, code);
       },
       "split piece 3"},
      {"reserved bytes",
       [&](Image& i) {
         SplitFaceCode code = i.Get<SplitFaceCode>(SectionId::kSplitFaceCodes, 5);
         code.reserved[2] = 1;
         i.Set(SectionId::kSplitFaceCodes, 5, code);
       },
       "split piece 5"},
      {"weights not summing to 1",
       [&](Image& i) {
         SplitFaceCode code = i.Get<SplitFaceCode>(SectionId::kSplitFaceCodes, 7);
         code.weight[2][2] = 64;
         i.Set(SectionId::kSplitFaceCodes, 7, code);
       },
       "piece 7"},
  };
  ExpectDataLoss(Serialize(make(0.5f)), corrupt);
}

TEST(IndexTest, RefinementCorruptionWithValidChecksumsIsDataLoss) {
  const std::string bytes = Serialize(MakeRefinedSphereIndex());
  const int32_t nv = 43;
  // A record is 10 four-byte words: the coarse face, then 3 x 3 weights.
  auto weight = [](int32_t face, int corner, int k) { return 10 * face + 1 + 3 * corner + k; };
  const std::vector<Case> cases = {
      {"piece of a coarse face out of range",
       [&](Image& i) { i.Set<int32_t>(SectionId::kSplitFaces, 10 * 3, 80); }, "piece 3"},
      {"NaN weight",
       [&](Image& i) {
         i.Set<float>(SectionId::kSplitFaces, weight(4, 1, 1),
                      std::numeric_limits<float>::quiet_NaN());
       },
       "piece 4"},
      {"weights not summing to 1",
       [&](Image& i) { i.Set<float>(SectionId::kSplitFaces, weight(5, 2, 0), 0.5f); },
       "piece 5"},
      {"negative weight",
       [&](Image& i) {
         i.Set<float>(SectionId::kSplitFaces, weight(6, 0, 0), 1.5f);
         i.Set<float>(SectionId::kSplitFaces, weight(6, 0, 1), -0.5f);
       },
       "piece 6"},
      {"coarse face without a piece",
       [&](Image& i) { i.Set<int32_t>(SectionId::kSplitFaces, 0, 1); }, "coarse face 0 has no"},
      {"coarse face on a midpoint",
       [&](Image& i) { i.Set<int32_t>(SectionId::kCoarseFaces, 7, nv - 1); }, "coarse face 2"},
      {"more midpoints than vertices", [&](Image& i) { i.header.params.split_vertices = nv + 1; },
       "midpoints"},
      {"split sections in a 1.x file", [&](Image& i) { i.header.format_major = kFormatMajor; },
       "split sections"},
  };
  ExpectDataLoss(bytes, cases);
}

TEST(IndexTest, SpreadBoundCorruptionWithValidChecksumsIsDataLoss) {
  IndexData d = MakeSphereIndex();
  d.accuracy = {AccuracyRecord{}};
  d.accuracy[0].scale_length = 0.1f;
  d.spread_bounds = {SpreadBoundRecord{}};
  const std::string bytes = Serialize(d);
  // The record is epsilon[2][8] then factor[2][8], four-byte words.
  const std::vector<Case> cases = {
      {"NaN factor",
       [&](Image& i) {
         i.Set<float>(SectionId::kSpreadBounds, 16 + 3, std::numeric_limits<float>::quiet_NaN());
       },
       "spread bounds"},
      {"negative epsilon", [&](Image& i) { i.Set<float>(SectionId::kSpreadBounds, 9, -1.0f); },
       "spread bounds"},
      {"spread bounds without a calibration", [&](Image& i) { i.Remove(SectionId::kAccuracy); },
       "spread bounds"},
  };
  ExpectDataLoss(bytes, cases);
}

// A corruption of the file's structure: the file it makes of the sphere
// index's image, and the message its DataLoss names.
struct StructuralCase {
  std::string name;
  std::function<std::string(Image&)> corrupt;
  std::string message;
};

void ExpectStructuralDataLoss(const std::vector<StructuralCase>& cases) {
  const std::string bytes = Serialize(MakeSphereIndex());
  for (const StructuralCase& c : cases) {
    Image image = Image::Parse(bytes);
    const std::string corrupt = c.corrupt(image);
    const absl::Status status = Index::FromBytes(corrupt).status();
    EXPECT_EQ(status.code(), absl::StatusCode::kDataLoss) << c.name << ": " << status;
    EXPECT_THAT(status.message(), HasSubstr(c.message)) << c.name;
  }
}

TEST(IndexTest, StructuralCorruptionOfTheSectionsIsDataLoss) {
  const std::vector<StructuralCase> cases = {
      {"missing required section",
       [](Image& i) {
         i.Remove(SectionId::kTriangles);
         return i.Layout();
       },
       "missing section: geodesic triangles"},
      {"missing BVH faces with a BVH",
       [](Image& i) {
         i.Remove(SectionId::kBvhFaces);
         return i.Layout();
       },
       "missing section: BVH faces"},
      {"duplicate section",
       [](Image& i) {
         i.entries.push_back(i.entries[1]);
         i.payloads.push_back(i.payloads[1]);
         return i.Layout();
       },
       "appears twice"},
      {"section shorter than the counts say",
       [](Image& i) {
         i.Payload(SectionId::kSamples).resize(4);
         return i.Layout();
       },
       "section samples"},
      {"header count larger than the section",
       [](Image& i) {
         ++i.header.num_triangles;
         return i.Layout();
       },
       "section geodesic triangles"},
      {"wrong element size",
       [](Image& i) {
         i.entries[1].element_size = 8;
         return i.Layout();
       },
       "element size"},
      {"params disagree with counts",
       [](Image& i) {
         ++i.header.params.num_samples;
         return i.Layout();
       },
       "num_samples"},
  };
  ExpectStructuralDataLoss(cases);
}

TEST(IndexTest, StructuralCorruptionOfTheLayoutIsDataLoss) {
  const std::vector<StructuralCase> cases = {
      {"misaligned section",
       [](Image& i) {
         std::string out = i.Layout();
         i.entries[2].offset += 4;
         return i.Finish(out);
       },
       "aligned"},
      {"section beyond the end",
       [](Image& i) {
         std::string out = i.Layout();
         i.entries.back().offset = (out.size() / kAlignment + 10) * kAlignment;
         return i.Finish(out);
       },
       "do not fit"},
      {"section size overflowing",
       [](Image& i) {
         std::string out = i.Layout();
         i.entries[3].size = ~uint64_t{0} - 8;
         return i.Finish(out);
       },
       "do not fit"},
      {"overlapping sections",
       [](Image& i) {
         // An unknown section (zeros) moved onto the positions, checksummed.
         i.entries.push_back(UnknownEntry(500, 1));
         i.payloads.push_back(std::string(64, '\0'));
         std::string out = i.Layout();
         SectionEntry& e = i.entries.back();
         e.offset = i.entries[0].offset;
         e.checksum = XXH64(out.data() + e.offset, e.size, 0);
         return i.Finish(out);
       },
       "overlapping"},
      {"section table beyond the end",
       [](Image& i) {
         std::string out = i.Layout();
         i.header.num_sections = 1000;
         return i.Finish(out);
       },
       "section table"},
      {"section table overlapping the header",
       [](Image& i) {
         std::string out = i.Layout();
         i.header.section_table_offset = 64;
         return i.WriteHeader(out);
       },
       "section table offset"},
      {"non-zero padding",
       [](Image& i) {
         std::string out = i.Layout();
         out[i.entries[0].offset - 1] = 1;
         return out;
       },
       "non-zero padding"},
  };
  ExpectStructuralDataLoss(cases);
}

}  // namespace
}  // namespace geodex::index
