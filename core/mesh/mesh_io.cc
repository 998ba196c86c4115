// LoadMeshFile: picks the reader by extension (mesh_io_obj.cc, mesh_io_ply.cc,
// mesh_io_off.cc, mesh_io_stl.cc, mesh_io_gltf.cc).

#include "core/mesh/mesh_io.h"

#include <string>
#include <string_view>
#include <utility>

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/string_view.h"
#include "core/common/file_util.h"
#include "core/common/status_macros.h"

namespace geodex::mesh {
namespace {

std::string Extension(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  const size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  const std::string_view extension = std::string_view(path).substr(dot + 1);
  return absl::AsciiStrToLower(absl::string_view(extension.data(), extension.size()));
}

}  // namespace

absl::StatusOr<RawMesh> LoadRawMeshFile(const std::string& path, const ReadOptions& options) {
  const std::string extension = Extension(path);
  absl::StatusOr<RawMesh> (*parse)(std::string_view, const std::string&) = nullptr;
  if (extension == "obj") {
    parse = &ParseObjTriangles;
  } else if (extension == "ply") {
    parse = &ParsePlyTriangles;
  } else if (extension == "off") {
    parse = &ParseOffTriangles;
  } else if (extension != "stl" && extension != "gltf" && extension != "glb") {
    return absl::InvalidArgumentError(
        absl::StrFormat("%s: unknown mesh file extension '%s' (expected .obj, .ply, .off, .stl, "
                        ".gltf or .glb)",
                        path, extension));
  }
  GEODEX_RETURN_IF_ERROR(ValidateWeldTolerance(options.weld_tolerance));
  if (parse != nullptr && options.weld_tolerance != 0) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "%s: a weld tolerance applies to STL and glTF files, whose corners name no vertices; "
        ".%s files name theirs",
        path, extension));
  }
  GEODEX_ASSIGN_OR_RETURN(const std::string contents, ReadWholeFile(path));
  if (parse != nullptr) return parse(contents, path);
  if (extension == "stl") return ParseStlTriangles(contents, path, options);
  // External buffers are named relative to the glTF file.
  const size_t slash = path.find_last_of('/');
  const std::string base_dir = slash == std::string::npos ? "." : path.substr(0, slash + 1);
  return ParseGltfTriangles(contents, path, base_dir, options);
}

absl::StatusOr<LoadedMesh> CreateLoadedMesh(RawMesh raw) {
  absl::StatusOr<Mesh> mesh =
      Mesh::Create(std::move(raw.positions), std::move(raw.triangles), raw.name);
  if (!mesh.ok()) {
    if (raw.polygons && mesh.status().code() == absl::StatusCode::kInvalidArgument) {
      return absl::InvalidArgumentError(absl::StrCat(
          mesh.status().message(),
          " [face ids count triangles after fan triangulation of the file's polygons]"));
    }
    return mesh.status();
  }
  return LoadedMesh{*std::move(mesh), std::move(raw.input_face)};
}

absl::StatusOr<LoadedMesh> LoadMeshFile(const std::string& path, const ReadOptions& options) {
  GEODEX_ASSIGN_OR_RETURN(RawMesh raw, LoadRawMeshFile(path, options));
  return CreateLoadedMesh(std::move(raw));
}

absl::StatusOr<LoadedMesh> ParseObj(std::string_view contents, const std::string& name) {
  GEODEX_ASSIGN_OR_RETURN(RawMesh raw, ParseObjTriangles(contents, name));
  return CreateLoadedMesh(std::move(raw));
}

absl::StatusOr<LoadedMesh> ParsePly(std::string_view contents, const std::string& name) {
  GEODEX_ASSIGN_OR_RETURN(RawMesh raw, ParsePlyTriangles(contents, name));
  return CreateLoadedMesh(std::move(raw));
}

absl::StatusOr<LoadedMesh> ParseOff(std::string_view contents, const std::string& name) {
  GEODEX_ASSIGN_OR_RETURN(RawMesh raw, ParseOffTriangles(contents, name));
  return CreateLoadedMesh(std::move(raw));
}

absl::StatusOr<Mesh> LoadMesh(const std::string& path, const ReadOptions& options) {
  GEODEX_ASSIGN_OR_RETURN(LoadedMesh loaded, LoadMeshFile(path, options));
  return std::move(loaded.mesh);
}

}  // namespace geodex::mesh
