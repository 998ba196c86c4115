#include "core/mesh/mesh_io.h"

#include <algorithm>
#include <bit>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <optional>
#include <string>
#include <system_error>
#include <utility>

#include "absl/status/status.h"
#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/string_view.h"
#include "core/common/file_util.h"
#include "core/common/status_macros.h"
#include "tiny_obj_loader.h"

namespace geodex::mesh {
namespace {

// ---------------------------------------------------------------------------
// Shared text helpers.

absl::Status LineError(const std::string& name, int64_t line, std::string_view message) {
  return absl::InvalidArgumentError(absl::StrFormat("%s: line %d: %s", name, line, message));
}

// Splits text into lines ended by "\n", "\r\n" or a lone "\r" (the rule
// tinyobjloader uses, so that both agree on line numbers).
class LineReader {
 public:
  explicit LineReader(std::string_view text, int64_t first_line = 1)
      : text_(text), next_line_(first_line) {}

  // Returns false at the end of the text.
  bool Next(std::string_view* line) {
    if (pos_ >= text_.size()) return false;
    size_t end = pos_;
    while (end < text_.size() && text_[end] != '\n' && text_[end] != '\r') ++end;
    *line = text_.substr(pos_, end - pos_);
    if (end < text_.size() && text_[end] == '\r' && end + 1 < text_.size() &&
        text_[end + 1] == '\n') {
      ++end;
    }
    pos_ = end + 1;
    line_ = next_line_++;
    return true;
  }
  // Number of the line last returned by Next().
  int64_t line() const { return line_; }
  // Bytes not yet returned.
  size_t remaining() const { return pos_ >= text_.size() ? 0 : text_.size() - pos_; }

