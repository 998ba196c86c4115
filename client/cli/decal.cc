#include "client/cli/decal.h"

#include <cmath>
#include <cstring>
#include <limits>
#include <utility>

#include "absl/strings/escaping.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"

namespace geodex::client::cli {
namespace {

constexpr char kMaterialName[] = "geodex_decal";

// Keeps the id lists readable in a text editor.
constexpr size_t kMaxCommentLineLength = 100;

absl::Status CheckFileName(const std::string& name, const char* what) {
  if (name.empty()) return absl::InvalidArgumentError(absl::StrCat("the ", what, " is empty"));
  for (const char c : name) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte <= ' ' || byte == 0x7f || c == '#') {
      return absl::InvalidArgumentError(
          absl::StrCat("the ", what, " \"", absl::CEscape(name),
                       "\" has white space, a control character or '#', which OBJ and MTL "
                       "readers cannot take in a file name"));
    }
  }
  return absl::OkStatus();
}

// `ids` (ascending) as comment lines "<prefix> a b-c ...", a run of
// consecutive ids as "first-last".
void AppendIdRanges(const char* prefix, const std::vector<int32_t>& ids, std::string* out) {
  std::string line = prefix;
  for (size_t i = 0; i < ids.size();) {
    size_t last = i;
    while (last + 1 < ids.size() && ids[last + 1] == ids[last] + 1) ++last;
    const std::string run =
        last == i ? absl::StrCat(" ", ids[i]) : absl::StrCat(" ", ids[i], "-", ids[last]);
    if (line.size() + run.size() > kMaxCommentLineLength && line.size() > std::strlen(prefix)) {
      absl::StrAppend(out, line, "\n");
      line = prefix;
    }
    line += run;
    i = last + 1;
  }
  absl::StrAppend(out, line, "\n");
}

}  // namespace

absl::Status CheckDecalRadius(double radius) {
  if (std::isfinite(radius) && radius > 0) return absl::OkStatus();
  return absl::InvalidArgumentError(
      absl::StrCat("the decal radius must be finite and > 0, not ", radius));
}

absl::StatusOr<DecalPatch> FindDecalPatch(const Mesh& mesh, const ExpMap& map) {
  const size_t n = map.vertices.size();
  if (map.r.size() != n || map.theta.size() != n || map.u.size() != n || map.v.size() != n) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "the exponential map's arrays differ in length: %d vertices, %d r, %d theta, %d u, %d v", n,
        map.r.size(), map.theta.size(), map.u.size(), map.v.size()));
  }
  if (n == 0) {
    return absl::InvalidArgumentError(
        "the exponential map is empty: no mesh vertex lies within its radius");
  }
  if (map.version != 0 && mesh.version != 0 && map.version != mesh.version) {
    return absl::FailedPreconditionError(
        absl::StrFormat("the exponential map is of model version %d, the mesh of version %d",
                        map.version, mesh.version));
  }
  const size_t num_vertices = mesh.positions.size();
  if (num_vertices > static_cast<size_t>(std::numeric_limits<int32_t>::max()) ||
      mesh.faces.size() > static_cast<size_t>(std::numeric_limits<int32_t>::max())) {
    return absl::InvalidArgumentError("the mesh has more than 2^31 - 1 vertices or faces");
  }

  DecalPatch patch;
  patch.map_entry.assign(num_vertices, -1);
  for (size_t i = 0; i < n; ++i) {
    const int32_t vertex = map.vertices[i];
    if (vertex < 0) {
      return absl::InvalidArgumentError(
          absl::StrFormat("exponential map entry %d: negative vertex id %d", i, vertex));
    }
    if (static_cast<size_t>(vertex) >= num_vertices) {
      return absl::OutOfRangeError(absl::StrFormat(
          "exponential map entry %d: vertex %d of a mesh of %d vertices", i, vertex, num_vertices));
    }
    if (i > 0 && vertex <= map.vertices[i - 1]) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "exponential map entry %d: vertex %d after vertex %d (vertex ids must strictly ascend)",
          i, vertex, map.vertices[i - 1]));
    }
    if (!std::isfinite(map.r[i]) || !std::isfinite(map.theta[i]) || !std::isfinite(map.u[i]) ||
        !std::isfinite(map.v[i])) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "exponential map entry %d (vertex %d): r, theta, u, v = %g, %g, %g, %g are not all "
          "finite",
          i, vertex, map.r[i], map.theta[i], map.u[i], map.v[i]));
    }
    const Position& p = mesh.positions[vertex];
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "mesh vertex %d (in the exponential map) is at a non-finite position (%g, %g, %g)",
          vertex, p[0], p[1], p[2]));
    }
    patch.map_entry[vertex] = static_cast<int32_t>(i);
  }
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    bool covered = true;
    for (const uint32_t vertex : mesh.faces[f]) {
      if (vertex >= num_vertices) {
        return absl::OutOfRangeError(absl::StrFormat(
            "mesh face %d refers to vertex %d of a mesh of %d vertices", f, vertex, num_vertices));
      }
      covered = covered && patch.map_entry[vertex] >= 0;
    }
    if (covered) patch.faces.push_back(static_cast<int32_t>(f));
  }
  if (patch.faces.empty()) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "no mesh face has all three vertices in the exponential map (%d vertices); the radius "
        "is too small for the mesh's edge lengths",
        n));
  }
  return patch;
}

