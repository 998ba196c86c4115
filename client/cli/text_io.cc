#include "client/cli/text_io.h"

#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cstring>
#include <cstdio>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <initializer_list>
#include <iostream>
#include <iterator>
#include <sstream>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"

namespace geodex::client::cli {
namespace {

// Splits on spaces, tabs, commas and carriage returns, dropping empty fields.
std::vector<std::string_view> Fields(std::string_view line) {
  std::vector<std::string_view> fields;
  size_t i = 0;
  auto separator = [](char c) { return c == ' ' || c == '\t' || c == ',' || c == '\r'; };
  while (i < line.size()) {
    while (i < line.size() && separator(line[i])) ++i;
    const size_t start = i;
    while (i < line.size() && !separator(line[i])) ++i;
    if (i > start) fields.push_back(line.substr(start, i - start));
  }
  return fields;
}

// Calls on_line(number, fields) for every line that is not blank or a comment.
template <typename F>
absl::Status ForEachLine(std::string_view text, F&& on_line) {
  int64_t number = 0;
  size_t begin = 0;
  while (begin < text.size()) {
    size_t end = text.find('\n', begin);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view line = text.substr(begin, end - begin);
    begin = end + 1;
    ++number;
    const std::vector<std::string_view> fields = Fields(line);
    if (fields.empty() || fields[0][0] == '#') continue;
    if (absl::Status s = on_line(number, fields); !s.ok()) return s;
  }
  return absl::OkStatus();
}

absl::Status ParseDouble(std::string_view text, int64_t line, size_t field, double* out) {
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), *out);
  if (ec != std::errc() || ptr != text.data() + text.size() || !std::isfinite(*out)) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "line %d: field %d ('%s') is not a finite number", line, field + 1, std::string(text)));
  }
  return absl::OkStatus();
}

absl::Status ParseFace(std::string_view text, int64_t line, size_t field, int32_t* out) {
  int64_t face = 0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), face);
  if (ec != std::errc() || ptr != text.data() + text.size() || face < 0 || face > INT32_MAX) {
    return absl::InvalidArgumentError(absl::StrFormat("line %d: field %d ('%s') is not a face id",
                                                      line, field + 1, std::string(text)));
  }
  *out = static_cast<int32_t>(face);
  return absl::OkStatus();
}

absl::Status CheckCount(const std::vector<std::string_view>& fields, size_t expected,
                        const char* format, int64_t line) {
  if (fields.size() == expected) return absl::OkStatus();
  return absl::InvalidArgumentError(absl::StrFormat("line %d: expected %d fields '%s', found %d",
                                                    line, expected, format, fields.size()));
}

// The surface point at fields[*next] ("v ID", a vertex id, or "f w0 w1 w2",
// which the caller has counted); *next moves past it.
absl::Status ParsePoint(const std::vector<std::string_view>& fields, size_t* next, int64_t line,
                        SurfacePoint* p) {
  const size_t first = *next;
  if (fields[first] == "v") {
    *next = first + 2;
    *p = SurfacePoint::Vertex(0);
    if (ParseFace(fields[first + 1], line, first + 1, &p->vertex).ok()) return absl::OkStatus();
    return absl::InvalidArgumentError(absl::StrFormat("line %d: field %d ('%s') is not a vertex id",
                                                      line, first + 2,
                                                      std::string(fields[first + 1])));
  }
  *next = first + 4;
  if (absl::Status s = ParseFace(fields[first], line, first, &p->face); !s.ok()) return s;
  for (size_t i = 0; i < 3; ++i) {
    if (absl::Status s = ParseDouble(fields[first + 1 + i], line, first + 1 + i, &p->w[i]);
        !s.ok()) {
      return s;
    }
  }
  return absl::OkStatus();
}

// All of `fields` as the surface points `points`, each "f w0 w1 w2" or
// "v ID" (`format` names the first kind in messages).
absl::Status ParsePointsOfLine(const std::vector<std::string_view>& fields, int64_t line,
                               const char* format, std::initializer_list<SurfacePoint*> points) {
  size_t expected = 0;
  bool vertices = false;
  for (size_t k = 0; k < points.size(); ++k) {
    const bool vertex = expected < fields.size() && fields[expected] == "v";
    vertices |= vertex;
    expected += vertex ? 2 : 4;
  }
  if (expected != fields.size()) {
    if (!vertices) return CheckCount(fields, expected, format, line);
    return absl::InvalidArgumentError(absl::StrFormat(
        "line %d: expected %d fields ('%s', a point 'v ID' for a vertex), found %d", line,
        expected, format, fields.size()));
  }
  size_t next = 0;
  for (SurfacePoint* p : points) {
    if (absl::Status s = ParsePoint(fields, &next, line, p); !s.ok()) return s;
  }
  return absl::OkStatus();
}