 private:
  std::string_view text_;
  size_t pos_ = 0;
  int64_t next_line_;
  int64_t line_ = 0;
};

bool IsBlank(char c) { return c == ' ' || c == '\t'; }

// Returns the next whitespace-separated token of `rest` (empty at the end) and
// advances `rest` past it.
std::string_view NextToken(std::string_view& rest) {
  size_t b = 0;
  while (b < rest.size() && IsBlank(rest[b])) ++b;
  size_t e = b;
  while (e < rest.size() && !IsBlank(rest[e])) ++e;
  const std::string_view token = rest.substr(b, e - b);
  rest.remove_prefix(e);
  return token;
}

std::vector<std::string_view> Tokens(std::string_view line) {
  std::vector<std::string_view> tokens;
  for (std::string_view t = NextToken(line); !t.empty(); t = NextToken(line)) tokens.push_back(t);
  return tokens;
}

std::string_view StripComment(std::string_view line) {
  const size_t hash = line.find('#');
  return hash == std::string_view::npos ? line : line.substr(0, hash);
}

bool IsBlankLine(std::string_view line) {
  return std::all_of(line.begin(), line.end(), [](char c) { return IsBlank(c); });
}

// Quotes a token for an error message, shortened and with unprintable bytes
// escaped (the token may come from a binary file).
std::string Quote(std::string_view token) {
  std::string out = "'";
  for (size_t i = 0; i < token.size() && i < 40; ++i) {
    const unsigned char c = static_cast<unsigned char>(token[i]);
    if (c >= 0x20 && c < 0x7f) {
      out += static_cast<char>(c);
    } else {
      absl::StrAppendFormat(&out, "\\x%02x", c);
    }
  }
  if (token.size() > 40) out += "...";
  return out + "'";
}

// Parses a whole token as a double (correctly rounded, unlike tinyobjloader's
// own parser). Accepts a leading '+', "nan" and "inf"; the caller decides
// whether non-finite values are allowed. Values that overflow are rejected;
// values that underflow become 0 or subnormal.
bool ParseDouble(std::string_view token, double* value) {
  if (token.size() > 1 && token[0] == '+' && token[1] != '-') token.remove_prefix(1);
  if (token.empty()) return false;
  const char* end = token.data() + token.size();
  const auto [ptr, ec] = std::from_chars(token.data(), end, *value);
  if (ptr != end) return false;
  if (ec == std::errc::result_out_of_range) {
    const std::string copy(token);
    *value = std::strtod(copy.c_str(), nullptr);
    return std::isfinite(*value);
  }
  return ec == std::errc();
}

bool ParseInt(std::string_view token, int64_t* value) {
  if (token.size() > 1 && token[0] == '+' && token[1] != '-') token.remove_prefix(1);
  if (token.empty()) return false;
  const char* end = token.data() + token.size();
  const auto [ptr, ec] = std::from_chars(token.data(), end, *value);
  return ec == std::errc() && ptr == end;
}

// Parses three coordinates; errors name the offending token.
absl::Status ParseCoordinates(std::span<const std::string_view> tokens, const std::string& name,
                              int64_t line, Vec3* p) {
  for (int i = 0; i < 3; ++i) {
    if (!ParseDouble(tokens[i], &(*p)[i])) {
      return LineError(name, line,
                       absl::StrCat("coordinate ", Quote(tokens[i]), " is not a number"));
    }
    if (!std::isfinite((*p)[i])) {
      return LineError(name, line, absl::StrCat("coordinate ", Quote(tokens[i]), " is not finite"));
    }
  }
  return absl::OkStatus();
}

// Hands the parsed polygons to Mesh::Create after fan triangulation.
absl::StatusOr<LoadedMesh> FanTriangulate(std::vector<Vec3> positions,
                                          const std::vector<int32_t>& corners,
                                          const std::vector<size_t>& face_begin,
                                          const std::string& name) {
  const size_t num_faces = face_begin.size() - 1;
  std::vector<Triangle> triangles;
  std::vector<int32_t> input_face;
  triangles.reserve(corners.size() - 2 * num_faces);
  input_face.reserve(corners.size() - 2 * num_faces);
  for (size_t f = 0; f < num_faces; ++f) {
    const size_t b = face_begin[f], e = face_begin[f + 1];
    for (size_t i = b + 1; i + 1 < e; ++i) {
      triangles.push_back({corners[b], corners[i], corners[i + 1]});
      input_face.push_back(static_cast<int32_t>(f));
    }
  }
  const bool polygons = triangles.size() != num_faces;
  absl::StatusOr<Mesh> mesh = Mesh::Create(std::move(positions), std::move(triangles), name);
  if (!mesh.ok()) {
    if (polygons && mesh.status().code() == absl::StatusCode::kInvalidArgument) {
      return absl::InvalidArgumentError(absl::StrCat(
          mesh.status().message(),
          " [face ids count triangles after fan triangulation of the file's polygons]"));
    }
    return mesh.status();
  }
  return LoadedMesh{*std::move(mesh), std::move(input_face)};
}

// ---------------------------------------------------------------------------
// OBJ.
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

// ---------------------------------------------------------------------------
// PLY (http://paulbourke.net/dataformats/ply/), written by hand: Debian has
// no PLY library. Every count is checked against the bytes that remain before
// anything is reserved or read.

enum class PlyType { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };
enum class PlyFormat { kAscii, kBinaryLittleEndian, kBinaryBigEndian };

std::optional<PlyType> ParsePlyType(std::string_view s) {
  if (s == "char" || s == "int8") return PlyType::kInt8;
  if (s == "uchar" || s == "uint8") return PlyType::kUint8;
  if (s == "short" || s == "int16") return PlyType::kInt16;
  if (s == "ushort" || s == "uint16") return PlyType::kUint16;
  if (s == "int" || s == "int32") return PlyType::kInt32;
  if (s == "uint" || s == "uint32") return PlyType::kUint32;
  if (s == "float" || s == "float32") return PlyType::kFloat32;
  if (s == "double" || s == "float64") return PlyType::kFloat64;
  return std::nullopt;
}

size_t PlyTypeSize(PlyType t) {
  switch (t) {
    case PlyType::kInt8:
    case PlyType::kUint8:
      return 1;
    case PlyType::kInt16:
    case PlyType::kUint16:
      return 2;
    case PlyType::kInt32:
    case PlyType::kUint32:
    case PlyType::kFloat32:
      return 4;
    case PlyType::kFloat64:
      return 8;
  }
  return 0;
}

bool IsPlyIntegerType(PlyType t) { return t != PlyType::kFloat32 && t != PlyType::kFloat64; }

struct PlyProperty {
  std::string name;
  bool is_list = false;
  PlyType count_type = PlyType::kUint8;  // lists only
  PlyType type = PlyType::kFloat32;      // scalar type, or the list's value type
};

struct PlyElement {
  std::string name;
  uint64_t count = 0;
  std::vector<PlyProperty> properties;
  // Roles in the mesh.
  bool is_vertex = false;
  bool is_face = false;
  int coordinate_of[3] = {-1, -1, -1};  // property index of x, y, z
  int indices_property = -1;            // face: the vertex_indices list
};

struct PlyHeader {
  PlyFormat format = PlyFormat::kAscii;
  std::vector<PlyElement> elements;
  size_t body_offset = 0;  // first byte after "end_header\n"
  int64_t body_line = 0;   // line number of the first body line (ASCII)
  int vertex_element = -1;
  int face_element = -1;
};

absl::StatusOr<PlyHeader> ParsePlyHeader(std::string_view contents, const std::string& name) {
  PlyHeader header;
  bool has_format = false, has_end = false;
  size_t pos = 0;
  int64_t line_number = 0;
  while (pos < contents.size()) {
    // Header lines end with '\n' (optionally preceded by '\r'); the binary
    // body starts right after the '\n' of end_header.
    const size_t newline = contents.find('\n', pos);
    std::string_view line =
        contents.substr(pos, (newline == std::string_view::npos ? contents.size() : newline) - pos);
    pos = newline == std::string_view::npos ? contents.size() : newline + 1;
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    auto error = [&](absl::string_view message) {
      return LineError(name, line_number, absl::StrCat("PLY header: ", message));
    };
    const std::vector<std::string_view> tokens = Tokens(line);
    if (line_number == 1) {
      if (tokens.size() != 1 || tokens[0] != "ply") {
        return LineError(name, 1, "not a PLY file (the first line must be 'ply')");
      }
      continue;
    }
    if (tokens.empty()) return error("empty line");
    const std::string_view keyword = tokens[0];
    if (keyword == "comment" || keyword == "obj_info") continue;
    if (keyword == "format") {
      if (has_format) return error("second 'format' line");
      if (!header.elements.empty()) return error("'format' after an element");
      if (tokens.size() != 3) return error("expected 'format <ascii|binary_*> 1.0'");
      if (tokens[1] == "ascii") {
        header.format = PlyFormat::kAscii;
      } else if (tokens[1] == "binary_little_endian") {
        header.format = PlyFormat::kBinaryLittleEndian;
      } else if (tokens[1] == "binary_big_endian") {
        header.format = PlyFormat::kBinaryBigEndian;
      } else {
        return error(absl::StrCat("unknown format ", Quote(tokens[1])));
      }
      if (tokens[2] != "1.0") return error(absl::StrCat("unsupported version ", Quote(tokens[2])));
      has_format = true;
    } else if (keyword == "element") {
      if (!has_format) return error("'element' before 'format'");
      int64_t count = 0;
      if (tokens.size() != 3 || !ParseInt(tokens[2], &count) || count < 0) {
        return error("expected 'element <name> <count>' with a count >= 0");
      }
      PlyElement element;
      element.name = std::string(tokens[1]);
      element.count = static_cast<uint64_t>(count);
      for (const PlyElement& other : header.elements) {
        if (other.name == element.name) {
          return error(absl::StrCat("element ", Quote(element.name), " declared twice"));
        }
      }
      if (element.name == "vertex") {
        element.is_vertex = true;
        header.vertex_element = static_cast<int>(header.elements.size());
      } else if (element.name == "face") {
        element.is_face = true;
        header.face_element = static_cast<int>(header.elements.size());
      }
      header.elements.push_back(std::move(element));
    } else if (keyword == "property") {
      if (header.elements.empty()) return error("'property' before any 'element'");
      PlyElement& element = header.elements.back();
      PlyProperty property;
      if (tokens.size() == 5 && tokens[1] == "list") {
        const std::optional<PlyType> count_type = ParsePlyType(tokens[2]);
        const std::optional<PlyType> type = ParsePlyType(tokens[3]);
        if (!count_type || !type) {
          return error(absl::StrCat("unknown type in list property ", Quote(tokens[4])));
        }
        if (!IsPlyIntegerType(*count_type)) {
          return error(
              absl::StrCat("list count type of ", Quote(tokens[4]), " must be an integer type"));
        }
        property.is_list = true;
        property.count_type = *count_type;
        property.type = *type;
        property.name = std::string(tokens[4]);
      } else if (tokens.size() == 3 && tokens[1] != "list") {
        const std::optional<PlyType> type = ParsePlyType(tokens[1]);
        if (!type) return error(absl::StrCat("unknown property type ", Quote(tokens[1])));
        property.type = *type;
        property.name = std::string(tokens[2]);
      } else {
        return error("expected 'property <type> <name>' or 'property list <type> <type> <name>'");
      }
      for (const PlyProperty& other : element.properties) {
        if (other.name == property.name) {
          return error(absl::StrCat("property ", Quote(property.name), " declared twice"));
        }
      }
      const int index = static_cast<int>(element.properties.size());
      if (element.is_vertex) {
        for (int axis = 0; axis < 3; ++axis) {
          if (property.name == std::string_view("xyz" + axis, 1)) {
            if (property.is_list) return error("vertex coordinate declared as a list");
            element.coordinate_of[axis] = index;
          }
        }
      }
      if (element.is_face &&
          (property.name == "vertex_indices" || property.name == "vertex_index")) {
        if (!property.is_list) return error(absl::StrCat(Quote(property.name), " is not a list"));
        if (!IsPlyIntegerType(property.type)) {
          return error(absl::StrCat(Quote(property.name), " must have an integer value type"));
        }
        if (element.indices_property >= 0) {
          return error("face element has both vertex_indices and vertex_index");
        }
        element.indices_property = index;
      }
      element.properties.push_back(std::move(property));
    } else if (keyword == "end_header") {
      if (tokens.size() != 1) return error("unexpected text after 'end_header'");
      has_end = true;
      break;
    } else {
      return error(absl::StrCat("unknown keyword ", Quote(keyword)));
    }
  }
  if (!has_end) {
    return LineError(name, line_number, "PLY header has no 'end_header' (truncated file?)");
  }
  if (!has_format) return LineError(name, line_number, "PLY header has no 'format' line");
  auto error = [&](absl::string_view message) {
    return absl::InvalidArgumentError(absl::StrCat(name, ": PLY header: ", message));
  };
  if (header.vertex_element < 0) return error("no 'vertex' element");
  if (header.face_element < 0) return error("no 'face' element");
  const PlyElement& vertex = header.elements[header.vertex_element];
  for (int axis = 0; axis < 3; ++axis) {
    if (vertex.coordinate_of[axis] < 0) {
      return error(
          absl::StrCat("element 'vertex' has no property '", std::string(1, "xyz"[axis]), "'"));
    }
  }
  if (vertex.count > static_cast<uint64_t>(std::numeric_limits<int32_t>::max() - 1)) {
    return error("too many vertices");
  }
  if (header.elements[header.face_element].indices_property < 0) {
    return error("element 'face' has no list property 'vertex_indices' or 'vertex_index'");
  }
  for (const PlyElement& element : header.elements) {
    if (element.properties.empty() && element.count > 0) {
      return error(absl::StrCat("element ", Quote(element.name), " has no properties"));
    }
  }
  header.body_offset = pos;
  header.body_line = line_number + 1;
  return header;
}

// Receives the values of the mesh-relevant properties while the body is read.
struct PlyMeshBuilder {
  std::vector<Vec3> positions;
  std::vector<int32_t> corners;
  std::vector<size_t> face_begin = {0};
};

// Reads values of the PLY body in either encoding. `Where()` names the current
// line (ASCII) or element instance (binary) for error messages.
class PlyAsciiSource {
 public:
  PlyAsciiSource(std::string_view body, int64_t first_line, const std::string& name)
      : reader_(body, first_line), name_(name) {}

