// STL reader (mesh_io.h): ASCII and binary, corners welded (mesh_weld.h).

#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "core/common/status_macros.h"
#include "core/mesh/mesh_io.h"
#include "core/mesh/mesh_io_text.h"
#include "core/mesh/mesh_weld.h"

namespace geodex::mesh {
namespace {

using io_internal::LineError;
using io_internal::ParseDouble;
using io_internal::Quote;

constexpr size_t kBinaryHeaderBytes = 84;    // 80 free bytes, then the uint32 count
constexpr size_t kBinaryTriangleBytes = 50;  // normal, 3 corners (float32), uint16

uint32_t LittleEndianU32(const char* p) {
  const auto* b = reinterpret_cast<const unsigned char*>(p);
  return static_cast<uint32_t>(b[0]) | static_cast<uint32_t>(b[1]) << 8 |
         static_cast<uint32_t>(b[2]) << 16 | static_cast<uint32_t>(b[3]) << 24;
}

float LittleEndianF32(const char* p) {
  const uint32_t bits = LittleEndianU32(p);
  float value;
  std::memcpy(&value, &bits, sizeof(value));
  return value;
}

// Keywords are case-insensitive (writers differ).
bool Is(std::string_view word, std::string_view keyword) {
  if (word.size() != keyword.size()) return false;
  for (size_t i = 0; i < word.size(); ++i) {
    const char c =
        word[i] >= 'A' && word[i] <= 'Z' ? static_cast<char>(word[i] - 'A' + 'a') : word[i];
    if (c != keyword[i]) return false;
  }
  return true;
}

bool IsSpace(char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v';
}

// True when the text begins (after white space) with the word "solid" and
// its first bytes are text: an ASCII STL. A binary file's free header may
// also begin with "solid" (some exporters write it), so the binary size
// test comes first.
bool LooksAscii(std::string_view contents) {
  size_t i = 0;
  while (i < contents.size() && IsSpace(contents[i])) ++i;
  if (!Is(contents.substr(i, 5), "solid")) return false;
  if (i + 5 < contents.size() && !IsSpace(contents[i + 5])) return false;
  for (size_t k = 0; k < contents.size() && k < 1024; ++k) {
    const unsigned char c = static_cast<unsigned char>(contents[k]);
    if (c < 0x20 && !IsSpace(static_cast<char>(c))) return false;
  }
  return true;
}

absl::StatusOr<std::vector<Vec3>> ParseBinary(std::string_view contents, const std::string& name) {
  if (contents.size() < kBinaryHeaderBytes) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "%s: not an STL file: %d bytes, shorter than a binary STL's 84-byte header, and not "
        "ASCII STL (which starts with 'solid')",
        name, contents.size()));
  }
  const uint64_t count = LittleEndianU32(contents.data() + 80);
  const uint64_t expected = kBinaryHeaderBytes + kBinaryTriangleBytes * count;
  if (contents.size() != expected) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "%s: binary STL: the header counts %d triangles (%d bytes) but the file has %d bytes "
        "(%s)",
        name, count, expected, contents.size(),
        contents.size() < expected ? "truncated, or a wrong count" : "a wrong count, or not STL"));
  }
  std::vector<Vec3> corners(3 * count);
  for (uint64_t t = 0; t < count; ++t) {
    const char* record = contents.data() + kBinaryHeaderBytes + kBinaryTriangleBytes * t;
    for (int c = 0; c < 3; ++c) {
      Vec3& p = corners[3 * t + c];
      for (int i = 0; i < 3; ++i) p[i] = LittleEndianF32(record + 12 + 12 * c + 4 * i);
      if (!p.allFinite()) {
        return absl::InvalidArgumentError(
            absl::StrFormat("%s: binary STL: triangle %d corner %d has a non-finite coordinate "
                            "(%g, %g, %g)",
                            name, t, c, p.x(), p.y(), p.z()));
      }
    }
  }
  return corners;
}

// White-space separated words with their line numbers.
class WordReader {
 public:
  explicit WordReader(std::string_view text) : text_(text) {}

  // The next word, empty at the end of the text.
  std::string_view Next() {
    while (pos_ < text_.size() && IsSpace(text_[pos_])) {
      if (text_[pos_] == '\n') ++line_;
      ++pos_;
    }
    word_line_ = line_;
    const size_t begin = pos_;
    while (pos_ < text_.size() && !IsSpace(text_[pos_])) ++pos_;
    return text_.substr(begin, pos_ - begin);
  }
  // Skips the rest of the current line (a solid's name).
  void SkipLine() {
    while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
  }
  // The line of the word Next() returned last.
  int64_t line() const { return word_line_; }

 private:
  std::string_view text_;
  size_t pos_ = 0;
  int64_t line_ = 1;
  int64_t word_line_ = 1;
};