std::array<double, 2> DecalTextureCoordinates(double u, double v, double radius) {
  return {u / (2 * radius) + 0.5, v / (2 * radius) + 0.5};
}

absl::StatusOr<DecalFiles> DecalToObj(const Mesh& mesh, const ExpMap& map, double radius,
                                      const std::string& mtl_file_name,
                                      const std::string& texture_file_name) {
  if (absl::Status s = CheckDecalRadius(radius); !s.ok()) return s;
  if (absl::Status s = CheckFileName(mtl_file_name, "MTL file name"); !s.ok()) return s;
  if (absl::Status s = CheckFileName(texture_file_name, "texture file name"); !s.ok()) return s;
  absl::StatusOr<DecalPatch> patch = FindDecalPatch(mesh, map);
  if (!patch.ok()) return patch.status();

  // OBJ numbers vertices from 1; ascending mesh order keeps the file's vertex
  // list a subsequence of the mesh's, which the id comment then compresses.
  // 0 for a vertex no decal face uses; else first a mark, then its OBJ index.
  std::vector<int32_t> obj_index(mesh.positions.size(), 0);
  for (const int32_t f : patch->faces) {
    for (const uint32_t vertex : mesh.faces[f]) obj_index[vertex] = 1;
  }
  std::vector<int32_t> used_vertices;
  for (const int32_t vertex : map.vertices) {
    if (obj_index[vertex] == 0) continue;
    used_vertices.push_back(vertex);
    obj_index[vertex] = static_cast<int32_t>(used_vertices.size());
  }

  std::string obj = absl::StrFormat(
      "# geodex decal: the discrete exponential map of radius %.17g (model version %d)\n"
      "# %d of the mesh's %d vertices and %d of its %d faces; vt = (u, v) / (2 radius) + 0.5\n"
      "# The mesh id of each OBJ vertex and face in order (first-last: a run of ids):\n",
      radius, map.version, used_vertices.size(), mesh.positions.size(), patch->faces.size(),
      mesh.faces.size());
  AppendIdRanges("# mesh vertices:", used_vertices, &obj);
  AppendIdRanges("# mesh faces:", patch->faces, &obj);
  absl::StrAppend(&obj, "mtllib ", mtl_file_name, "\no ", kMaterialName, "\n");
  for (const int32_t vertex : used_vertices) {
    const Position& p = mesh.positions[vertex];
    absl::StrAppendFormat(&obj, "v %.17g %.17g %.17g\n", p[0], p[1], p[2]);
  }
  for (const int32_t vertex : used_vertices) {
    const int32_t entry = patch->map_entry[vertex];
    const auto [s, t] = DecalTextureCoordinates(map.u[entry], map.v[entry], radius);
    // Viewers keep texture coordinates in single precision.
    absl::StrAppendFormat(&obj, "vt %.9g %.9g\n", s, t);
  }
  absl::StrAppend(&obj, "usemtl ", kMaterialName, "\ns off\n");
  for (const int32_t f : patch->faces) {
    const auto& face = mesh.faces[f];
    const int32_t a = obj_index[face[0]], b = obj_index[face[1]], c = obj_index[face[2]];
    absl::StrAppendFormat(&obj, "f %d/%d %d/%d %d/%d\n", a, a, b, b, c, c);
  }

  // illum 1 (no highlights) and Ks 0: a matte surface shows the texture's
  // colours as they are. Blender reads Ka as metallic only for illum >= 3.
  std::string mtl = absl::StrCat("# geodex decal material\nnewmtl ", kMaterialName,
                                 "\nKa 1 1 1\nKd 1 1 1\nKs 0 0 0\nNs 0\nd 1\nillum 1\nmap_Kd ",
                                 texture_file_name, "\n");
  return DecalFiles{std::move(obj), std::move(mtl)};
}

}  // namespace geodex::client::cli