  absl::Status BeginInstance(const PlyElement& element, uint64_t i) {
    std::string_view line;
    while (reader_.Next(&line)) {
      if (!IsBlankLine(line)) {
        rest_ = line;
        return absl::OkStatus();
      }
    }
    return absl::InvalidArgumentError(absl::StrFormat(
        "%s: line %d: file ends before %s %d of %d (truncated file, or the header count is "
        "too large)",
        name_, reader_.line() + 1, Quote(element.name), i, element.count));
  }
  absl::Status EndInstance() {
    const std::string_view extra = NextToken(rest_);
    if (!extra.empty()) {
      return Error(absl::StrCat("unexpected value ", Quote(extra), " at the end of the line"));
    }
    return absl::OkStatus();
  }
  absl::Status Read(PlyType type, double* value) {
    const std::string_view token = NextToken(rest_);
    if (token.empty()) return Error("line ends early: too few values for the header's properties");
    if (IsPlyIntegerType(type)) {
      int64_t v = 0;
      if (!ParseInt(token, &v)) {
        return Error(absl::StrCat("value ", Quote(token), " is not an integer"));
      }
      const size_t bits = 8 * PlyTypeSize(type);
      const bool is_signed =
          type == PlyType::kInt8 || type == PlyType::kInt16 || type == PlyType::kInt32;
      const int64_t lo = is_signed ? -(int64_t{1} << (bits - 1)) : 0;
      const int64_t hi = is_signed ? (int64_t{1} << (bits - 1)) - 1 : (int64_t{1} << bits) - 1;
      if (v < lo || v > hi) {
        return Error(absl::StrCat("value ", Quote(token), " is out of range for its type"));
      }
      *value = static_cast<double>(v);
    } else if (!ParseDouble(token, value)) {
      return Error(absl::StrCat("value ", Quote(token), " is not a number"));
    }
    return absl::OkStatus();
  }
  // Checks that a list of `count` values can be present.
  absl::Status CheckListCount(uint64_t count, PlyType) {
    // Every value takes at least two characters (a digit and a separator).
    if (count > rest_.size() / 2 + 1) {
      return Error(absl::StrFormat("list count %d exceeds the values on the line", count));
    }
    return absl::OkStatus();
  }
  // Checks that `count` instances of `element` can be present.
  absl::Status CheckElementCount(const PlyElement& element) {
    if (element.count > reader_.remaining() / 2 + 1) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "%s: line %d: element %s declares %d instances but only %d bytes remain", name_,
          reader_.line() + 1, Quote(element.name), element.count, reader_.remaining()));
    }
    return absl::OkStatus();
  }
  absl::Status Finish() {
    std::string_view line;
    while (reader_.Next(&line)) {
      if (!IsBlankLine(line)) {
        return Error(
            "unexpected data after the last element (the header counts do not match the data)");
      }
    }
    return absl::OkStatus();
  }
  std::string Where() const { return absl::StrFormat("%s: line %d", name_, reader_.line()); }
  absl::Status Error(absl::string_view message) const {
    return absl::InvalidArgumentError(absl::StrCat(Where(), ": ", message));
  }

 private:
  LineReader reader_;
  std::string_view rest_;
  const std::string& name_;
};

