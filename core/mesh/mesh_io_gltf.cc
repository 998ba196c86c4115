// glTF 2.0 reader (mesh_io.h), over tinygltf (Debian's libtinygltf-dev): it
// parses the JSON, the GLB container and the buffers (data: URIs, the GLB
// chunk, external files); this file walks the default scene and reads the
// triangles in the order mesh_io.h documents. tinygltf keeps everything the
// file says in its own structures, so the file's order is ours to choose
// (assimp, the other Debian option, reorders and merges primitives).

#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <exception>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "Eigen/Geometry"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "core/common/file_util.h"
#include "core/common/status_macros.h"
#include "core/mesh/mesh_io.h"
#include "core/mesh/mesh_weld.h"
#include "tiny_gltf.h"

namespace geodex::mesh {
namespace {

constexpr uint32_t kGlbMagic = 0x46546C67;      // "glTF"
constexpr uint32_t kGlbJsonChunk = 0x4E4F534A;  // "JSON"
constexpr uint32_t kGlbBinChunk = 0x004E4942;   // "BIN\0"

uint32_t LittleEndianU32(const char* p) {
  const auto* b = reinterpret_cast<const unsigned char*>(p);
  return static_cast<uint32_t>(b[0]) | static_cast<uint32_t>(b[1]) << 8 |
         static_cast<uint32_t>(b[2]) << 16 | static_cast<uint32_t>(b[3]) << 24;
}

// Checks the GLB container (header, JSON chunk, optional BIN chunk) against
// the file's size before tinygltf reads it, with messages that say what is
// wrong: tinygltf 2.7.0 lets a BIN chunk's payload end up to 8 bytes past
// the declared length.
absl::Status CheckGlbContainer(std::string_view bytes, const std::string& name) {
  auto error = [&](std::string what) {
    return absl::InvalidArgumentError(absl::StrCat(name, ": GLB: ", what));
  };
  if (bytes.size() < 20) return error("shorter than its 12-byte header and one chunk header");
  const uint32_t version = LittleEndianU32(bytes.data() + 4);
  const uint64_t length = LittleEndianU32(bytes.data() + 8);
  if (version != 2) return error(absl::StrFormat("version %d, not 2", version));
  if (length != bytes.size()) {
    return error(absl::StrFormat("the header says %d bytes but the file has %d%s", length,
                                 bytes.size(), length > bytes.size() ? " (truncated?)" : ""));
  }
  const uint64_t json_length = LittleEndianU32(bytes.data() + 12);
  if (LittleEndianU32(bytes.data() + 16) != kGlbJsonChunk) {
    return error("the first chunk is not JSON");
  }
  if (json_length == 0 || 20 + json_length > length) {
    return error(absl::StrFormat("the JSON chunk's %d bytes do not fit in the file's %d",
                                 json_length, length));
  }
  const uint64_t bin_at = 20 + json_length;
  if (bin_at == length) return absl::OkStatus();
  if (bin_at + 8 > length) return error("a chunk header is cut short (truncated?)");
  const uint64_t bin_length = LittleEndianU32(bytes.data() + bin_at);
  if (LittleEndianU32(bytes.data() + bin_at + 4) != kGlbBinChunk) {
    return error("the second chunk is not BIN");
  }
  if (bin_at + 8 + bin_length > length) {
    return error(
        absl::StrFormat("the BIN chunk's %d bytes run past the end of the file (%d "
                        "bytes; truncated?)",
                        bin_length, length));
  }
  if (bin_length < 4 || bin_length % 4 != 0) {
    return error("the BIN chunk is not padded to 4 bytes");
  }
  return absl::OkStatus();
}

// File access for tinygltf: external buffers and images under the glTF
// file's directory through the project's reader, no path expansion (the
// library's default expands with wordexp), nothing at all for in-memory
// contents, and no writes.
struct FileAccess {
  bool allowed = false;
};

bool FileExists(const std::string& path, void* user) {
  if (!static_cast<const FileAccess*>(user)->allowed) return false;
  struct stat info;
  return ::stat(path.c_str(), &info) == 0 && S_ISREG(info.st_mode);
}

std::string ExpandFilePath(const std::string& path, void*) { return path; }

bool ReadFile(std::vector<unsigned char>* out, std::string* err, const std::string& path,
              void* user) {
  if (!static_cast<const FileAccess*>(user)->allowed) {
    if (err != nullptr) *err += "external files are not read here: " + path + "\n";
    return false;
  }
  absl::StatusOr<std::string> contents = ReadWholeFile(path);
  if (!contents.ok()) {
    if (err != nullptr) *err += std::string(contents.status().message()) + "\n";
    return false;
  }
  out->assign(contents->begin(), contents->end());
  return true;
}

bool RefuseWrite(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
  if (err != nullptr) *err += "geodex does not write glTF files\n";
  return false;
}

// Images are not needed: keep their bytes undecoded.
bool SkipImage(tinygltf::Image*, const int, std::string*, std::string*, int, int,
               const unsigned char*, int, void*) {
  return true;
}

std::string ModeName(int mode) {
  switch (mode) {
    case TINYGLTF_MODE_POINTS:
      return "POINTS";
    case TINYGLTF_MODE_LINE:
      return "LINES";
    case TINYGLTF_MODE_LINE_LOOP:
      return "LINE_LOOP";
    case TINYGLTF_MODE_LINE_STRIP:
      return "LINE_STRIP";
    case TINYGLTF_MODE_TRIANGLE_STRIP:
      return "TRIANGLE_STRIP";
    case TINYGLTF_MODE_TRIANGLE_FAN:
      return "TRIANGLE_FAN";
    default:
      return absl::StrCat("mode ", mode);
  }
}

// Reads the triangles of the default scene (mesh_io.h) into corners.
class SceneReader {
 public:
  SceneReader(const tinygltf::Model& model, const std::string& name)
      : model_(model), name_(name), visited_(model.nodes.size(), 0) {}

