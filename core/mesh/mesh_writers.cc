// Mesh writers (mesh_io.h): ASCII OBJ, binary little-endian PLY, STL and GLB,
// written atomically (core/common/file_util.h).

#include <algorithm>
#include <bit>
#include <cstring>
#include <limits>
#include <string>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "core/common/file_util.h"
#include "core/mesh/mesh_io.h"

namespace geodex::mesh {
namespace {

template <typename T>
void AppendLittleEndian(std::string* out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  if constexpr (std::endian::native == std::endian::big) std::reverse(bytes, bytes + sizeof(T));
  out->append(bytes, sizeof(T));
}

Vec3 UnitNormal(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = (b - a).cross(c - a);
  const double length = n.norm();
  return length > 0 ? Vec3(n / length) : Vec3::Zero();
}

}  // namespace

absl::Status WriteObj(const Mesh& mesh, const std::string& path) {
  std::string out;
  for (const Vec3& p : mesh.positions()) {
    absl::StrAppendFormat(&out, "v %.17g %.17g %.17g\n", p.x(), p.y(), p.z());
  }
  for (const Triangle& t : mesh.faces()) {
    absl::StrAppendFormat(&out, "f %d %d %d\n", t[0] + 1, t[1] + 1, t[2] + 1);
  }
  return AtomicWriteFile(path, out);
}

absl::Status WritePly(const Mesh& mesh, const std::string& path) {
  std::string out = absl::StrFormat(
      "ply\n"
      "format binary_little_endian 1.0\n"
      "comment written by geodex\n"
      "element vertex %d\n"
      "property double x\n"
      "property double y\n"
      "property double z\n"
      "element face %d\n"
      "property list uchar int vertex_indices\n"
      "end_header\n",
      mesh.num_vertices(), mesh.num_faces());
  out.reserve(out.size() + 24 * mesh.num_vertices() + 13 * mesh.num_faces());
  for (const Vec3& p : mesh.positions()) {
    for (int i = 0; i < 3; ++i) AppendLittleEndian<double>(&out, p[i]);
  }
  for (const Triangle& t : mesh.faces()) {
    AppendLittleEndian<uint8_t>(&out, 3);
    for (int i = 0; i < 3; ++i) AppendLittleEndian<int32_t>(&out, t[i]);
  }
  return AtomicWriteFile(path, out);
}

std::string StlBytes(const Mesh& mesh, bool binary) {
  std::string out;
  if (binary) {
    // The free header must not begin with "solid", which marks ASCII STL.
    std::string header = "binary STL written by geodex";
    header.resize(80, ' ');
    out = header;
    out.reserve(84 + 50 * static_cast<size_t>(mesh.num_faces()));
    AppendLittleEndian<uint32_t>(&out, static_cast<uint32_t>(mesh.num_faces()));
    for (const Triangle& t : mesh.faces()) {
      const Vec3 n = UnitNormal(mesh.position(t[0]), mesh.position(t[1]), mesh.position(t[2]));
      for (int i = 0; i < 3; ++i) AppendLittleEndian<float>(&out, static_cast<float>(n[i]));
      for (int32_t v : t) {
        for (int i = 0; i < 3; ++i) {
          AppendLittleEndian<float>(&out, static_cast<float>(mesh.position(v)[i]));
        }
      }
      AppendLittleEndian<uint16_t>(&out, 0);
    }
    return out;
  }
  out = "solid geodex\n";
  for (const Triangle& t : mesh.faces()) {
    const Vec3 n = UnitNormal(mesh.position(t[0]), mesh.position(t[1]), mesh.position(t[2]));
    absl::StrAppendFormat(&out, "facet normal %.9g %.9g %.9g\n  outer loop\n", n.x(), n.y(), n.z());
    for (int32_t v : t) {
      const Vec3& p = mesh.position(v);
      absl::StrAppendFormat(&out, "    vertex %.17g %.17g %.17g\n", p.x(), p.y(), p.z());
    }
    out += "  endloop\nendfacet\n";
  }
  out += "endsolid geodex\n";
  return out;
}

std::string GlbBytes(const Mesh& mesh) {
  // BIN: float32 positions, then uint32 indices (both 4-byte aligned).
  std::string bin;
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::max());
  Eigen::Vector3f hi = -lo;
  for (const Vec3& p : mesh.positions()) {
    const Eigen::Vector3f f = p.cast<float>();
    lo = lo.cwiseMin(f);
    hi = hi.cwiseMax(f);
    for (int i = 0; i < 3; ++i) AppendLittleEndian<float>(&bin, f[i]);
  }
  const size_t positions_bytes = bin.size();
  for (const Triangle& t : mesh.faces()) {
    for (int32_t v : t) AppendLittleEndian<uint32_t>(&bin, static_cast<uint32_t>(v));
  }
  const size_t indices_bytes = bin.size() - positions_bytes;
  // The accessor's bounds are required for POSITION; printed to round-trip.
  std::string json = absl::StrFormat(
      R"({"asset":{"version":"2.0","generator":"geodex"},"scene":0,"scenes":[{"nodes":[0]}],)"
      R"("nodes":[{"mesh":0}],"meshes":[{"primitives":[{"attributes":{"POSITION":0},)"
      R"("indices":1,"mode":4}]}],"buffers":[{"byteLength":%d}],"bufferViews":[)"
      R"({"buffer":0,"byteOffset":0,"byteLength":%d,"target":34962},)"
      R"({"buffer":0,"byteOffset":%d,"byteLength":%d,"target":34963}],"accessors":[)"
      R"({"bufferView":0,"componentType":5126,"count":%d,"type":"VEC3",)"
      R"("min":[%.9g,%.9g,%.9g],"max":[%.9g,%.9g,%.9g]},)"
      R"({"bufferView":1,"componentType":5125,"count":%d,"type":"SCALAR"}]})",
      bin.size(), positions_bytes, positions_bytes, indices_bytes, mesh.num_vertices(), lo.x(),
      lo.y(), lo.z(), hi.x(), hi.y(), hi.z(), 3 * static_cast<int64_t>(mesh.num_faces()));
  json.resize((json.size() + 3) / 4 * 4, ' ');
  bin.resize((bin.size() + 3) / 4 * 4, '\0');
  std::string out;
  AppendLittleEndian<uint32_t>(&out, 0x46546C67);  // "glTF"
  AppendLittleEndian<uint32_t>(&out, 2);
  AppendLittleEndian<uint32_t>(&out, static_cast<uint32_t>(12 + 8 + json.size() + 8 + bin.size()));
  AppendLittleEndian<uint32_t>(&out, static_cast<uint32_t>(json.size()));
  AppendLittleEndian<uint32_t>(&out, 0x4E4F534A);  // "JSON"
  out += json;
  AppendLittleEndian<uint32_t>(&out, static_cast<uint32_t>(bin.size()));
  AppendLittleEndian<uint32_t>(&out, 0x004E4942);  // "BIN\0"
  out += bin;
  return out;
}

absl::Status WriteStl(const Mesh& mesh, const std::string& path, bool binary) {
  return AtomicWriteFile(path, StlBytes(mesh, binary));
}

absl::Status WriteGlb(const Mesh& mesh, const std::string& path) {
  return AtomicWriteFile(path, GlbBytes(mesh));
}

}  // namespace geodex::mesh