class PlyBinarySource {
 public:
  PlyBinarySource(std::string_view body, bool big_endian, const std::string& name)
      : body_(body), big_endian_(big_endian), name_(name) {}

  absl::Status BeginInstance(const PlyElement& element, uint64_t i) {
    element_ = &element;
    instance_ = i;
    return absl::OkStatus();
  }
  absl::Status EndInstance() { return absl::OkStatus(); }
  absl::Status Read(PlyType type, double* value) {
    const size_t size = PlyTypeSize(type);
    if (body_.size() - pos_ < size) {
      return Error("file ends inside this element (truncated file?)");
    }
    unsigned char bytes[8];
    std::memcpy(bytes, body_.data() + pos_, size);
    pos_ += size;
    if (big_endian_ != (std::endian::native == std::endian::big)) std::reverse(bytes, bytes + size);
    switch (type) {
      case PlyType::kInt8:
        *value = Load<int8_t>(bytes);
        break;
      case PlyType::kUint8:
        *value = Load<uint8_t>(bytes);
        break;
      case PlyType::kInt16:
        *value = Load<int16_t>(bytes);
        break;
      case PlyType::kUint16:
        *value = Load<uint16_t>(bytes);
        break;
      case PlyType::kInt32:
        *value = Load<int32_t>(bytes);
        break;
      case PlyType::kUint32:
        *value = Load<uint32_t>(bytes);
        break;
      case PlyType::kFloat32:
        *value = Load<float>(bytes);
        break;
      case PlyType::kFloat64:
        *value = Load<double>(bytes);
        break;
    }
    return absl::OkStatus();
  }
  absl::Status CheckListCount(uint64_t count, PlyType type) {
    if (count > (body_.size() - pos_) / PlyTypeSize(type)) {
      return Error(absl::StrFormat("list count %d exceeds the %d bytes left in the file", count,
                                   body_.size() - pos_));
    }
    return absl::OkStatus();
  }
  absl::Status CheckElementCount(const PlyElement& element) {
    size_t min_size = 0;
    for (const PlyProperty& p : element.properties) {
      min_size += PlyTypeSize(p.is_list ? p.count_type : p.type);
    }
    const size_t left = body_.size() - pos_;
    if (min_size > 0 && element.count > left / min_size) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "%s: element %s declares %d instances of at least %d bytes but only %d bytes remain "
          "(truncated file, or the header count is too large)",
          name_, Quote(element.name), element.count, min_size, left));
    }
    return absl::OkStatus();
  }
  absl::Status Finish() {
    if (pos_ != body_.size()) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "%s: %d bytes after the last element (the header counts do not match the data)", name_,
          body_.size() - pos_));
    }
    return absl::OkStatus();
  }
  std::string Where() const {
    return absl::StrFormat("%s: element %s %d (of %d)", name_, Quote(element_->name), instance_,
                           element_->count);
  }
  absl::Status Error(absl::string_view message) const {
    return absl::InvalidArgumentError(absl::StrCat(Where(), ": ", message));
  }

 private:
  template <typename T>
  static double Load(const unsigned char* bytes) {
    T v;
    std::memcpy(&v, bytes, sizeof(T));
    return static_cast<double>(v);
  }

  std::string_view body_;
  size_t pos_ = 0;
  bool big_endian_;
  const std::string& name_;
  const PlyElement* element_ = nullptr;
  uint64_t instance_ = 0;
};