  absl::Status Read(std::vector<Vec3>* corners) {
    corners_ = corners;
    for (const std::string& extension : model_.extensionsRequired) {
      if (extension == "KHR_draco_mesh_compression" || extension == "EXT_meshopt_compression") {
        return Error(absl::StrCat("the file requires ", extension,
                                  ", which geodex does not decode (export it uncompressed)"));
      }
    }
    const Eigen::Matrix4d identity = Eigen::Matrix4d::Identity();
    if (model_.scenes.empty()) {
      for (size_t m = 0; m < model_.meshes.size(); ++m) {
        GEODEX_RETURN_IF_ERROR(ReadMesh(static_cast<int>(m), identity));
      }
      return absl::OkStatus();
    }
    const int scene = model_.defaultScene >= 0 ? model_.defaultScene : 0;
    if (scene >= static_cast<int>(model_.scenes.size())) {
      return Error(absl::StrFormat("the default scene %d does not exist (%d scenes)", scene,
                                   model_.scenes.size()));
    }
    for (int node : model_.scenes[scene].nodes) {
      GEODEX_RETURN_IF_ERROR(ReadNode(node, identity));
    }
    return absl::OkStatus();
  }

 private:
  absl::Status Error(std::string message) const {
    return absl::InvalidArgumentError(absl::StrCat(name_, ": glTF: ", message));
  }

  absl::StatusOr<Eigen::Matrix4d> LocalMatrix(const tinygltf::Node& node, int index) const {
    Eigen::Matrix4d local = Eigen::Matrix4d::Identity();
    if (!node.matrix.empty()) {
      if (node.matrix.size() != 16) {
        return Error(
            absl::StrFormat("node %d: matrix of %d numbers, not 16", index, node.matrix.size()));
      }
      for (int i = 0; i < 16; ++i) local(i % 4, i / 4) = node.matrix[i];  // column-major
    } else {
      auto check = [&](const std::vector<double>& v, size_t n, const char* what) {
        return v.empty() || v.size() == n
                   ? absl::OkStatus()
                   : Error(absl::StrFormat("node %d: %s of %d numbers, not %d", index, what,
                                           v.size(), n));
      };
      GEODEX_RETURN_IF_ERROR(check(node.translation, 3, "translation"));
      GEODEX_RETURN_IF_ERROR(check(node.rotation, 4, "rotation"));
      GEODEX_RETURN_IF_ERROR(check(node.scale, 3, "scale"));
      Eigen::Affine3d trs = Eigen::Affine3d::Identity();
      if (!node.translation.empty()) {
        trs.translate(
            Eigen::Vector3d(node.translation[0], node.translation[1], node.translation[2]));
      }
      if (!node.rotation.empty()) {
        // glTF quaternions are (x, y, z, w) and unit; normalised here so
        // that rounding in the file does not scale the mesh.
        Eigen::Quaterniond q(node.rotation[3], node.rotation[0], node.rotation[1],
                             node.rotation[2]);
        if (!(q.norm() > 0) || !std::isfinite(q.norm())) {
          return Error(absl::StrFormat("node %d: rotation is not a quaternion", index));
        }
        trs.rotate(q.normalized());
      }
      if (!node.scale.empty()) {
        trs.scale(Eigen::Vector3d(node.scale[0], node.scale[1], node.scale[2]));
      }
      local = trs.matrix();
    }
    if (!local.allFinite()) {
      return Error(absl::StrFormat("node %d: its transform is not finite", index));
    }
    return local;
  }

