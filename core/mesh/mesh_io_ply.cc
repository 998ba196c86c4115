// PLY reader (mesh_io.h), ASCII and binary in either byte order.

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/string_view.h"
#include "core/common/status_macros.h"
#include "core/mesh/mesh_io.h"
#include "core/mesh/mesh_io_text.h"

namespace geodex::mesh {
namespace {

using io_internal::FanTriangulateRaw;
using io_internal::IsBlankLine;
using io_internal::LineError;
using io_internal::LineReader;
using io_internal::NextToken;
using io_internal::ParseDouble;
using io_internal::ParseInt;
using io_internal::Quote;
using io_internal::Tokens;

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

// The helpers below read one header line each. Their errors carry only the
// message; ParsePlyHeader adds the file name and line number.

// 'format <ascii|binary_little_endian|binary_big_endian> 1.0'.
absl::Status ParsePlyFormatLine(std::span<const std::string_view> tokens, PlyHeader* header) {
  if (!header->elements.empty()) return absl::InvalidArgumentError("'format' after an element");
  if (tokens.size() != 3) {
    return absl::InvalidArgumentError("expected 'format <ascii|binary_*> 1.0'");
  }
  if (tokens[1] == "ascii") {
    header->format = PlyFormat::kAscii;
  } else if (tokens[1] == "binary_little_endian") {
    header->format = PlyFormat::kBinaryLittleEndian;
  } else if (tokens[1] == "binary_big_endian") {
    header->format = PlyFormat::kBinaryBigEndian;
  } else {
    return absl::InvalidArgumentError(absl::StrCat("unknown format ", Quote(tokens[1])));
  }
  if (tokens[2] != "1.0") {
    return absl::InvalidArgumentError(absl::StrCat("unsupported version ", Quote(tokens[2])));
  }
  return absl::OkStatus();
}

// 'element <name> <count>'; notes which element is the vertex and the face.
absl::Status ParsePlyElementLine(std::span<const std::string_view> tokens, PlyHeader* header) {
  int64_t count = 0;
  if (tokens.size() != 3 || !ParseInt(tokens[2], &count) || count < 0) {
    return absl::InvalidArgumentError("expected 'element <name> <count>' with a count >= 0");
  }
  PlyElement element;
  element.name = std::string(tokens[1]);
  element.count = static_cast<uint64_t>(count);
  for (const PlyElement& other : header->elements) {
    if (other.name == element.name) {
      return absl::InvalidArgumentError(
          absl::StrCat("element ", Quote(element.name), " declared twice"));
    }
  }
  if (element.name == "vertex") {
    element.is_vertex = true;
    header->vertex_element = static_cast<int>(header->elements.size());
  } else if (element.name == "face") {
    element.is_face = true;
    header->face_element = static_cast<int>(header->elements.size());
  }
  header->elements.push_back(std::move(element));
  return absl::OkStatus();
}

// 'property <type> <name>' or 'property list <count type> <type> <name>' of
// the last element; notes the vertex coordinates and the face's index list.
absl::Status ParsePlyPropertyLine(std::span<const std::string_view> tokens, PlyHeader* header) {
  if (header->elements.empty()) {
    return absl::InvalidArgumentError("'property' before any 'element'");
  }
  PlyElement& element = header->elements.back();
  PlyProperty property;
  if (tokens.size() == 5 && tokens[1] == "list") {
    const std::optional<PlyType> count_type = ParsePlyType(tokens[2]);
    const std::optional<PlyType> type = ParsePlyType(tokens[3]);
    if (!count_type || !type) {
      return absl::InvalidArgumentError(
          absl::StrCat("unknown type in list property ", Quote(tokens[4])));
    }
    if (!IsPlyIntegerType(*count_type)) {
      return absl::InvalidArgumentError(
          absl::StrCat("list count type of ", Quote(tokens[4]), " must be an integer type"));
    }
    property.is_list = true;
    property.count_type = *count_type;
    property.type = *type;
    property.name = std::string(tokens[4]);
  } else if (tokens.size() == 3 && tokens[1] != "list") {
    const std::optional<PlyType> type = ParsePlyType(tokens[1]);
    if (!type) {
      return absl::InvalidArgumentError(absl::StrCat("unknown property type ", Quote(tokens[1])));
    }
    property.type = *type;
    property.name = std::string(tokens[2]);
  } else {
    return absl::InvalidArgumentError(
        "expected 'property <type> <name>' or 'property list <type> <type> <name>'");
  }
  for (const PlyProperty& other : element.properties) {
    if (other.name == property.name) {
      return absl::InvalidArgumentError(
          absl::StrCat("property ", Quote(property.name), " declared twice"));
    }
  }
  const int index = static_cast<int>(element.properties.size());
  if (element.is_vertex) {
    for (int axis = 0; axis < 3; ++axis) {
      if (property.name == std::string_view(&"xyz"[axis], 1)) {
        if (property.is_list) {
          return absl::InvalidArgumentError("vertex coordinate declared as a list");
        }
        element.coordinate_of[axis] = index;
      }
    }
  }
  if (element.is_face && (property.name == "vertex_indices" || property.name == "vertex_index")) {
    if (!property.is_list) {
      return absl::InvalidArgumentError(absl::StrCat(Quote(property.name), " is not a list"));
    }
    if (!IsPlyIntegerType(property.type)) {
      return absl::InvalidArgumentError(
          absl::StrCat(Quote(property.name), " must have an integer value type"));
    }
    if (element.indices_property >= 0) {
      return absl::InvalidArgumentError("face element has both vertex_indices and vertex_index");
    }
    element.indices_property = index;
  }
  element.properties.push_back(std::move(property));
  return absl::OkStatus();
}

// Once the header has ended: a vertex element with x, y, z and a face
// element with an index list, and no element without properties.
absl::Status CheckPlyHeaderHasAMesh(const PlyHeader& header) {
  if (header.vertex_element < 0) return absl::InvalidArgumentError("no 'vertex' element");
  if (header.face_element < 0) return absl::InvalidArgumentError("no 'face' element");
  const PlyElement& vertex = header.elements[header.vertex_element];
  for (int axis = 0; axis < 3; ++axis) {
    if (vertex.coordinate_of[axis] < 0) {
      return absl::InvalidArgumentError(
          absl::StrCat("element 'vertex' has no property '", std::string(1, "xyz"[axis]), "'"));
    }
  }
  if (vertex.count > static_cast<uint64_t>(std::numeric_limits<int32_t>::max() - 1)) {
    return absl::InvalidArgumentError("too many vertices");
  }
  if (header.elements[header.face_element].indices_property < 0) {
    return absl::InvalidArgumentError(
        "element 'face' has no list property 'vertex_indices' or 'vertex_index'");
  }
  for (const PlyElement& element : header.elements) {
    if (element.properties.empty() && element.count > 0) {
      return absl::InvalidArgumentError(
          absl::StrCat("element ", Quote(element.name), " has no properties"));
    }
  }
  return absl::OkStatus();
}

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
    absl::Status status;
    if (keyword == "format") {
      if (has_format) return error("second 'format' line");
      status = ParsePlyFormatLine(tokens, &header);
      has_format = status.ok();
    } else if (keyword == "element") {
      if (!has_format) return error("'element' before 'format'");
      status = ParsePlyElementLine(tokens, &header);
    } else if (keyword == "property") {
      status = ParsePlyPropertyLine(tokens, &header);
    } else if (keyword == "end_header") {
      if (tokens.size() != 1) return error("unexpected text after 'end_header'");
      has_end = true;
      break;
    } else {
      return error(absl::StrCat("unknown keyword ", Quote(keyword)));
    }
    if (!status.ok()) return error(status.message());
  }
  if (!has_end) {
    return LineError(name, line_number, "PLY header has no 'end_header' (truncated file?)");
  }
  if (!has_format) return LineError(name, line_number, "PLY header has no 'format' line");
  if (absl::Status status = CheckPlyHeaderHasAMesh(header); !status.ok()) {
    return absl::InvalidArgumentError(absl::StrCat(name, ": PLY header: ", status.message()));
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

}  // namespace

absl::StatusOr<RawMesh> ParsePlyTriangles(std::string_view contents, const std::string& name) {
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
  return FanTriangulateRaw(std::move(builder.positions), builder.corners, builder.face_begin, name);
}

}  // namespace geodex::mesh