template <typename Source>
absl::Status ReadPlyBody(const PlyHeader& header, Source& source, PlyMeshBuilder* out) {
  const int32_t num_vertices = static_cast<int32_t>(header.elements[header.vertex_element].count);
  for (const PlyElement& element : header.elements) {
    GEODEX_RETURN_IF_ERROR(source.CheckElementCount(element));
    if (element.is_vertex) out->positions.reserve(element.count);
    if (element.is_face) out->face_begin.reserve(element.count + 1);
    std::vector<double> scalars(element.properties.size());
    for (uint64_t i = 0; i < element.count; ++i) {
      GEODEX_RETURN_IF_ERROR(source.BeginInstance(element, i));
      for (size_t p = 0; p < element.properties.size(); ++p) {
        const PlyProperty& property = element.properties[p];
        if (!property.is_list) {
          GEODEX_RETURN_IF_ERROR(source.Read(property.type, &scalars[p]));
          continue;
        }
        double count_value = 0;
        GEODEX_RETURN_IF_ERROR(source.Read(property.count_type, &count_value));
        if (count_value < 0) {
          return source.Error(absl::StrFormat("negative list count %g", count_value));
        }
        const uint64_t count = static_cast<uint64_t>(count_value);
        GEODEX_RETURN_IF_ERROR(source.CheckListCount(count, property.type));
        const bool is_indices = element.is_face && static_cast<int>(p) == element.indices_property;
        if (is_indices && count < 3) {
          return source.Error(absl::StrFormat("face has %d corners, at least 3 needed", count));
        }
        for (uint64_t k = 0; k < count; ++k) {
          double v = 0;
          GEODEX_RETURN_IF_ERROR(source.Read(property.type, &v));
          if (!is_indices) continue;
          if (v < 0 || v >= num_vertices) {
            return source.Error(absl::StrFormat(
                "vertex index %.0f is out of range (the file has %d vertices)", v, num_vertices));
          }
          out->corners.push_back(static_cast<int32_t>(v));
        }
        if (is_indices) out->face_begin.push_back(out->corners.size());
      }
      if (element.is_vertex) {
        Vec3 position;
        for (int axis = 0; axis < 3; ++axis) {
          position[axis] = scalars[element.coordinate_of[axis]];
          if (!std::isfinite(position[axis])) {
            return source.Error(
                absl::StrFormat("coordinate %c is not finite (%g)", "xyz"[axis], position[axis]));
          }
        }
        out->positions.push_back(position);
      }
      GEODEX_RETURN_IF_ERROR(source.EndInstance());
    }
  }
  return source.Finish();
}