  // The node and its descendants, depth first (a node's mesh, then its
  // children in order), without recursion: a chain of nodes is as deep as
  // the file makes it.
  absl::Status ReadNode(int root, const Eigen::Matrix4d& parent) {
    struct Pending {
      int node;
      Eigen::Matrix4d parent;
    };
    std::vector<Pending> stack = {{root, parent}};
    while (!stack.empty()) {
      const Pending next = stack.back();
      stack.pop_back();
      const int index = next.node;
      if (index < 0 || index >= static_cast<int>(model_.nodes.size())) {
        return Error(
            absl::StrFormat("node %d does not exist (%d nodes)", index, model_.nodes.size()));
      }
      // Nodes form disjoint trees: a node reached twice is in a cycle or has
      // two parents (and reading it again could multiply the work without
      // bound).
      if (visited_[index]) {
        return Error(absl::StrFormat(
            "node %d is reached twice from the scene (a cycle, or a node with two parents)",
            index));
      }
      visited_[index] = 1;
      const tinygltf::Node& node = model_.nodes[index];
      GEODEX_ASSIGN_OR_RETURN(const Eigen::Matrix4d local, LocalMatrix(node, index));
      const Eigen::Matrix4d world = next.parent * local;
      if (node.mesh >= 0) GEODEX_RETURN_IF_ERROR(ReadMesh(node.mesh, world));
      for (auto child = node.children.rbegin(); child != node.children.rend(); ++child) {
        stack.push_back({*child, world});
      }
    }
    return absl::OkStatus();
  }

  absl::Status ReadMesh(int index, const Eigen::Matrix4d& world) {
    if (index >= static_cast<int>(model_.meshes.size())) {
      return Error(
          absl::StrFormat("mesh %d does not exist (%d meshes)", index, model_.meshes.size()));
    }
    const tinygltf::Mesh& mesh = model_.meshes[index];
    for (size_t p = 0; p < mesh.primitives.size(); ++p) {
      GEODEX_RETURN_IF_ERROR(ReadPrimitive(index, static_cast<int>(p), world));
    }
    return absl::OkStatus();
  }