// The next word, `word` (`what` says where in the facet it belongs).
absl::Status Expect(WordReader& words, const std::string& name, std::string_view word,
                    std::string_view what) {
  const std::string_view got = words.Next();
  if (Is(got, word)) return absl::OkStatus();
  return LineError(name, words.line(),
                   got.empty() ? absl::StrCat("file ends where '", std::string(word), "' ",
                                              std::string(what), " was expected (truncated?)")
                               : absl::StrCat("expected '", std::string(word), "' ",
                                              std::string(what), ", found ", Quote(got)));
}

// The three coordinates after 'vertex'.
absl::StatusOr<Vec3> ParseAsciiVertex(WordReader& words, const std::string& name) {
  Vec3 p;
  for (int i = 0; i < 3; ++i) {
    const std::string_view x = words.Next();
    if (!ParseDouble(x, &p[i])) {
      return LineError(name, words.line(),
                       x.empty() ? std::string("file ends inside a facet (truncated?)")
                                 : absl::StrCat("coordinate ", Quote(x), " is not a number"));
    }
    if (!std::isfinite(p[i])) {
      return LineError(name, words.line(), absl::StrCat("coordinate ", Quote(x), " is not finite"));
    }
  }
  return p;
}

// Facet number `facet` after its 'facet' keyword, up to its 'endfacet';
// appends its three corners to `corners`.
absl::Status ParseAsciiFacet(WordReader& words, const std::string& name, int64_t facet,
                             std::vector<Vec3>& corners) {
  // "facet normal nx ny nz": the normal is not used (the corners' order
  // says the orientation), and some writers leave it out.
  std::string_view next = words.Next();
  if (Is(next, "normal")) {
    for (int i = 0; i < 3; ++i) {
      double unused;
      const std::string_view n = words.Next();
      if (!ParseDouble(n, &unused)) {
        return LineError(
            name, words.line(),
            absl::StrCat("facet ", facet, ": normal component ", Quote(n), " is not a number"));
      }
    }
    next = words.Next();
  }
  if (!Is(next, "outer")) {
    return LineError(name, words.line(),
                     next.empty() ? std::string("file ends inside a facet (truncated?)")
                                  : absl::StrCat("facet ", facet, ": expected 'outer loop', found ",
                                                 Quote(next)));
  }
  GEODEX_RETURN_IF_ERROR(Expect(words, name, "loop", "(after 'outer')"));
  int vertices = 0;
  for (;;) {
    const std::string_view v = words.Next();
    if (Is(v, "endloop")) break;
    if (!Is(v, "vertex")) {
      return LineError(name, words.line(),
                       v.empty()
                           ? std::string("file ends inside a facet (truncated?)")
                           : absl::StrCat("facet ", facet,
                                          ": expected 'vertex' or 'endloop', found ", Quote(v)));
    }
    GEODEX_ASSIGN_OR_RETURN(const Vec3 p, ParseAsciiVertex(words, name));
    if (++vertices <= 3) corners.push_back(p);
  }
  if (vertices != 3) {
    return LineError(
        name, words.line(),
        absl::StrFormat("facet %d has %d vertices (STL facets are triangles)", facet, vertices));
  }
  return Expect(words, name, "endfacet", "(after 'endloop')");
}

absl::StatusOr<std::vector<Vec3>> ParseAscii(std::string_view contents, const std::string& name) {
  WordReader words(contents);
  std::vector<Vec3> corners;
  int64_t facet = 0;
  bool in_solid = false;
  for (;;) {
    const std::string_view word = words.Next();
    if (word.empty()) {
      if (in_solid) {
        return LineError(name, words.line(), "file ends before 'endsolid' (truncated?)");
      }
      break;
    }
    if (!in_solid) {
      if (!Is(word, "solid")) {
        return LineError(name, words.line(), absl::StrCat("expected 'solid', found ", Quote(word)));
      }
      words.SkipLine();  // the solid's name
      in_solid = true;
      continue;
    }
    if (Is(word, "endsolid")) {
      words.SkipLine();
      in_solid = false;
      continue;
    }
    if (!Is(word, "facet")) {
      return LineError(name, words.line(),
                       absl::StrCat("expected 'facet' or 'endsolid', found ", Quote(word)));
    }
    GEODEX_RETURN_IF_ERROR(ParseAsciiFacet(words, name, facet, corners));
    ++facet;
  }
  return corners;
}

}  // namespace

absl::StatusOr<RawMesh> ParseStlTriangles(std::string_view contents, const std::string& name,
                                          const ReadOptions& options) {
  GEODEX_RETURN_IF_ERROR(ValidateWeldTolerance(options.weld_tolerance));
  bool binary = false;
  if (contents.size() >= kBinaryHeaderBytes) {
    const uint64_t count = LittleEndianU32(contents.data() + 80);
    binary = contents.size() == kBinaryHeaderBytes + kBinaryTriangleBytes * count;
  }
  if (!binary) binary = !LooksAscii(contents);
  GEODEX_ASSIGN_OR_RETURN(const std::vector<Vec3> corners,
                          binary ? ParseBinary(contents, name) : ParseAscii(contents, name));
  return io_internal::WeldCorners(corners, options, name);
}

}  // namespace geodex::mesh