// ---------------------------------------------------------------------------
// OFF (Geomview's Object File Format, as also written by libigl and CGAL).

// Returns true for OFF header keywords whose vertex lines start with x y z:
// OFF and its colour/normal/texture variants. 4OFF / nOFF change the
// dimension and are not supported.
bool IsOffKeyword(std::string_view keyword) {
  if (keyword.size() < 3 || keyword.substr(keyword.size() - 3) != "OFF") return false;
  std::string_view prefix = keyword.substr(0, keyword.size() - 3);
  if (prefix.starts_with("ST")) prefix.remove_prefix(2);
  if (prefix.starts_with("C")) prefix.remove_prefix(1);
  if (prefix.starts_with("N")) prefix.remove_prefix(1);
  return prefix.empty();
}

// ---------------------------------------------------------------------------
// Files.

std::string Lowercase(std::string_view s) {
  return absl::AsciiStrToLower(absl::string_view(s.data(), s.size()));
}

std::string Extension(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  const size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  return Lowercase(std::string_view(path).substr(dot + 1));
}

template <typename T>
void AppendLittleEndian(std::string* out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  if constexpr (std::endian::native == std::endian::big) std::reverse(bytes, bytes + sizeof(T));
  out->append(bytes, sizeof(T));
}

}  // namespace