  // The values of accessor `index` as doubles, `components` per element,
  // sparse substitutions applied. `what` names it in errors.
  absl::StatusOr<std::vector<double>> AccessorValues(int index, int type,
                                                     const std::vector<int>& component_types,
                                                     const std::string& what) const {
    if (index < 0 || index >= static_cast<int>(model_.accessors.size())) {
      return Error(absl::StrFormat("%s: accessor %d does not exist (%d accessors)", what, index,
                                   model_.accessors.size()));
    }
    const tinygltf::Accessor& accessor = model_.accessors[index];
    const std::string where = absl::StrFormat("%s (accessor %d)", what, index);
    if (accessor.type != type) {
      return Error(absl::StrFormat("%s: type %d, expected %s", where, accessor.type,
                                   type == TINYGLTF_TYPE_VEC3 ? "VEC3" : "SCALAR"));
    }
    if (std::find(component_types.begin(), component_types.end(), accessor.componentType) ==
        component_types.end()) {
      return Error(
          absl::StrFormat("%s: component type %d is not %s", where, accessor.componentType,
                          type == TINYGLTF_TYPE_VEC3
                              ? "FLOAT (quantized positions, KHR_mesh_quantization, are not read)"
                              : "an unsigned byte, short or int"));
    }
    if (accessor.bufferView < 0) {
      return Error(absl::StrFormat(
          "%s: no bufferView (accessors of zeros, sparse or not, are not read)", where));
    }
    const int components = type == TINYGLTF_TYPE_VEC3 ? 3 : 1;
    const size_t count = accessor.count;
    std::vector<double> values;
    GEODEX_RETURN_IF_ERROR(ReadElements(accessor.bufferView, accessor.byteOffset, count,
                                        accessor.componentType, components, /*packed=*/false, where,
                                        &values));
    if (accessor.sparse.isSparse) {
      const auto& sparse = accessor.sparse;
      if (sparse.count < 0 || static_cast<size_t>(sparse.count) > count) {
        return Error(
            absl::StrFormat("%s: sparse count %d out of [0, %d]", where, sparse.count, count));
      }
      const int index_type = sparse.indices.componentType;
      if (index_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
          index_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
          index_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT) {
        return Error(absl::StrFormat("%s: sparse index component type %d", where, index_type));
      }
      std::vector<double> indices, substitutes;
      GEODEX_RETURN_IF_ERROR(ReadElements(sparse.indices.bufferView, sparse.indices.byteOffset,
                                          sparse.count, index_type, 1, /*packed=*/true,
                                          where + " sparse indices", &indices));
      GEODEX_RETURN_IF_ERROR(ReadElements(sparse.values.bufferView, sparse.values.byteOffset,
                                          sparse.count, accessor.componentType, components,
                                          /*packed=*/true, where + " sparse values", &substitutes));
      for (int i = 0; i < sparse.count; ++i) {
        const double at = indices[i];
        if (at >= static_cast<double>(count)) {
          return Error(absl::StrFormat("%s: sparse index %d out of range [0, %d)", where,
                                       static_cast<uint64_t>(at), count));
        }
        for (int c = 0; c < components; ++c) {
          values[static_cast<size_t>(at) * components + c] = substitutes[i * components + c];
        }
      }
    }
    return values;
  }

  // The little-endian component at `p`, of `component_type`; nullopt for a
  // type no accessor geodex reads has.
  static std::optional<double> DecodeComponent(const unsigned char* p, int component_type) {
    switch (component_type) {
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
        return p[0];
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
        return static_cast<uint16_t>(p[0] | p[1] << 8);
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
        return LittleEndianU32(reinterpret_cast<const char*>(p));
      case TINYGLTF_COMPONENT_TYPE_FLOAT: {
        const uint32_t bits = LittleEndianU32(reinterpret_cast<const char*>(p));
        float f;
        std::memcpy(&f, &bits, sizeof(f));
        return f;
      }
      default:
        return std::nullopt;
    }
  }

