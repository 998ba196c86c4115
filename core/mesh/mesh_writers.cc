// Mesh writers (mesh_io.h): ASCII OBJ and binary little-endian PLY, written
// atomically (core/common/file_util.h).

#include <algorithm>
#include <bit>
#include <cstring>
#include <string>

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

}  // namespace geodex::mesh