absl::StatusOr<LoadedMesh> ParseObj(std::string_view contents, const std::string& name) {
  std::vector<Vec3> positions;
  ObjFaces faces;
  GEODEX_RETURN_IF_ERROR(ScanObj(contents, name, &positions, &faces));
  GEODEX_RETURN_IF_ERROR(CrossCheckWithTinyObj(contents, name, positions.size(), faces));
  return FanTriangulate(std::move(positions), faces.corners, faces.face_begin, name);
}

absl::StatusOr<LoadedMesh> ParsePly(std::string_view contents, const std::string& name) {
  GEODEX_ASSIGN_OR_RETURN(const PlyHeader header, ParsePlyHeader(contents, name));
  const std::string_view body = contents.substr(header.body_offset);
  PlyMeshBuilder builder;
  if (header.format == PlyFormat::kAscii) {
    PlyAsciiSource source(body, header.body_line, name);
    GEODEX_RETURN_IF_ERROR(ReadPlyBody(header, source, &builder));
  } else {
    PlyBinarySource source(body, header.format == PlyFormat::kBinaryBigEndian, name);
    GEODEX_RETURN_IF_ERROR(ReadPlyBody(header, source, &builder));
  }
  return FanTriangulate(std::move(builder.positions), builder.corners, builder.face_begin, name);
}