absl::Status ParsePosition(const std::vector<std::string_view>& fields, size_t first, int64_t line,
                           Position* p) {
  for (size_t i = 0; i < 3; ++i) {
    if (absl::Status s = ParseDouble(fields[first + i], line, first + i, &(*p)[i]); !s.ok()) {
      return s;
    }
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<std::string> ReadFileOrStdin(const std::string& path) {
  if (path == "-") return std::string(std::istreambuf_iterator<char>(std::cin), {});
  std::ifstream in(path, std::ios::binary);
  if (!in) return absl::NotFoundError(absl::StrFormat("cannot open %s", path));
  std::ostringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

absl::StatusOr<ParsedPairs> ParsePairs(std::string_view text) {
  ParsedPairs out;
  absl::Status status = ForEachLine(text, [&](int64_t line, const auto& fields) {
    PointPair pair;
    if (absl::Status s =
            ParsePointsOfLine(fields, line, "fa a0 a1 a2 fb b0 b1 b2", {&pair.a, &pair.b});
        !s.ok()) {
      return s;
    }
    out.pairs.push_back(pair);
    out.lines.push_back(line);
    return absl::OkStatus();
  });
  if (!status.ok()) return status;
  return out;
}

absl::StatusOr<ParsedPositionPairs> ParsePositionPairs(std::string_view text) {
  ParsedPositionPairs out;
  absl::Status status = ForEachLine(text, [&](int64_t line, const auto& fields) {
    if (absl::Status s = CheckCount(fields, 6, "xa ya za xb yb zb", line); !s.ok()) return s;
    Position a, b;
    if (absl::Status s = ParsePosition(fields, 0, line, &a); !s.ok()) return s;
    if (absl::Status s = ParsePosition(fields, 3, line, &b); !s.ok()) return s;
    out.a.push_back(a);
    out.b.push_back(b);
    out.lines.push_back(line);
    return absl::OkStatus();
  });
  if (!status.ok()) return status;
  return out;
}

absl::StatusOr<ParsedPoints> ParsePoints(std::string_view text) {
  ParsedPoints out;
  absl::Status status = ForEachLine(text, [&](int64_t line, const auto& fields) {
    SurfacePoint p;
    if (absl::Status s = ParsePointsOfLine(fields, line, "f w0 w1 w2", {&p}); !s.ok()) return s;
    out.points.push_back(p);
    out.lines.push_back(line);
    return absl::OkStatus();
  });
  if (!status.ok()) return status;
  return out;
}

absl::StatusOr<ParsedPositions> ParsePositions(std::string_view text) {
  ParsedPositions out;
  absl::Status status = ForEachLine(text, [&](int64_t line, const auto& fields) {
    if (absl::Status s = CheckCount(fields, 3, "x y z", line); !s.ok()) return s;
    Position p;
    if (absl::Status s = ParsePosition(fields, 0, line, &p); !s.ok()) return s;
    out.positions.push_back(p);
    out.lines.push_back(line);
    return absl::OkStatus();
  });
  if (!status.ok()) return status;
  return out;
}

absl::Status CheckPoint(const SurfacePoint& p, int64_t num_faces, int64_t line) {
  if (p.vertex >= 0) return absl::OkStatus();  // the server checks it against the mesh
  if (p.face >= num_faces) {
    return absl::OutOfRangeError(absl::StrFormat(
        "line %d: face %d is past the end (the model has %d faces)", line, p.face, num_faces));
  }
  constexpr double kTolerance = 1e-6;
  for (double w : p.w) {
    if (w < -kTolerance) {
      return absl::InvalidArgumentError(
          absl::StrFormat("line %d: barycentric weights (%g, %g, %g) must not be negative", line,
                          p.w[0], p.w[1], p.w[2]));
    }
  }
  const double sum = p.w[0] + p.w[1] + p.w[2];
  if (std::abs(sum - 1.0) > kTolerance) {
    return absl::InvalidArgumentError(
        absl::StrFormat("line %d: barycentric weights (%g, %g, %g) sum to %.9g, not 1", line,
                        p.w[0], p.w[1], p.w[2], sum));
  }
  return absl::OkStatus();
}

std::string FormatDistance(double d) {
  if (std::isinf(d)) return "inf";
  char buffer[64];
  const auto [ptr, ec] = std::to_chars(buffer, buffer + sizeof(buffer), d);
  return std::string(buffer, ptr);
}

std::string FormatPairs(const std::vector<PointPair>& pairs) {
  std::string out;
  auto point = [&out](const SurfacePoint& p) {
    if (p.vertex >= 0) {
      absl::StrAppend(&out, "v ", p.vertex);
      return;
    }
    absl::StrAppend(&out, p.face);
    for (double w : p.w) absl::StrAppend(&out, " ", FormatDistance(w));
  };
  for (const PointPair& pair : pairs) {
    point(pair.a);
    out += ' ';
    point(pair.b);
    out += '\n';
  }
  return out;
}

absl::Status WriteFileOrStdout(const std::string& path, const std::string& contents) {
  if (path == "-") {
    if (std::fwrite(contents.data(), 1, contents.size(), stdout) != contents.size() ||
        std::fflush(stdout) != 0) {
      return absl::DataLossError("cannot write to standard output");
    }
    return absl::OkStatus();
  }
  // Written beside `path` and renamed over it, so that a reader (or a killed
  // run) never leaves half a file under the name asked for.
  const std::string tmp = absl::StrCat(path, ".tmp.", ::getpid());
  auto failed = [&](const char* what) {
    const std::string reason = std::strerror(errno);
    ::unlink(tmp.c_str());
    return absl::Status(errno == ENOSPC || errno == EDQUOT ? absl::StatusCode::kResourceExhausted
                                                           : absl::StatusCode::kPermissionDenied,
                        absl::StrCat("cannot ", what, " ", path, ": ", reason));
  };
  std::FILE* out = std::fopen(tmp.c_str(), "wb");
  if (out == nullptr) return failed("write");
  const bool written = std::fwrite(contents.data(), 1, contents.size(), out) == contents.size();
  if (!written || std::fflush(out) != 0) {
    const int err = errno;
    std::fclose(out);
    errno = err;
    return failed("write");
  }
  if (std::fclose(out) != 0) return failed("write");
  if (std::rename(tmp.c_str(), path.c_str()) != 0) return failed("replace");
  return absl::OkStatus();
}

}  // namespace geodex::client::cli
