#include "core/index/index.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "core/index/face_bvh.h"
#include "core/mesh/generators.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

// Header-only xxHash in this file: the test recomputes checksums itself to
// forge files that are corrupt yet consistently checksummed.
#define XXH_INLINE_ALL
#include "xxhash.h"

namespace geodex::index {
namespace {

using ::testing::AnyOf;
using ::testing::HasSubstr;

constexpr float kInf = std::numeric_limits<float>::infinity();

float GreatCircle(const mesh::Vec3& a, const mesh::Vec3& b) {
  return static_cast<float>(std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)));
}

// A small but realistic index: the unit icosphere with one subdivision (42
// vertices, 80 faces) plus one unreferenced vertex at the centre; the 12
// icosahedron vertices are the samples and the 20 icosahedron faces the
// geodesic triangles; distances are great-circle distances; a real face BVH.
IndexData MakeSphereIndex() {
  const mesh::Mesh fine = mesh::gen::Sphere(1, 1.0);
  const mesh::Mesh coarse = mesh::gen::Sphere(0, 1.0);
  IndexData d;
  d.builder_version = "geodex-test 0.1";
  for (const mesh::Vec3& p : fine.positions())
    d.positions.insert(d.positions.end(), {p.x(), p.y(), p.z()});
  d.positions.insert(d.positions.end(), {0.0, 0.0, 0.0});  // unreferenced
  for (const mesh::Triangle& f : fine.faces()) d.faces.insert(d.faces.end(), f.begin(), f.end());
  for (int32_t h = 0; h < fine.num_halfedges(); ++h) d.twins.push_back(fine.Twin(h));
  // Sphere(1) keeps the icosahedron's vertices as its first 12.
  for (int32_t s = 0; s < coarse.num_vertices(); ++s) d.samples.push_back(s);
  const int32_t m = static_cast<int32_t>(d.samples.size());
  for (int32_t i = 0; i < m; ++i) {
    for (int32_t j = 0; j < m; ++j) {
      d.sample_distances.push_back(
          i == j ? 0.0f : GreatCircle(fine.position(d.samples[i]), fine.position(d.samples[j])));
    }
  }
  for (int32_t t = 0; t < coarse.num_faces(); ++t) {
    GeodesicTriangle g;
    for (int k = 0; k < 3; ++k) {
      g.corner[k] = coarse.face(t)[k];
      const int32_t twin = coarse.Twin(3 * t + k);
      g.neighbor[k] = twin == mesh::kNone ? -1 : twin / 3;
    }
    d.triangles.push_back(g);
  }
  for (int32_t v = 0; v < fine.num_vertices(); ++v) {
    const mesh::Vec3& p = fine.position(v);
    VertexRecord r{};
    r.triangle = -1;
    for (int32_t t = 0; t < coarse.num_faces() && r.triangle < 0; ++t) {
      const mesh::Triangle& c = coarse.face(t);
      bool inside = true;
      for (int k = 0; k < 3; ++k) {
        const mesh::Vec3& a = coarse.position(c[k]);
        const mesh::Vec3& b = coarse.position(c[(k + 1) % 3]);
        inside = inside && a.cross(b).dot(p) >= -1e-12;
      }
      if (inside) r.triangle = t;
    }
    EXPECT_GE(r.triangle, 0) << v;
    for (int k = 0; k < 3; ++k) {
      r.corner[k] = coarse.face(r.triangle)[k];
      r.distance[k] = GreatCircle(p, fine.position(d.samples[r.corner[k]]));
    }
    d.vertices.push_back(r);
  }
  VertexRecord none{};
  none.triangle = -1;
  for (int k = 0; k < 3; ++k) {
    none.corner[k] = -1;
    none.distance[k] = kInf;
  }
  d.vertices.push_back(none);
  BuildFaceBvh(d.positions, d.faces, &d.bvh_nodes, &d.bvh_faces);
  d.mesh_hash = MeshHash(d.positions, d.faces);
  d.params = {.requested_samples = 10,
              .num_samples = static_cast<uint32_t>(m),
              .seed = 42,
              .samples_added_by_repair = 2};
  d.report = "samples = 12\nrepairs = 2\n";
  return d;
}

std::string Serialize(const IndexData& d) {
  absl::StatusOr<std::string> bytes = SerializeIndex(d);
  EXPECT_TRUE(bytes.ok()) << bytes.status();
  return bytes.ok() ? *bytes : std::string();
}

template <typename T>
std::vector<T> ToVector(std::span<const T> s) {
  return std::vector<T>(s.begin(), s.end());
}

// Byte-wise equality for the on-disk records (which have no operator==).
template <typename T>
bool SameBytes(std::span<const T> a, const std::vector<T>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size_bytes()) == 0);
}

SectionEntry UnknownEntry(uint32_t id, uint32_t element_size) {
  SectionEntry e{};
  e.id = id;
  e.element_size = element_size;
  return e;
}