absl::StatusOr<LoadedMesh> ParseOff(std::string_view contents, const std::string& name) {
  LineReader reader(contents);
  std::string_view line;
  // Next line with content, comments removed; false at the end of the file.
  auto next_tokens = [&](std::vector<std::string_view>* tokens) {
    while (reader.Next(&line)) {
      *tokens = Tokens(StripComment(line));
      if (!tokens->empty()) return true;
    }
    return false;
  };
  std::vector<std::string_view> tokens;
  if (!next_tokens(&tokens)) {
    return absl::InvalidArgumentError(absl::StrCat(name, ": empty OFF file"));
  }
  if (!IsOffKeyword(tokens[0])) {
    return LineError(name, reader.line(),
                     absl::StrCat("not an OFF file: expected 'OFF', found ", Quote(tokens[0])));
  }
  if (tokens.size() > 1 && tokens[1] == "BINARY") {
    return LineError(name, reader.line(), "binary OFF is not supported");
  }
  // The counts may follow the keyword on the same line.
  tokens.erase(tokens.begin());
  if (tokens.empty() && !next_tokens(&tokens)) {
    return LineError(name, reader.line() + 1, "file ends before the counts line");
  }
  int64_t num_vertices = 0, num_faces = 0, num_edges = 0;
  if (tokens.size() < 2 || tokens.size() > 3 || !ParseInt(tokens[0], &num_vertices) ||
      !ParseInt(tokens[1], &num_faces) ||
      (tokens.size() == 3 && !ParseInt(tokens[2], &num_edges)) || num_vertices < 0 ||
      num_faces < 0) {
    return LineError(name, reader.line(),
                     "expected the counts line '<vertices> <faces> [<edges>]' (integers >= 0)");
  }
  // Each vertex and face needs at least one line of at least two bytes.
  if (num_vertices > std::numeric_limits<int32_t>::max() - 1 ||
      num_faces > std::numeric_limits<int32_t>::max() ||
      num_vertices + num_faces > static_cast<int64_t>(reader.remaining() / 2 + 1)) {
    return LineError(name, reader.line(),
                     absl::StrFormat("counts (%d vertices, %d faces) exceed the %d bytes left in "
                                     "the file",
                                     num_vertices, num_faces, reader.remaining()));
  }
  std::vector<Vec3> positions;
  positions.reserve(num_vertices);
  for (int64_t v = 0; v < num_vertices; ++v) {
    if (!next_tokens(&tokens)) {
      return LineError(name, reader.line() + 1,
                       absl::StrFormat("file ends before vertex %d of %d (truncated file, or the "
                                       "header count is too large)",
                                       v, num_vertices));
    }
    if (tokens.size() < 3) {
      return LineError(name, reader.line(),
                       absl::StrFormat("vertex has %d coordinates, expected 3", tokens.size()));
    }
    // Values after x y z (colours, normals, texture coordinates) are ignored.
    Vec3 p;
    GEODEX_RETURN_IF_ERROR(ParseCoordinates(tokens, name, reader.line(), &p));
    positions.push_back(p);
  }
  std::vector<int32_t> corners;
  std::vector<size_t> face_begin = {0};
  face_begin.reserve(num_faces + 1);
  for (int64_t f = 0; f < num_faces; ++f) {
    if (!next_tokens(&tokens)) {
      return LineError(name, reader.line() + 1,
                       absl::StrFormat("file ends before face %d of %d (truncated file, or the "
                                       "header count is too large)",
                                       f, num_faces));
    }
    int64_t k = 0;
    if (!ParseInt(tokens[0], &k)) {
      return LineError(name, reader.line(),
                       absl::StrCat("face corner count ", Quote(tokens[0]), " is not an integer"));
    }
    if (k < 3) {
      return LineError(name, reader.line(),
                       absl::StrFormat("face has %d corners, at least 3 needed", k));
    }
    if (k > static_cast<int64_t>(tokens.size()) - 1) {
      return LineError(
          name, reader.line(),
          absl::StrFormat("face declares %d corners but lists %d values", k, tokens.size() - 1));
    }
    // Values after the k indices (a face colour) are ignored.
    for (int64_t i = 1; i <= k; ++i) {
      int64_t index = 0;
      if (!ParseInt(tokens[i], &index)) {
        return LineError(name, reader.line(),
                         absl::StrCat("vertex index ", Quote(tokens[i]), " is not an integer"));
      }
      if (index < 0 || index >= num_vertices) {
        return LineError(name, reader.line(),
                         absl::StrFormat("vertex index %d is out of range (the file has %d "
                                         "vertices)",
                                         index, num_vertices));
      }
      corners.push_back(static_cast<int32_t>(index));
    }
    face_begin.push_back(corners.size());
  }
  if (next_tokens(&tokens)) {
    return LineError(name, reader.line(),
                     "unexpected data after the last face (the header counts do not match the "
                     "data)");
  }
  return FanTriangulate(std::move(positions), corners, face_begin, name);
}

absl::StatusOr<LoadedMesh> LoadMeshFile(const std::string& path) {
  const std::string extension = Extension(path);
  absl::StatusOr<LoadedMesh> (*parse)(std::string_view, const std::string&) = nullptr;
  if (extension == "obj") {
    parse = &ParseObj;
  } else if (extension == "ply") {
    parse = &ParsePly;
  } else if (extension == "off") {
    parse = &ParseOff;
  } else {
    return absl::InvalidArgumentError(absl::StrFormat(
        "%s: unknown mesh file extension '%s' (expected .obj, .ply or .off)", path, extension));
  }
  GEODEX_ASSIGN_OR_RETURN(const std::string contents, ReadWholeFile(path));
  return parse(contents, path);
}

absl::StatusOr<Mesh> LoadMesh(const std::string& path) {
  GEODEX_ASSIGN_OR_RETURN(LoadedMesh loaded, LoadMeshFile(path));
  return std::move(loaded.mesh);
}

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
