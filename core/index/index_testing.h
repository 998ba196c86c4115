#pragma once

// Test utilities of the index tests (index_test.cc, index_corruption_test.cc):
// a small but realistic index, byte-level comparisons, and an editable file
// image that lays sections out again with valid checksums, so that tests can
// forge files that are corrupt yet consistently checksummed.

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
#include "core/index/index.h"
#include "xxhash.h"

namespace geodex::index::testing_util {

inline constexpr float kInf = std::numeric_limits<float>::infinity();

inline float GreatCircle(const mesh::Vec3& a, const mesh::Vec3& b) {
  return static_cast<float>(std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)));
}

// A small but realistic index: the unit icosphere with one subdivision (42
// vertices, 80 faces) plus one unreferenced vertex at the centre; the 12
// icosahedron vertices are the samples and the 20 icosahedron faces the
// geodesic triangles; distances are great-circle distances; a real face BVH.
inline IndexData MakeSphereIndex() {
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
      r.distance[k] = GreatCircle(p, fine.position(d.samples[coarse.face(r.triangle)[k]]));
    }
    d.vertices.push_back(r);
  }
  VertexRecord none{};
  none.triangle = -1;
  for (int k = 0; k < 3; ++k) none.distance[k] = kInf;
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

inline std::string Serialize(const IndexData& d) {
  absl::StatusOr<std::string> bytes = SerializeIndex(d);
  EXPECT_TRUE(bytes.ok()) << bytes.status();
  return bytes.ok() ? *bytes : std::string();
}

template <typename T>
inline std::vector<T> ToVector(std::span<const T> s) {
  return std::vector<T>(s.begin(), s.end());
}

// Byte-wise equality for the on-disk records (which have no operator==).
template <typename T>
inline bool SameBytes(std::span<const T> a, const std::vector<T>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size_bytes()) == 0);
}

inline SectionEntry UnknownEntry(uint32_t id, uint32_t element_size) {
  SectionEntry e{};
  e.id = id;
  e.element_size = element_size;
  return e;
}

inline void ExpectSameData(const Index& index, const IndexData& d) {
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

inline absl::StatusCode CodeOf(const std::string& bytes) {
  return Index::FromBytes(bytes).status().code();
}

}  // namespace geodex::index::testing_util
