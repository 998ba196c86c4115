// OBJ reader (mesh_io.h).

#include <algorithm>
#include <iterator>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "core/common/status_macros.h"
#include "core/mesh/mesh_io.h"
#include "core/mesh/mesh_io_text.h"
#include "tiny_obj_loader.h"

namespace geodex::mesh {
namespace {

using io_internal::FanTriangulateRaw;
using io_internal::LineError;
using io_internal::LineReader;
using io_internal::NextToken;
using io_internal::ParseCoordinates;
using io_internal::ParseDouble;
using io_internal::ParseInt;
using io_internal::Quote;
using io_internal::Tokens;

//
// tinyobjloader is the parser of record for faces, but on its own it is too
// lenient for validated input (observed with 2.0rc10): unparsable or "nan"
// coordinates become 0, coordinates are not correctly rounded (0.30000000000000004
// reads as 0.3000000000000001), faces with fewer than 3 corners are dropped with
// only a warning, out-of-range indices give only a warning, relative indices
// before the first vertex resolve to negative ids silently, "3x" reads as 3,
// indices overflow through atoi, and polygon sizes are stored in an unsigned
// char. So a strict line pass runs first: it rejects malformed lines with their
// line number, supplies exact coordinates, and reads the faces independently;
// tinyobjloader's faces must then agree with it.

// Statements that carry no surface geometry; skipped.
bool IsIgnoredObjStatement(std::string_view keyword) {
  static constexpr std::string_view kIgnored[] = {
      "vt",         "vn",        "vp",    "l",        "p",        "g",    "o",      "s",
      "usemtl",     "mtllib",    "t",     "cstype",   "deg",      "bmat", "step",   "curv",
      "curv2",      "surf",      "parm",  "trim",     "hole",     "scrv", "sp",     "end",
      "con",        "mg",        "bevel", "c_interp", "d_interp", "lod",  "usemap", "maplib",
      "shadow_obj", "trace_obj", "ctech", "stech",    "call",     "csh"};
  return std::find(std::begin(kIgnored), std::end(kIgnored), keyword) != std::end(kIgnored);
}

struct ObjFaces {
  std::vector<int32_t> corners;    // resolved 0-based vertex ids
  std::vector<size_t> face_begin;  // face f: corners[face_begin[f], face_begin[f+1])
  std::vector<int64_t> face_line;  // line of each face
};

// Parses one corner "v", "v/vt", "v/vt/vn" or "v//vn"; returns the raw vertex
// index (nonzero). tinyobjloader rejects zero indices in every slot.
absl::StatusOr<int64_t> ParseObjCorner(std::string_view token, const std::string& name,
                                       int64_t line) {
  std::string_view parts[3];
  int num_parts = 0;
  std::string_view rest = token;
  while (true) {
    if (num_parts == 3) {
      return LineError(name, line, absl::StrCat("face corner ", Quote(token), " is malformed"));
    }
    const size_t slash = rest.find('/');
    parts[num_parts++] = rest.substr(0, slash);
    if (slash == std::string_view::npos) break;
    rest.remove_prefix(slash + 1);
  }
  int64_t vertex = 0;
  for (int i = 0; i < num_parts; ++i) {
    if (parts[i].empty() && i == 1 && num_parts == 3) continue;  // v//vn
    int64_t value = 0;
    if (!ParseInt(parts[i], &value) || value == 0 || value > std::numeric_limits<int32_t>::max() ||
        value < -int64_t{std::numeric_limits<int32_t>::max()}) {
      return LineError(
          name, line,
          absl::StrCat("face corner ", Quote(token),
                       " is not a valid index (nonzero integers, 1-based or negative relative)"));
    }
    if (i == 0) vertex = value;
  }
  return vertex;
}

absl::Status ScanObj(std::string_view contents, const std::string& name,
                     std::vector<Vec3>* positions, ObjFaces* faces) {
  LineReader reader(contents);
  std::string_view line;
  faces->face_begin.push_back(0);
  while (reader.Next(&line)) {
    if (line.find('\0') != std::string_view::npos) {
      return LineError(name, reader.line(), "contains a NUL byte (not a text OBJ file?)");
    }
    std::string_view rest = line;
    const std::string_view keyword = NextToken(rest);
    if (keyword.empty() || keyword[0] == '#') continue;
    if (keyword == "v") {
      const std::vector<std::string_view> tokens = Tokens(rest);
      if (tokens.size() < 3) {
        return LineError(name, reader.line(),
                         absl::StrFormat("vertex has %d coordinates, expected 3", tokens.size()));
      }
      Vec3 p;
      GEODEX_RETURN_IF_ERROR(ParseCoordinates(tokens, name, reader.line(), &p));
      // Optional w or vertex colour: must at least be numbers.
      for (size_t i = 3; i < tokens.size(); ++i) {
        double unused;
        if (!ParseDouble(tokens[i], &unused)) {
          return LineError(name, reader.line(),
                           absl::StrCat("vertex value ", Quote(tokens[i]), " is not a number"));
        }
      }
      positions->push_back(p);
    } else if (keyword == "f") {
      const int64_t num_before = static_cast<int64_t>(positions->size());
      size_t count = 0;
      for (std::string_view token = NextToken(rest); !token.empty(); token = NextToken(rest)) {
        GEODEX_ASSIGN_OR_RETURN(const int64_t index, ParseObjCorner(token, name, reader.line()));
        int64_t resolved;
        if (index > 0) {
          resolved = index - 1;
        } else {
          resolved = num_before + index;
          if (resolved < 0) {
            return LineError(name, reader.line(),
                             absl::StrFormat("relative vertex index %d refers before the first "
                                             "vertex (%d vertices precede this line)",
                                             index, num_before));
          }
        }
        faces->corners.push_back(static_cast<int32_t>(resolved));
        ++count;
      }
      if (count < 3) {
        return LineError(name, reader.line(),
                         absl::StrFormat("face has %d corners, at least 3 needed", count));
      }
      faces->face_begin.push_back(faces->corners.size());
      faces->face_line.push_back(reader.line());
    } else if (!IsIgnoredObjStatement(keyword)) {
      return LineError(name, reader.line(),
                       absl::StrCat("unknown statement ", Quote(keyword), " (not an OBJ file?)"));
    }
  }
  // Positive indices may refer to vertices defined later (tinyobjloader
  // accepts that), so they are range-checked once the vertex count is known.
  const size_t num_faces = faces->face_line.size();
  for (size_t f = 0; f < num_faces; ++f) {
    for (size_t c = faces->face_begin[f]; c < faces->face_begin[f + 1]; ++c) {
      if (faces->corners[c] >= static_cast<int64_t>(positions->size())) {
        return LineError(name, faces->face_line[f],
                         absl::StrFormat("vertex index %d is out of range (the file has %d "
                                         "vertices)",
                                         faces->corners[c] + int64_t{1}, positions->size()));
      }
    }
  }
  return absl::OkStatus();
}

// Runs tinyobjloader and checks that it read the same faces as ScanObj.
absl::Status CrossCheckWithTinyObj(std::string_view contents, const std::string& name,
                                   size_t num_vertices, const ObjFaces& faces) {
  tinyobj::ObjReaderConfig config;
  config.triangulate = false;
  config.vertex_color = false;
  tinyobj::ObjReader reader;
  // ParseFromString never opens files: `mtllib` statements are ignored.
  if (!reader.ParseFromString(std::string(contents), /*mtl_text=*/"", config)) {
    std::string error(reader.Error());
    while (!error.empty() && error.back() == '\n') error.pop_back();
    return absl::InvalidArgumentError(absl::StrCat(name, ": ", error));
  }
  // Warnings (unknown materials, out-of-range normal or texture indices) are
  // about data we do not use; those about positions and faces cannot occur
  // once ScanObj has accepted the file, and any disagreement is caught below.
  auto mismatch = [&](size_t f, std::string_view what) {
    return absl::InternalError(absl::StrFormat(
        "%s: line %d: tinyobjloader and the geodex OBJ scanner disagree on this face (%s)", name,
        f < faces.face_line.size() ? faces.face_line[f] : 0, what));
  };
  if (reader.GetAttrib().vertices.size() != 3 * num_vertices) {
    return absl::InternalError(
        absl::StrFormat("%s: tinyobjloader read %d vertices, the geodex OBJ scanner %d", name,
                        reader.GetAttrib().vertices.size() / 3, num_vertices));
  }
  // Shapes hold the faces in file order, split at each g/o/usemtl statement.
  size_t f = 0, corner = 0;
  const size_t num_faces = faces.face_begin.size() - 1;
  for (const tinyobj::shape_t& shape : reader.GetShapes()) {
    size_t k = 0;
    for (const unsigned char stored_count : shape.mesh.num_face_vertices) {
      if (f >= num_faces) return mismatch(f, "extra face");
      const size_t count = faces.face_begin[f + 1] - faces.face_begin[f];
      // num_face_vertices is an unsigned char: compare modulo 256.
      if (stored_count != (count & 0xff) || k + count > shape.mesh.indices.size()) {
        return mismatch(f, "corner count");
      }
      for (size_t i = 0; i < count; ++i, ++k, ++corner) {
        if (shape.mesh.indices[k].vertex_index != faces.corners[corner]) {
          return mismatch(f, "vertex index");
        }
      }
      ++f;
    }
    if (k != shape.mesh.indices.size()) return mismatch(f, "corner count");
  }
  if (f != num_faces) return mismatch(f, "missing face");
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<RawMesh> ParseObjTriangles(std::string_view contents, const std::string& name) {
  std::vector<Vec3> positions;
  ObjFaces faces;
  GEODEX_RETURN_IF_ERROR(ScanObj(contents, name, &positions, &faces));
  GEODEX_RETURN_IF_ERROR(CrossCheckWithTinyObj(contents, name, positions.size(), faces));
  return FanTriangulateRaw(std::move(positions), faces.corners, faces.face_begin, name);
}

}  // namespace geodex::mesh