  // `count` elements of `components` components of `component_type` from
  // buffer view `view` at `offset`, with the view's stride (none when
  // `packed`, as sparse arrays are), bounds checked.
  absl::Status ReadElements(int view, size_t offset, size_t count, int component_type,
                            int components, bool packed, const std::string& where,
                            std::vector<double>* out) const {
    if (view < 0 || view >= static_cast<int>(model_.bufferViews.size())) {
      return Error(absl::StrFormat("%s: bufferView %d does not exist (%d bufferViews)", where, view,
                                   model_.bufferViews.size()));
    }
    const tinygltf::BufferView& bv = model_.bufferViews[view];
    if (bv.extensions.count("EXT_meshopt_compression") > 0) {
      return Error(absl::StrFormat(
          "%s: bufferView %d is compressed (EXT_meshopt_compression), which geodex does not "
          "decode",
          where, view));
    }
    if (bv.buffer < 0 || bv.buffer >= static_cast<int>(model_.buffers.size())) {
      return Error(absl::StrFormat("%s: bufferView %d: buffer %d does not exist (%d buffers)",
                                   where, view, bv.buffer, model_.buffers.size()));
    }
    const std::vector<unsigned char>& buffer = model_.buffers[bv.buffer].data;
    const uint64_t component_bytes = tinygltf::GetComponentSizeInBytes(component_type);
    const uint64_t element_bytes = component_bytes * components;
    const uint64_t stride = packed || bv.byteStride == 0 ? element_bytes : bv.byteStride;
    if (stride < element_bytes) {
      return Error(
          absl::StrFormat("%s: bufferView %d: stride %d is shorter than an element (%d "
                          "bytes)",
                          where, view, stride, element_bytes));
    }
    // Sizes come from the file: compare in 64 bits and without overflow.
    const uint64_t limit = uint64_t{1} << 40;
    if (bv.byteOffset > limit || bv.byteLength > limit || offset > limit || count > limit) {
      return Error(absl::StrFormat("%s: offsets or counts beyond any buffer", where));
    }
    if (bv.byteOffset + bv.byteLength > buffer.size()) {
      return Error(absl::StrFormat(
          "%s: bufferView %d (bytes %d to %d) runs past the end of buffer %d (%d bytes; missing "
          "or short .bin file?)",
          where, view, bv.byteOffset, bv.byteOffset + bv.byteLength, bv.buffer, buffer.size()));
    }
    if (count > 0 && offset + stride * (count - 1) + element_bytes > bv.byteLength) {
      return Error(absl::StrFormat(
          "%s: %d elements of %d bytes from byte %d, stride %d, run past the end of bufferView "
          "%d (%d bytes)",
          where, count, element_bytes, offset, stride, view, bv.byteLength));
    }
    if (offset % component_bytes != 0 || (bv.byteOffset + offset) % component_bytes != 0) {
      return Error(absl::StrFormat("%s: byte offset %d is not aligned to its components", where,
                                   bv.byteOffset + offset));
    }
    out->resize(count * components);
    const unsigned char* base = buffer.data() + bv.byteOffset + offset;
    for (size_t e = 0; e < count; ++e) {
      const unsigned char* element = base + stride * e;
      for (int c = 0; c < components; ++c) {
        const std::optional<double> value =
            DecodeComponent(element + component_bytes * c, component_type);
        if (!value) return Error(absl::StrFormat("%s: component type %d", where, component_type));
        (*out)[e * components + c] = *value;
      }
    }
    return absl::OkStatus();
  }

  absl::Status ReadPrimitive(int mesh_index, int primitive_index, const Eigen::Matrix4d& world) {
    const tinygltf::Primitive& primitive = model_.meshes[mesh_index].primitives[primitive_index];
    const std::string& mesh_name = model_.meshes[mesh_index].name;
    const std::string what = absl::StrFormat(
        "mesh %d%s primitive %d", mesh_index,
        mesh_name.empty() ? "" : absl::StrCat(" ('", mesh_name, "')"), primitive_index);
    const int mode = primitive.mode < 0 ? TINYGLTF_MODE_TRIANGLES : primitive.mode;
    if (mode != TINYGLTF_MODE_TRIANGLES) {
      return Error(absl::StrFormat(
          "%s: a primitive of %s; geodex reads TRIANGLES primitives (a surface of separate "
          "triangles)",
          what, ModeName(mode)));
    }
    if (primitive.extensions.count("KHR_draco_mesh_compression") > 0) {
      return Error(absl::StrCat(what,
                                ": compressed with KHR_draco_mesh_compression, which geodex does "
                                "not decode (export it uncompressed)"));
    }
    const auto position = primitive.attributes.find("POSITION");
    if (position == primitive.attributes.end()) {
      return Error(absl::StrCat(what, ": no POSITION attribute"));
    }
    GEODEX_ASSIGN_OR_RETURN(const std::vector<double> xyz,
                            AccessorValues(position->second, TINYGLTF_TYPE_VEC3,
                                           {TINYGLTF_COMPONENT_TYPE_FLOAT}, what + " POSITION"));
    const size_t num_positions = xyz.size() / 3;
    std::vector<double> indices;
    if (primitive.indices >= 0) {
      GEODEX_ASSIGN_OR_RETURN(indices, AccessorValues(primitive.indices, TINYGLTF_TYPE_SCALAR,
                                                      {TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE,
                                                       TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
                                                       TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT},
                                                      what + " indices"));
    }
    const size_t num_corners = primitive.indices >= 0 ? indices.size() : num_positions;
    if (num_corners % 3 != 0) {
      return Error(absl::StrFormat("%s: %d %s, not a multiple of 3 (TRIANGLES)", what, num_corners,
                                   primitive.indices >= 0 ? "indices" : "positions"));
    }
    if (corners_->size() + num_corners >=
        static_cast<size_t>(std::numeric_limits<int32_t>::max())) {
      return Error("more triangles than a mesh holds");
    }
    const size_t first_triangle = corners_->size() / 3;
    for (size_t i = 0; i < num_corners; ++i) {
      const size_t v = primitive.indices >= 0 ? static_cast<size_t>(indices[i]) : i;
      if (v >= num_positions) {
        return Error(absl::StrFormat("%s: index %d of triangle %d is %d, out of range [0, %d)",
                                     what, i, i / 3, v, num_positions));
      }
      const Eigen::Vector4d local(xyz[3 * v], xyz[3 * v + 1], xyz[3 * v + 2], 1.0);
      const Vec3 p = (world * local).head<3>();
      if (!p.allFinite()) {
        return Error(absl::StrFormat(
            "%s: vertex %d (corner %d of triangle %d, face %d of the scene) has a non-finite "
            "position (%g, %g, %g)",
            what, v, i % 3, i / 3, first_triangle + i / 3, p.x(), p.y(), p.z()));
      }
      corners_->push_back(p);
    }
    return absl::OkStatus();
  }