void ExpectSameData(const Index& index, const IndexData& d) {
  EXPECT_EQ(index.builder_version(), d.builder_version);
  EXPECT_EQ(index.header().mesh_hash, d.mesh_hash);
  EXPECT_EQ(index.header().params.requested_samples, d.params.requested_samples);
  EXPECT_EQ(index.header().params.num_samples, d.params.num_samples);
  EXPECT_EQ(index.header().params.seed, d.params.seed);
  EXPECT_EQ(index.header().params.samples_added_by_repair, d.params.samples_added_by_repair);
  EXPECT_EQ(index.num_vertices(), static_cast<int32_t>(d.positions.size() / 3));
  EXPECT_EQ(index.num_faces(), static_cast<int32_t>(d.faces.size() / 3));
  EXPECT_EQ(index.num_samples(), static_cast<int32_t>(d.samples.size()));
  EXPECT_EQ(index.num_triangles(), static_cast<int32_t>(d.triangles.size()));
  EXPECT_EQ(ToVector(index.positions()), d.positions);
  EXPECT_EQ(ToVector(index.faces()), d.faces);
  EXPECT_EQ(ToVector(index.twins()), d.twins);
  EXPECT_EQ(ToVector(index.samples()), d.samples);
  EXPECT_EQ(ToVector(index.sample_distances()), d.sample_distances);
  EXPECT_TRUE(SameBytes(index.vertices(), d.vertices));
  EXPECT_TRUE(SameBytes(index.triangles(), d.triangles));
  EXPECT_TRUE(SameBytes(index.bvh_nodes(), d.bvh_nodes));
  EXPECT_EQ(ToVector(index.bvh_faces()), d.bvh_faces);
  EXPECT_EQ(index.report(), d.report);
  const int32_t m = index.num_samples();
  for (int32_t i = 0; i < m; ++i) {
    for (int32_t j = 0; j < m; ++j)
      EXPECT_EQ(index.SampleDistance(i, j), d.sample_distances[i * m + j]);
  }
}

// A parsed file image that the test can edit and lay out again with correct
// checksums, offsets and sizes: corruption that only semantic checks can see.
struct Image {
  FileHeader header;
  std::vector<SectionEntry> entries;
  std::vector<std::string> payloads;

  static Image Parse(const std::string& bytes) {
    Image image;
    std::memcpy(&image.header, bytes.data(), sizeof(FileHeader));
    image.entries.resize(image.header.num_sections);
    std::memcpy(image.entries.data(), bytes.data() + image.header.section_table_offset,
                image.entries.size() * sizeof(SectionEntry));
    for (const SectionEntry& e : image.entries)
      image.payloads.push_back(bytes.substr(e.offset, e.size));
    return image;
  }

  std::string& Payload(SectionId id) {
    for (size_t i = 0; i < entries.size(); ++i) {
      if (entries[i].id == static_cast<uint32_t>(id)) return payloads[i];
    }
    ADD_FAILURE() << "no section " << static_cast<uint32_t>(id);
    return payloads[0];
  }

  template <typename T>
  T Get(SectionId id, size_t i) {
    T value;
    std::memcpy(&value, Payload(id).data() + i * sizeof(T), sizeof(T));
    return value;
  }
  template <typename T>
  void Set(SectionId id, size_t i, const T& value) {
    std::memcpy(Payload(id).data() + i * sizeof(T), &value, sizeof(T));
  }

  void Remove(SectionId id) {
    for (size_t i = 0; i < entries.size(); ++i) {
      if (entries[i].id == static_cast<uint32_t>(id)) {
        entries.erase(entries.begin() + i);
        payloads.erase(payloads.begin() + i);
        return;
      }
    }
  }

  // Lays the sections out again in order; sizes are kept unless
  // `keep_sizes` is false (then they follow the payloads).
  std::string Layout(bool keep_sizes = false) {
    header.num_sections = static_cast<uint32_t>(entries.size());
    header.section_table_offset = header.header_size;
    uint64_t cursor = header.section_table_offset + entries.size() * sizeof(SectionEntry);
    for (size_t i = 0; i < entries.size(); ++i) {
      cursor = (cursor + kAlignment - 1) / kAlignment * kAlignment;
      entries[i].offset = cursor;
      if (!keep_sizes) entries[i].size = payloads[i].size();
      entries[i].checksum = XXH64(payloads[i].data(), payloads[i].size(), 0);
      cursor += payloads[i].size();
    }
    header.file_size = cursor;
    std::string out(cursor, '\0');
    for (size_t i = 0; i < entries.size(); ++i) {
      std::memcpy(out.data() + entries[i].offset, payloads[i].data(), payloads[i].size());
    }
    return Finish(std::move(out));
  }

  // Writes the header and table into `out` with fresh checksums.
  std::string Finish(std::string out) {
    const size_t table_bytes = entries.size() * sizeof(SectionEntry);
    header.table_checksum = XXH64(entries.data(), table_bytes, 0);
    out.replace(header.section_table_offset, table_bytes,
                reinterpret_cast<const char*>(entries.data()), table_bytes);
    return WriteHeader(std::move(out));
  }

