#include "core/index/index.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "core/index/index_testing.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::index {
namespace {

using namespace testing_util;  // NOLINT: the shared fixtures of the index tests
using ::testing::HasSubstr;

TEST(IndexTest, RoundTripFromBytes) {
  const IndexData d = MakeSphereIndex();
  const std::string bytes = Serialize(d);
  absl::StatusOr<std::shared_ptr<const Index>> index = Index::FromBytes(bytes);
  ASSERT_TRUE(index.ok()) << index.status();
  ExpectSameData(**index, d);
  EXPECT_FALSE((*index)->is_mapped());
  EXPECT_EQ((*index)->size_bytes(), bytes.size());
  EXPECT_EQ(reinterpret_cast<uintptr_t>((*index)->positions().data()) % kAlignment, 0u);
  EXPECT_EQ((*index)->header().format_major, kFormatMajor);
  EXPECT_EQ((*index)->header().format_minor, kFormatMinor);
}

// Format 3.0: the matrix stored once. The same distances from
// SampleDistance, half the matrix bytes, and a 3.x file copied through
// ToIndexData is written packed again.
TEST(IndexTest, MatrixStoredOnceRoundTrips) {
  IndexData d = MakeSphereIndex();
  const std::string full = Serialize(d);
  d.sample_matrix = MatrixLayout::kLower;
  const std::string packed = Serialize(d);
  absl::StatusOr<std::shared_ptr<const Index>> index = Index::FromBytes(packed);
  ASSERT_TRUE(index.ok()) << index.status();
  EXPECT_EQ((*index)->header().format_major, kPackedFormatMajor);
  EXPECT_EQ((*index)->header().format_minor, kPackedFormatMinor);
  EXPECT_EQ((*index)->matrix().layout(), MatrixLayout::kLower);
  EXPECT_TRUE((*index)->sample_distances().empty());
  const int32_t m = (*index)->num_samples();
  EXPECT_EQ((*index)->sample_distances_lower().size(), static_cast<size_t>(m * (m - 1) / 2));
  for (int32_t i = 0; i < m; ++i) {
    for (int32_t j = 0; j < m; ++j) {
      EXPECT_EQ((*index)->SampleDistance(i, j), d.sample_distances[i * m + j]) << i << " " << j;
    }
  }
  // The matrix's bytes: m^2 floats before, m (m - 1) / 2 now (to alignment).
  const size_t saved = full.size() - packed.size();
  EXPECT_GE(saved + 2 * kAlignment, sizeof(float) * (m * m - m * (m - 1) / 2));
  EXPECT_EQ(Serialize(ToIndexData(**index)), packed);
  // Older files still read, in their layout.
  absl::StatusOr<std::shared_ptr<const Index>> old = Index::FromBytes(full);
  ASSERT_TRUE(old.ok()) << old.status();
  EXPECT_EQ((*old)->matrix().layout(), MatrixLayout::kFull);
  EXPECT_EQ((*old)->SampleDistance(3, 7), (*index)->SampleDistance(3, 7));
  // Only a symmetric matrix with a zero diagonal is stored once.
  IndexData asymmetric = d;
  asymmetric.sample_distances[1 * m + 2] += 0.5f;
  EXPECT_EQ(SerializeIndex(asymmetric).status().code(), absl::StatusCode::kInvalidArgument);
  IndexData diagonal = d;
  diagonal.sample_distances[2 * m + 2] = 0.1f;
  EXPECT_EQ(SerializeIndex(diagonal).status().code(), absl::StatusCode::kInvalidArgument);
}

// Format 4.0: the lower triangle in 24-bit codes. Every distance within
// 2^-22 of itself (or 2^-30 of the largest below 1/256 of it), 3/8 of
// the full matrix's bytes, +inf kept, and written again to the same bytes.
TEST(IndexTest, CodedMatrixRoundTrips) {
  IndexData d = MakeSphereIndex();
  const int32_t m = static_cast<int32_t>(d.samples.size());
  d.sample_distances[1 * m + 0] = d.sample_distances[0 * m + 1] =
      std::numeric_limits<float>::infinity();
  const std::string full = Serialize(d);
  d.sample_matrix = MatrixLayout::kCoded;
  const std::string coded = Serialize(d);
  absl::StatusOr<std::shared_ptr<const Index>> index = Index::FromBytes(coded);
  ASSERT_TRUE(index.ok()) << index.status();
  EXPECT_EQ((*index)->header().format_major, kDerivedFormatMajor);
  EXPECT_EQ((*index)->header().format_minor, kDerivedFormatMinor);
  EXPECT_EQ((*index)->matrix().layout(), MatrixLayout::kCoded);
  EXPECT_TRUE((*index)->sample_distances().empty());
  EXPECT_TRUE((*index)->sample_distances_lower().empty());
  EXPECT_EQ((*index)->sample_distances_coded().size(), static_cast<size_t>(m * (m - 1) / 2));
  double largest = 0;
  for (float x : d.sample_distances) {
    if (std::isfinite(x)) largest = std::max(largest, static_cast<double>(x));
  }
  for (int32_t i = 0; i < m; ++i) {
    for (int32_t j = 0; j < m; ++j) {
      const double exact = d.sample_distances[i * m + j];
      const double got = (*index)->SampleDistance(i, j);
      if (!std::isfinite(exact)) {
        EXPECT_EQ(got, exact) << i << " " << j;
        continue;
      }
      EXPECT_LE(std::abs(got - exact), std::max(0x1p-22 * exact, 0x1p-30 * largest) * 1.0001)
          << i << " " << j;
      EXPECT_EQ(got, (*index)->SampleDistance(j, i));
    }
  }
  const size_t saved = full.size() - coded.size();
  EXPECT_GE(saved + 3 * kAlignment, sizeof(float) * m * m - sizeof(PackedCode) * (m * (m - 1) / 2));
  EXPECT_EQ(Serialize(ToIndexData(**index)), coded);
  // A NaN has no code.
  IndexData nan = d;
  nan.sample_distances[2 * m + 1] = nan.sample_distances[1 * m + 2] = std::nanf("");
  EXPECT_EQ(SerializeIndex(nan).status().code(), absl::StatusCode::kInvalidArgument);
}

TEST(IndexTest, PredictedBytesAreTheWrittenBytes) {
  IndexData d = MakeSphereIndex();
  for (MatrixLayout layout : {MatrixLayout::kFull, MatrixLayout::kLower, MatrixLayout::kCoded}) {
    d.sample_matrix = layout;
    EXPECT_EQ(PredictIndexBytes(d), Serialize(d).size());
    IndexData without_matrix = d;
    without_matrix.sample_distances.clear();
    EXPECT_EQ(PredictIndexBytes(without_matrix), Serialize(d).size());
  }
}

// The code itself: nearest, increasing, exact at 0 and the largest distance.
TEST(DistanceCodeTest, NearestCodeWithinItsPrecision) {
  const double largest = 3.7;
  const double scale = DistanceCode::ScaleFor(largest);
  EXPECT_EQ(DistanceCode::Encode(0, scale), 0);
  EXPECT_EQ(DistanceCode::Decode(0, scale), 0);
  EXPECT_EQ(DistanceCode::Encode(largest, scale), DistanceCode::kLargest);
  EXPECT_NEAR(DistanceCode::Decode(DistanceCode::kLargest, scale), largest, 1e-15);
  EXPECT_EQ(DistanceCode::Encode(std::numeric_limits<double>::infinity(), scale),
            DistanceCode::kInfinity);
  EXPECT_EQ(DistanceCode::Decode(DistanceCode::kInfinity, scale),
            std::numeric_limits<double>::infinity());
  for (uint32_t c = 1; c <= DistanceCode::kLargest; ++c) {
    ASSERT_LT(DistanceCode::Unit(c - 1), DistanceCode::Unit(c));
  }
  for (uint32_t c : {0u, 1u, 0x123456u, DistanceCode::kLargest, DistanceCode::kInfinity}) {
    EXPECT_EQ(DistanceCode::Unpack(DistanceCode::Pack(c)), c);
  }
  double worst_relative = 0;
  for (int k = 0; k <= 200000; ++k) {
    const double d = largest * std::pow(1e-6, k / 200000.0);
    const uint32_t c = DistanceCode::Encode(d, scale);
    const double error = std::abs(DistanceCode::Decode(c, scale) - d);
    // No other code is nearer.
    if (c > 0) {
      EXPECT_GE(std::abs(DistanceCode::Decode(c - 1, scale) - d), error) << d;
    }
    if (c < DistanceCode::kLargest) {
      EXPECT_GE(std::abs(DistanceCode::Decode(c + 1, scale) - d), error) << d;
    }
    if (d >= largest / 16) worst_relative = std::max(worst_relative, error / d);
    EXPECT_LE(error, 0x1p-22 * (d + 0x1p-8 * scale) * 1.0001) << d;
    if (d < 0x1p-8 * scale) {
      EXPECT_LE(error, 0x1p-30 * scale * 1.0001) << d;
    }
  }
  // A sixteenth of the largest distance and more: within 2^-22 (1 + 1/16).
  EXPECT_LE(worst_relative, 0x1p-22 * (1 + 1.0 / 16) * 1.0001);
  EXPECT_GT(worst_relative, 0x1p-23);  // the bound is tight, not vacuous
}

AccuracyRecord SomeAccuracy() {
  AccuracyRecord r{};
  r.scale_length = 0.1f;
  r.num_sources = 4;
  r.num_pairs = 100;
  r.bound_quantile_permille = 995;
  for (int b = 0; b < kAccuracyBins; ++b) {
    r.unfold_bound[0][b] = 0.01f * b;
    r.unfold_bound[1][b] = 0.02f * b;
    for (int k = 0; k < 4; ++k) r.trace_bound[k][b] = 0.001f * (k + b);
  }
  r.p99[3] = 0.01f;
  return r;
}

TEST(IndexTest, AccuracyCalibrationRoundTripsAndIsOptional) {
  IndexData d = MakeSphereIndex();
  auto without = Index::FromBytes(Serialize(d));
  ASSERT_TRUE(without.ok()) << without.status();
  EXPECT_EQ((*without)->accuracy(), nullptr);
  d.accuracy = {SomeAccuracy()};
  auto with = Index::FromBytes(Serialize(d));
  ASSERT_TRUE(with.ok()) << with.status();
  ASSERT_NE((*with)->accuracy(), nullptr);
  EXPECT_EQ(std::memcmp((*with)->accuracy(), &d.accuracy[0], sizeof(AccuracyRecord)), 0);
  // ToIndexData keeps it: the same bytes again.
  EXPECT_EQ(Serialize(ToIndexData(**with)), Serialize(d));
}

TEST(IndexTest, BadAccuracyCalibrationIsRefused) {
  IndexData d = MakeSphereIndex();
  d.accuracy = {SomeAccuracy(), SomeAccuracy()};
  EXPECT_EQ(SerializeIndex(d).status().code(), absl::StatusCode::kInvalidArgument);
  d.accuracy = {SomeAccuracy()};
  d.accuracy[0].trace_bound[2][3] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(SerializeIndex(d).status().code(), absl::StatusCode::kInvalidArgument);
  d.accuracy[0].trace_bound[2][3] = -1;
  EXPECT_EQ(SerializeIndex(d).status().code(), absl::StatusCode::kInvalidArgument);
}

SpreadBoundRecord SomeSpreadBounds() {
  SpreadBoundRecord r{};
  for (int k = 0; k < 2; ++k) {
    for (int b = 0; b < kAccuracyBins; ++b) {
      r.epsilon[k][b] = 0.001f * (1 + b);
      r.factor[k][b] = 2.0f + k;
    }
  }
  return r;
}

TEST(IndexTest, SpreadBoundsRoundTripBesideTheCalibrationAndAreOptional) {
  IndexData d = MakeSphereIndex();
  d.accuracy = {SomeAccuracy()};
  const std::string without_bytes = Serialize(d);
  auto without = Index::FromBytes(without_bytes);
  ASSERT_TRUE(without.ok()) << without.status();
  EXPECT_EQ((*without)->spread_bounds(), nullptr);
  d.spread_bounds = {SomeSpreadBounds()};
  const std::string bytes = Serialize(d);
  // One more section than without: it is written only when present.
  EXPECT_EQ(Image::Parse(bytes).header.num_sections,
            Image::Parse(without_bytes).header.num_sections + 1);
  auto with = Index::FromBytes(bytes);
  ASSERT_TRUE(with.ok()) << with.status();
  ASSERT_NE((*with)->spread_bounds(), nullptr);
  EXPECT_EQ(std::memcmp((*with)->spread_bounds(), &d.spread_bounds[0], sizeof(SpreadBoundRecord)),
            0);
  EXPECT_EQ(Serialize(ToIndexData(**with)), bytes);
}

TEST(IndexTest, BadSpreadBoundsAreRefused) {
  IndexData d = MakeSphereIndex();
  d.spread_bounds = {SomeSpreadBounds()};  // without a calibration
  EXPECT_EQ(SerializeIndex(d).status().code(), absl::StatusCode::kInvalidArgument);
  d.accuracy = {SomeAccuracy()};
  d.spread_bounds = {SomeSpreadBounds(), SomeSpreadBounds()};
  EXPECT_EQ(SerializeIndex(d).status().code(), absl::StatusCode::kInvalidArgument);
  for (float bad :
       {-1.0f, std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
    d.spread_bounds = {SomeSpreadBounds()};
    d.spread_bounds[0].factor[1][5] = bad;
    EXPECT_EQ(SerializeIndex(d).status().code(), absl::StatusCode::kInvalidArgument) << bad;
    d.spread_bounds = {SomeSpreadBounds()};
    d.spread_bounds[0].epsilon[0][2] = bad;
    EXPECT_EQ(SerializeIndex(d).status().code(), absl::StatusCode::kInvalidArgument) << bad;
  }
}

TEST(IndexTest, LayoutFollowsTheFormat) {
  const std::string bytes = Serialize(MakeSphereIndex());
  const Image image = Image::Parse(bytes);
  EXPECT_EQ(std::memcmp(image.header.magic, kMagic, sizeof(kMagic)), 0);
  EXPECT_EQ(image.header.byte_order_mark, kByteOrderMark);
  EXPECT_EQ(image.header.header_size, sizeof(FileHeader));
  EXPECT_EQ(image.header.section_table_offset, sizeof(FileHeader));
  EXPECT_EQ(image.header.file_size, bytes.size());
  ASSERT_EQ(image.header.num_sections, 11u);
  for (const SectionEntry& e : image.entries) {
    EXPECT_EQ(e.offset % kAlignment, 0u) << e.id;
    EXPECT_EQ(e.checksum, XXH64(bytes.data() + e.offset, e.size, 0)) << e.id;
  }
  EXPECT_EQ(image.entries[0].id, static_cast<uint32_t>(SectionId::kPositions));
  EXPECT_EQ(image.entries[0].element_size, sizeof(double));
  EXPECT_EQ(image.entries[5].element_size, sizeof(VertexRecordWithCorners));
}

TEST(IndexTest, SerializationIsDeterministic) {
  const std::string a = Serialize(MakeSphereIndex());
  const std::string b = Serialize(MakeSphereIndex());
  EXPECT_FALSE(a.empty());
  EXPECT_TRUE(a == b);
}

TEST(IndexTest, EmptyOptionalSectionsRoundTrip) {
  IndexData d = MakeSphereIndex();
  d.bvh_nodes.clear();
  d.bvh_faces.clear();
  d.report.clear();
  const std::string bytes = Serialize(d);
  absl::StatusOr<std::shared_ptr<const Index>> index = Index::FromBytes(bytes);
  ASSERT_TRUE(index.ok()) << index.status();
  ExpectSameData(**index, d);
  EXPECT_TRUE((*index)->bvh_nodes().empty());
  EXPECT_TRUE((*index)->report().empty());
  // Absent (rather than empty) optional sections are accepted too.
  Image image = Image::Parse(bytes);
  image.Remove(SectionId::kFaceBvh);
  image.Remove(SectionId::kBvhFaces);
  image.Remove(SectionId::kReport);
  index = Index::FromBytes(image.Layout());
  ASSERT_TRUE(index.ok()) << index.status();
  ExpectSameData(**index, d);
}

TEST(IndexTest, InfiniteSampleDistanceAllowed) {
  // Samples on different connected components are infinitely far apart.
  IndexData d = MakeSphereIndex();
  const size_t m = d.samples.size();
  d.sample_distances[0 * m + 1] = d.sample_distances[1 * m + 0] = kInf;
  absl::StatusOr<std::shared_ptr<const Index>> index = Index::FromBytes(Serialize(d));
  ASSERT_TRUE(index.ok()) << index.status();
  EXPECT_EQ((*index)->SampleDistance(0, 1), kInf);
}

TEST(IndexTest, SerializeRejectsInconsistentData) {
  struct Case {
    std::string name;
    std::function<void(IndexData&)> change;
  };
  const std::vector<Case> cases = {
      {"positions not triples", [](IndexData& d) { d.positions.pop_back(); }},
      {"faces not triples", [](IndexData& d) { d.faces.pop_back(); }},
      {"twins size", [](IndexData& d) { d.twins.pop_back(); }},
      {"matrix size", [](IndexData& d) { d.sample_distances.pop_back(); }},
      {"vertex records size", [](IndexData& d) { d.vertices.pop_back(); }},
      {"bvh faces size", [](IndexData& d) { d.bvh_faces.pop_back(); }},
      {"bvh faces without nodes", [](IndexData& d) { d.bvh_nodes.clear(); }},
      {"params.num_samples", [](IndexData& d) { d.params.num_samples++; }},
      {"builder version too long", [](IndexData& d) { d.builder_version.assign(32, 'v'); }},
      {"face out of range", [](IndexData& d) { d.faces[4] = 1000; }},
      {"NaN distance",
       [](IndexData& d) { d.sample_distances[3] = std::numeric_limits<float>::quiet_NaN(); }},
      {"sample out of range", [](IndexData& d) { d.samples[0] = -1; }},
  };
  for (const Case& c : cases) {
    IndexData d = MakeSphereIndex();
    c.change(d);
    EXPECT_EQ(SerializeIndex(d).status().code(), absl::StatusCode::kInvalidArgument) << c.name;
  }
}

TEST(IndexTest, MeshHashCoversPositionsThenFaces) {
  const IndexData d = MakeSphereIndex();
  std::string bytes(reinterpret_cast<const char*>(d.positions.data()),
                    d.positions.size() * sizeof(double));
  bytes.append(reinterpret_cast<const char*>(d.faces.data()), d.faces.size() * sizeof(int32_t));
  EXPECT_EQ(MeshHash(d.positions, d.faces), XXH64(bytes.data(), bytes.size(), 0));
  std::vector<double> moved = d.positions;
  moved[5] += 1e-12;
  EXPECT_NE(MeshHash(moved, d.faces), MeshHash(d.positions, d.faces));
}

class IndexFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern =
        (std::filesystem::path(testing::TempDir()) / "index_test.XXXXXX").string();
    ASSERT_NE(::mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  std::vector<std::string> Files() const {
    std::vector<std::string> names;
    for (const auto& entry : std::filesystem::directory_iterator(dir_)) {
      names.push_back(entry.path().filename().string());
    }
    std::sort(names.begin(), names.end());
    return names;
  }

  std::filesystem::path dir_;
};

TEST_F(IndexFileTest, WriteThenOpenMapped) {
  const IndexData d = MakeSphereIndex();
  const std::string path = (dir_ / "index.gdx").string();
  ASSERT_TRUE(WriteIndexFile(d, path).ok());
  absl::StatusOr<std::shared_ptr<const Index>> index = Index::Open(path);
  ASSERT_TRUE(index.ok()) << index.status();
  EXPECT_TRUE((*index)->is_mapped());
  ExpectSameData(**index, d);
  EXPECT_EQ((*index)->size_bytes(), std::filesystem::file_size(path));
  EXPECT_EQ(Files(), std::vector<std::string>{"index.gdx"});
}

TEST_F(IndexFileTest, WriteReplacesAtomicallyAndLeavesNoTemporaryFiles) {
  const std::string path = (dir_ / "index.gdx").string();
  IndexData first = MakeSphereIndex();
  ASSERT_TRUE(WriteIndexFile(first, path).ok());
  absl::StatusOr<std::shared_ptr<const Index>> old_index = Index::Open(path);
  ASSERT_TRUE(old_index.ok()) << old_index.status();

  IndexData second = MakeSphereIndex();
  second.report = "second build\n";
  second.builder_version = "geodex-test 0.2";
  ASSERT_TRUE(WriteIndexFile(second, path).ok());
  EXPECT_EQ(Files(), std::vector<std::string>{"index.gdx"});
  absl::StatusOr<std::shared_ptr<const Index>> new_index = Index::Open(path);
  ASSERT_TRUE(new_index.ok()) << new_index.status();
  EXPECT_EQ((*new_index)->report(), "second build\n");
  EXPECT_EQ((*new_index)->builder_version(), "geodex-test 0.2");
  // The mapping of the replaced file stays valid and unchanged.
  ExpectSameData(**old_index, first);
}

TEST_F(IndexFileTest, WriteErrors) {
  const std::string missing_dir = (dir_ / "no" / "such" / "index.gdx").string();
  const absl::Status status = WriteIndexFile(MakeSphereIndex(), missing_dir);
  EXPECT_EQ(status.code(), absl::StatusCode::kNotFound) << status;
  EXPECT_THAT(status.message(), HasSubstr(missing_dir));

  IndexData bad = MakeSphereIndex();
  bad.twins.clear();
  const std::string path = (dir_ / "bad.gdx").string();
  EXPECT_EQ(WriteIndexFile(bad, path).code(), absl::StatusCode::kInvalidArgument);
  EXPECT_TRUE(Files().empty());
}

TEST_F(IndexFileTest, OpenErrors) {
  const std::string missing = (dir_ / "missing.gdx").string();
  absl::Status status = Index::Open(missing).status();
  EXPECT_EQ(status.code(), absl::StatusCode::kNotFound) << status;
  EXPECT_THAT(status.message(), HasSubstr(missing));

  EXPECT_EQ(Index::Open(dir_.string()).status().code(), absl::StatusCode::kFailedPrecondition);

  const std::string empty = (dir_ / "empty.gdx").string();
  std::ofstream(empty).close();
  status = Index::Open(empty).status();
  EXPECT_EQ(status.code(), absl::StatusCode::kDataLoss) << status;
  EXPECT_THAT(status.message(), HasSubstr(empty));

  const std::string text = (dir_ / "text.gdx").string();
  std::ofstream(text) << std::string(500, 'x');
  status = Index::Open(text).status();
  EXPECT_EQ(status.code(), absl::StatusCode::kFailedPrecondition) << status;
  EXPECT_THAT(status.message(), HasSubstr("not a geodex index"));

  // A truncated file on disk.
  const std::string bytes = Serialize(MakeSphereIndex());
  const std::string truncated = (dir_ / "truncated.gdx").string();
  std::ofstream(truncated, std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  status = Index::Open(truncated).status();
  EXPECT_EQ(status.code(), absl::StatusCode::kDataLoss) << status;
  EXPECT_THAT(status.message(), HasSubstr("truncated"));
}

// Format 1.2: the input ids of a repaired mesh (core/mesh/mesh_repair.h).
IndexData WithInputIds(IndexData d) {
  const int32_t nf = static_cast<int32_t>(d.faces.size() / 3);
  for (int32_t f = 0; f < nf; ++f) d.input_faces.push_back({f, {0, 1, 2}, 0});
  d.input_faces[3] = {3, {0, 2, 1}, kInputFaceReoriented};
  d.input_faces.push_back({3, {1, 0, 2}, kInputFaceDropped});  // a duplicate of face 3
  d.vertex_copies = {5};  // the last vertex is a copy of vertex 5
  return d;
}

TEST(IndexTest, InputIdSectionsRoundTripAndAreAbsentWithoutRepair) {
  // Not repaired: the sections are not written (the 1.1 layout).
  EXPECT_EQ(Image::Parse(Serialize(MakeSphereIndex())).header.num_sections, 11u);
  const IndexData d = WithInputIds(MakeSphereIndex());
  const std::string bytes = Serialize(d);
  Image image = Image::Parse(bytes);
  EXPECT_EQ(image.header.num_sections, 13u);
  EXPECT_EQ(image.header.format_minor, kFormatMinor);
  absl::StatusOr<std::shared_ptr<const Index>> index = Index::FromBytes(bytes);
  ASSERT_TRUE(index.ok()) << index.status();
  ExpectSameData(**index, d);
  EXPECT_TRUE(SameBytes((*index)->input_faces(), d.input_faces));
  EXPECT_EQ(ToVector((*index)->vertex_copies()), d.vertex_copies);
  const IndexData copy = ToIndexData(**index);
  EXPECT_TRUE(SameBytes(std::span<const InputFaceRecord>(copy.input_faces), d.input_faces));
  EXPECT_EQ(copy.vertex_copies, d.vertex_copies);
  // An index without them (a mesh that needed no repair, or 1.1) has none:
  // identity maps.
  image.Remove(SectionId::kInputFaces);
  image.Remove(SectionId::kVertexCopies);
  index = Index::FromBytes(image.Layout());
  ASSERT_TRUE(index.ok()) << index.status();
  EXPECT_TRUE((*index)->input_faces().empty());
  EXPECT_TRUE((*index)->vertex_copies().empty());
}

TEST(IndexTest, BadInputIdSectionsAreRefused) {
  const IndexData good = WithInputIds(MakeSphereIndex());
  const int32_t nf = static_cast<int32_t>(good.faces.size() / 3);
  struct Case {
    const char* what;
    std::function<void(IndexData&)> edit;
    const char* message;
  };
  const Case cases[] = {
      {"face out of range", [&](IndexData& d) { d.input_faces[0].face = nf; }, "input face 0"},
      {"corners not a permutation", [](IndexData& d) { d.input_faces[1].corner[2] = 1; },
       "input face 1"},
      {"unknown flag", [](IndexData& d) { d.input_faces[2].flags = 4; }, "input face 2"},
      {"a face kept twice", [](IndexData& d) { d.input_faces.back().flags = 0; },
       "face 3 is kept twice"},
      {"a face of no input face", [](IndexData& d) { d.input_faces[7].flags = kInputFaceDropped; },
       "face 7 is no input face's"},
      {"copy of a copy", [](IndexData& d) { d.vertex_copies = {42}; }, "vertex copy 0"},
  };
  for (const Case& c : cases) {
    IndexData d = good;
    c.edit(d);
    const absl::Status status = SerializeIndex(d).status();
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << c.what;
    EXPECT_THAT(std::string(status.message()), HasSubstr(c.message)) << c.what;
  }
}

}  // namespace
}  // namespace geodex::index