  const tinygltf::Model& model_;
  const std::string& name_;
  std::vector<uint8_t> visited_;
  std::vector<Vec3>* corners_ = nullptr;
};

}  // namespace

absl::StatusOr<RawMesh> ParseGltfTriangles(std::string_view contents, const std::string& name,
                                           const std::string& base_dir,
                                           const ReadOptions& options) {
  GEODEX_RETURN_IF_ERROR(ValidateWeldTolerance(options.weld_tolerance));
  const bool binary = contents.size() >= 4 && LittleEndianU32(contents.data()) == kGlbMagic;
  if (binary) GEODEX_RETURN_IF_ERROR(CheckGlbContainer(contents, name));
  if (contents.size() > std::numeric_limits<unsigned int>::max()) {
    return absl::InvalidArgumentError(absl::StrCat(name,
                                                   ": glTF files of 4 GiB or more are not "
                                                   "read"));
  }
  FileAccess access{.allowed = !base_dir.empty()};
  tinygltf::TinyGLTF loader;
  loader.SetFsCallbacks({&FileExists, &ExpandFilePath, &ReadFile, &RefuseWrite, &access});
  loader.SetImageLoader(&SkipImage, nullptr);
  tinygltf::Model model;
  std::string err, warn;
  bool loaded = false;
  // tinygltf and its JSON library throw on some malformed input (and on
  // allocation failure): no exception leaves this function.
  try {
    loaded = binary
                 ? loader.LoadBinaryFromMemory(
                       &model, &err, &warn, reinterpret_cast<const unsigned char*>(contents.data()),
                       static_cast<unsigned int>(contents.size()), base_dir)
                 : loader.LoadASCIIFromString(&model, &err, &warn, contents.data(),
                                              static_cast<unsigned int>(contents.size()), base_dir);
  } catch (const std::exception& e) {
    err = e.what();
    loaded = false;
  }
  if (!loaded) {
    while (!err.empty() && (err.back() == '\n' || err.back() == ' ')) err.pop_back();
    std::replace(err.begin(), err.end(), '\n', ';');
    return absl::InvalidArgumentError(absl::StrFormat("%s: not a readable %s: %s", name,
                                                      binary ? "GLB file" : "glTF file",
                                                      err.empty() ? "(no reason given)" : err));
  }
  std::vector<Vec3> corners;
  SceneReader reader(model, name);
  GEODEX_RETURN_IF_ERROR(reader.Read(&corners));
  if (corners.empty()) {
    return absl::InvalidArgumentError(
        absl::StrCat(name, ": glTF: the default scene has no triangles"));
  }
  return io_internal::WeldCorners(corners, options, name);
}

}  // namespace geodex::mesh