  // Writes only the header into `out`, with a fresh header checksum.
  std::string WriteHeader(std::string out) {
    header.header_checksum = 0;
    header.header_checksum = XXH64(&header, sizeof(header), 0);
    out.replace(0, sizeof(header), reinterpret_cast<const char*>(&header), sizeof(header));
    return out;
  }
};

absl::StatusCode CodeOf(const std::string& bytes) {
  return Index::FromBytes(bytes).status().code();
}

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
  EXPECT_EQ(image.entries[5].element_size, sizeof(VertexRecord));
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
  image.header.format_major = kFormatMajor + 1;
  image.header.format_minor = 3;
  const absl::Status status = Index::FromBytes(image.Layout()).status();
  EXPECT_EQ(status.code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(status.message(), HasSubstr(absl::StrCat(kFormatMajor + 1, ".3")));
  EXPECT_THAT(status.message(), HasSubstr(absl::StrCat(kFormatMajor, ".", kFormatMinor)));
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

TEST(IndexTest, SemanticCorruptionWithValidChecksumsIsDataLoss) {
  const IndexData d = MakeSphereIndex();
  const std::string bytes = Serialize(d);
  const int32_t nv = static_cast<int32_t>(d.positions.size() / 3);
  const int32_t nf = static_cast<int32_t>(d.faces.size() / 3);
  const int32_t m = static_cast<int32_t>(d.samples.size());
  const int32_t nt = static_cast<int32_t>(d.triangles.size());
  const int32_t nb = static_cast<int32_t>(d.bvh_nodes.size());
  struct Case {
    std::string name;
    std::function<void(Image&)> corrupt;
    std::string message;
  };
  const float kNaN = std::numeric_limits<float>::quiet_NaN();
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
      {"NaN sample distance", [&](Image& i) { i.Set<float>(SectionId::kSampleDistances, 1, kNaN); },
       "sample distance"},
      {"negative sample distance",
       [&](Image& i) { i.Set<float>(SectionId::kSampleDistances, m + 2, -0.5f); },
       "sample distance (1, 2)"},
      {"vertex triangle out of range",
       [&](Image& i) {
         VertexRecord r = i.Get<VertexRecord>(SectionId::kVertexRecords, 9);
         r.triangle = nt;
         i.Set(SectionId::kVertexRecords, 9, r);
       },
       "vertex record 9"},
      {"vertex corner out of range",
       [&](Image& i) {
         VertexRecord r = i.Get<VertexRecord>(SectionId::kVertexRecords, 9);
         r.corner[2] = m;
         i.Set(SectionId::kVertexRecords, 9, r);
       },
       "vertex record 9"},
      {"corner of a vertex without triangle",
       [&](Image& i) {
         VertexRecord r = i.Get<VertexRecord>(SectionId::kVertexRecords, nv - 1);
         r.corner[0] = 0;
         i.Set(SectionId::kVertexRecords, nv - 1, r);
       },
       "vertex record"},
      {"infinite vertex distance",
       [&](Image& i) {
         VertexRecord r = i.Get<VertexRecord>(SectionId::kVertexRecords, 9);
         r.distance[1] = kInf;
         i.Set(SectionId::kVertexRecords, 9, r);
       },
       "vertex record 9"},
      {"negative vertex distance",
       [&](Image& i) {
         VertexRecord r = i.Get<VertexRecord>(SectionId::kVertexRecords, 9);
         r.distance[1] = -1e-3f;
         i.Set(SectionId::kVertexRecords, 9, r);
       },
       "vertex record 9"},
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
  for (const Case& c : cases) {
    Image image = Image::Parse(bytes);
    c.corrupt(image);
    const absl::Status status = Index::FromBytes(image.Layout()).status();
    EXPECT_EQ(status.code(), absl::StatusCode::kDataLoss) << c.name << ": " << status;
    EXPECT_THAT(status.message(), HasSubstr(c.message)) << c.name;
  }
}

TEST(IndexTest, StructuralCorruptionWithValidChecksumsIsDataLoss) {
  const std::string bytes = Serialize(MakeSphereIndex());
  struct Case {
    std::string name;
    std::function<std::string(Image&)> corrupt;
    std::string message;
  };
  const std::vector<Case> cases = {
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
      {"params disagree with counts",
       [](Image& i) {
         ++i.header.params.num_samples;
         return i.Layout();
       },
       "num_samples"},
  };
  for (const Case& c : cases) {
    Image image = Image::Parse(bytes);
    const std::string corrupt = c.corrupt(image);
    const absl::Status status = Index::FromBytes(corrupt).status();
    EXPECT_EQ(status.code(), absl::StatusCode::kDataLoss) << c.name << ": " << status;
    EXPECT_THAT(status.message(), HasSubstr(c.message)) << c.name;
  }
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

}  // namespace
}  // namespace geodex::index
