#include "core/index/index_report.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <map>
#include <set>

#include "absl/strings/ascii.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"

namespace geodex::index {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The calibration's bins (core/validation/pair_sampling.h, the report's
// accuracy_*_<key> lines) and the target's p99 limit of each, in units of E
// (core/validation/target_error.h: 2E below 3L, 4E from 3L).
struct BinSpec {
  const char* key;
  const char* label;
  double from_l, to_l, limit_factor;
};
constexpr BinSpec kBins[4] = {{"below_L", "d < L", 0, 1, 2},
                              {"L_3L", "L-3L", 1, 3, 2},
                              {"3L_10L", "3L-10L", 3, 10, 4},
                              {"beyond_10L", ">= 10L", 10, kInf, 4}};

// Groups of sections, as a person thinks of the index.
struct SectionGroup {
  const char* key;
  const char* label;
  std::vector<SectionId> ids;
};
const std::vector<SectionGroup>& Groups() {
  static const auto* const groups = new std::vector<SectionGroup>{
      {"distance_matrix",
       "distance matrix",
       {SectionId::kSampleDistances, SectionId::kSampleDistancesLower,
        SectionId::kSampleDistancesCoded, SectionId::kDistanceCode}},
      {"mesh", "mesh", {SectionId::kPositions, SectionId::kFaces, SectionId::kTwins}},
      {"vertex_records", "vertex records", {SectionId::kVertexRecords, SectionId::kCompactVertexRecords}},
      {"triangles", "samples, triangles", {SectionId::kSamples, SectionId::kTriangles}},
      {"face_bvh", "face BVH", {SectionId::kFaceBvh, SectionId::kBvhFaces}},
      {"input_ids", "input ids", {SectionId::kInputFaces, SectionId::kVertexCopies}},
      {"split",
       "split",
       {SectionId::kCoarseFaces, SectionId::kSplitFaces, SectionId::kSplitCoarseFaces,
        SectionId::kSplitPieces, SectionId::kSplitFaceCodes, SectionId::kSplitPieceCodes}},
      {"calibration", "calibration", {SectionId::kAccuracy, SectionId::kSpreadBounds}},
      {"report", "build report", {SectionId::kReport}},
  };
  return *groups;
}

// The shortest decimal of `x`, read back as a double: every form of the
// report (this text, the JSON, the viewer reading the JSON) then starts from
// the same number.
double Tidy(float x) {
  char buffer[32];
  const auto end = std::to_chars(buffer, buffer + sizeof(buffer), x).ptr;
  return std::strtod(std::string(buffer, end).c_str(), nullptr);
}

std::string JsonNumber(double x) {
  if (!std::isfinite(x)) return "null";
  char buffer[32];
  const auto end = std::to_chars(buffer, buffer + sizeof(buffer), x).ptr;
  return std::string(buffer, end);
}

std::string JsonString(std::string_view s) {
  std::string out = "\"";
  for (const char c : s) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\t':
        out += "\\t";
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          absl::StrAppendFormat(&out, "\\u%04x", static_cast<int>(c));
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
}

const std::string* Find(const IndexReport& r, std::string_view key) {
  for (const auto& [k, v] : r.entries) {
    if (k == key) return &v;
  }
  return nullptr;
}

// The repairs made, one phrase each: the builder's summary
// ("0 non-manifold vertices split (0 copies), ..., 0 zero-area faces and 0
// slivers kept") without the phrases that count nothing.
std::string RepairsMade(const std::string* summary) {
  if (summary == nullptr) return "none recorded";
  std::vector<std::string> made;
  for (absl::string_view part : absl::StrSplit(*summary, ", ")) {
    for (absl::string_view phrase : absl::StrSplit(part, " and ")) {
      if (!absl::StartsWith(phrase, "0 ")) made.emplace_back(phrase);
    }
  }
  return made.empty() ? "none" : absl::StrJoin(made, ", ");
}

// The builder's repair_euler_samples (sample indices), placed on the mesh.
// The index's vertices are the file's, then the repair's copies, then the
// split's midpoints (r.vertices counts the file's).
void ReadEulerSamples(const Index& index, IndexReport& r) {
  const std::string* list = Find(r, "repair_euler_samples");
  if (list == nullptr) return;
  const std::span<const int32_t> samples = index.samples();
  const std::span<const double> positions = index.positions();
  const std::span<const int32_t> copies = index.vertex_copies();
  for (absl::string_view word : absl::StrSplit(*list, ' ', absl::SkipEmpty())) {
    int64_t a = 0;
    if (!absl::SimpleAtoi(word, &a) || a < 0 || a >= static_cast<int64_t>(samples.size())) continue;
    ++r.euler_samples;
    if (r.euler_sample_places.size() >= kReportedEulerSamples) continue;
    const int64_t v = samples[a];
    if (v < 0 || 3 * v + 2 >= static_cast<int64_t>(positions.size())) continue;
    PlacedSample p;
    p.sample = a;
    p.position = {positions[3 * v], positions[3 * v + 1], positions[3 * v + 2]};
    if (v < r.vertices) {
      p.vertex = v;
    } else if (v - r.vertices < static_cast<int64_t>(copies.size())) {
      p.copy = true;
      p.vertex = copies[v - r.vertices];
    } else {
      p.midpoint = true;
      p.vertex = -1;
    }
    r.euler_sample_places.push_back(p);
  }
}

// "vertex 12 (0.1, 0.2, 0.3)", "a copy of vertex 12 (...)", "a midpoint (...)".
std::string DescribePlace(const PlacedSample& p) {
  const std::string at =
      absl::StrFormat("(%.4g, %.4g, %.4g)", p.position[0], p.position[1], p.position[2]);
  if (p.midpoint) return absl::StrCat("a midpoint ", at);
  return absl::StrCat(p.copy ? "a copy of vertex " : "vertex ", p.vertex, " ", at);
}

// The fixed bands of the target (band_* lines of a format 4 build).
void ReadBands(IndexReport& r) {
  static const char* const kKeys[] = {"0_0.5", "0.5_1", "1_2", "2_4", "4_8", "8_16", "16_inf"};
  static const char* const kLabels[] = {"0-0.5", "0.5-1", "1-2", "2-4", "4-8", "8-16", ">=16"};
  const std::string* unit = Find(r, "band_unit");
  const std::string* below = Find(r, "band_refined_below");
  if (unit == nullptr || below == nullptr || !absl::SimpleAtod(*unit, &r.band_unit) ||
      !absl::SimpleAtod(*below, &r.refined_below)) {
    return;
  }
  for (int b = 0; b < 7; ++b) {
    ReportBand band;
    band.key = kKeys[b];
    band.label = kLabels[b];
    band.from = b == 0 ? 0 : std::ldexp(1.0, b - 2);
    band.to = b == 6 ? kInf : std::ldexp(1.0, b - 1);
    static const char* const kKind[2] = {"vertex", "interior"};
    for (int k = 0; k < 2; ++k) {
      const std::string* p99 = Find(r, absl::StrCat("band_p99_", kKind[k], "_", kKeys[b]));
      const std::string* pairs = Find(r, absl::StrCat("band_pairs_", kKind[k], "_", kKeys[b]));
      if (pairs == nullptr || !absl::SimpleAtoi(*pairs, &band.pairs[k])) band.pairs[k] = 0;
      if (p99 == nullptr || band.pairs[k] == 0 || !absl::SimpleAtod(*p99, &band.p99[k])) {
        band.p99[k] = kNaN;
      }
    }
    band.p99_limit = band.from >= 8 ? 4 * r.target_error : kNaN;
    band.answer = band.to <= r.refined_below    ? "walked or exact"
                  : band.from >= r.refined_below ? "O(1)"
                                                 : absl::StrFormat("walked or exact below %.3g, O(1) above",
                                                                   r.refined_below);
    r.bands.push_back(band);
  }
}

void ReadTarget(IndexReport& r) {
  const std::string* error = Find(r, "target_error");
  double target = 0;
  if (error != nullptr && absl::SimpleAtod(*error, &target) && target > 0) {
    r.target_asked = true;
    r.target_error = target;
    const std::string* reached = Find(r, "target_error_reached");
    r.target_met = reached != nullptr && *reached == "yes";
    if (reached != nullptr && absl::StartsWith(*reached, "no (") && absl::EndsWith(*reached, ")")) {
      r.target_stop = reached->substr(4, reached->size() - 5);
    }
    for (int k = 1;; ++k) {
      const std::string* round = Find(r, absl::StrCat("target_error_round_", k));
      int64_t m = 0;
      if (round == nullptr) break;
      absl::string_view text = *round;
      if (!absl::ConsumePrefix(&text, "m = ")) break;
      if (!absl::SimpleAtoi(text.substr(0, text.find(':')), &m)) break;
      r.target_rounds.push_back(m);
    }
    // "vertex 3L-10L p99 0.064817 of 0.02"
    if (const std::string* worst = Find(r, "target_error_worst"); worst != nullptr) {
      const size_t of = worst->rfind(" of ");
      const size_t space = of == std::string::npos ? of : worst->rfind(' ', of - 1);
      if (space != std::string::npos &&
          absl::SimpleAtod(worst->substr(space + 1, of - space - 1), &r.closest_upper95) &&
          absl::SimpleAtod(worst->substr(of + 4), &r.closest_limit)) {
        r.closest_check = worst->substr(0, space);
      }
    }
  }
  for (int b = 0; b < 4; ++b) r.bins[b].p99_limit = kBins[b].limit_factor * r.target_error;
}

// The judged checks (check_<key> = measured upper95 pairs), in
// core/validation/target_error.h's order and names.
void ReadChecks(IndexReport& r) {
  struct CheckSpec {
    const char* key;
    const char* label;
    double limit_factor;
  };
  static constexpr CheckSpec kChecks[3] = {{"uniform_rms", "uniform RMS", 1},
                                           {"vertex_far_p99", "vertex >=8 L1000 p99", 4},
                                           {"interior_far_p99", "interior >=8 L1000 p99", 4}};
  for (const CheckSpec& spec : kChecks) {
    const std::string* line = Find(r, absl::StrCat("check_", spec.key));
    if (line == nullptr) return;
    const std::vector<absl::string_view> words = absl::StrSplit(*line, ' ', absl::SkipEmpty());
    ReportCheck c;
    c.key = spec.key;
    c.label = spec.label;
    c.limit = spec.limit_factor * r.target_error;
    if (words.size() != 3 || !absl::SimpleAtod(words[0], &c.measured) ||
        !absl::SimpleAtod(words[1], &c.upper95) || !absl::SimpleAtoi(words[2], &c.pairs)) {
      r.checks.clear();
      return;
    }
    r.checks.push_back(c);
  }
}

// The fixed-m verdict's "over the limit" list: the judged checks over their
// limits, or for an index built before the checks were stored, the uniform
// RMS and the judged bands' measured p99s.
std::vector<std::string> OverTheLimit(const IndexReport& r) {
  std::vector<std::string> over;
  if (!r.checks.empty()) {
    for (const ReportCheck& c : r.checks) {
      if (c.pairs > 0 && c.upper95 > c.limit) {
        over.push_back(absl::StrFormat("the %s (95%% upper limit %s against %s)", c.label,
                                       FormatPercent(c.upper95), FormatPercent(c.limit)));
      }
    }
    return over;
  }
  if (r.uniform_rms > r.target_error) over.push_back("the uniform RMS");
  static const char* const kKind[2] = {"vertex", "interior"};
  for (const ReportBand& band : r.bands) {
    for (int k = 0; k < 2; ++k) {
      if (band.p99[k] > band.p99_limit) {
        over.push_back(absl::StrCat(kKind[k], " p99 at ", band.label, " L1000"));
      }
    }
  }
  return over;
}

std::string Verdict(const IndexReport& r) {
  if (r.target_asked) {
    const std::string rounds = absl::StrFormat("%d round%s (m = %s)", r.target_rounds.size(),
                                               r.target_rounds.size() == 1 ? "" : "s",
                                               absl::StrJoin(r.target_rounds, ", "));
    const std::string closest =
        r.closest_check.empty()
            ? ""
            : absl::StrFormat("%s, %s, has a 95%% upper limit of %s against %s",
                              r.target_met ? "; the closest check" : "; the furthest check",
                              r.closest_check, FormatPercent(r.closest_upper95),
                              FormatPercent(r.closest_limit));
    if (r.target_met) {
      return absl::StrFormat("%s met in %s%s", FormatPercent(r.target_error), rounds, closest);
    }
    return absl::StrFormat("%s NOT met: m stopped at %s after %s%s", FormatPercent(r.target_error),
                           r.target_stop.empty() ? "the builder's limit" : r.target_stop, rounds,
                           closest);
  }
  // Said without the tool's words: the same index comes from geodex-build
  // --samples and from Python's geodex.build(samples=).
  const std::string none =
      absl::StrFormat("none asked (a fixed m, %d requested)", r.requested_samples);
  if (!r.has_accuracy) return none + "; no calibration to compare with";
  const std::vector<std::string> over = OverTheLimit(r);
  return absl::StrFormat("%s; measured against the default target %s: %s", none,
                         FormatPercent(r.target_error),
                         over.empty() ? "every judged figure within its limit"
                                      : absl::StrCat(absl::StrJoin(over, ", "), " over the limit"));
}

// `text` broken between words into lines of at most `width` columns, the
// lines after the first indented by `indent` (which the first line's label
// takes).
std::string Wrap(const std::string& text, int indent, int width) {
  std::string out;
  int column = indent;
  for (absl::string_view word : absl::StrSplit(text, ' ')) {
    if (column > indent && column + 1 + static_cast<int>(word.size()) > width) {
      absl::StrAppend(&out, "\n", std::string(indent, ' '));
      column = indent;
    } else if (column > indent) {
      out += ' ';
      ++column;
    }
    absl::StrAppend(&out, word);
    column += static_cast<int>(word.size());
  }
  return out;
}

void ReadSections(const Index& index, IndexReport& r) {
  const FileHeader& h = index.header();
  const std::span<const uint8_t> image = index.image();
  std::map<uint32_t, uint64_t> by_id;
  std::set<uint32_t> present;
  uint64_t in_sections = 0;
  for (uint32_t i = 0; i < h.num_sections; ++i) {
    SectionEntry e;
    // Index::Open checked that the table lies inside the file.
    std::memcpy(&e, image.data() + h.section_table_offset + i * sizeof(SectionEntry), sizeof(e));
    by_id[e.id] += e.size;
    present.insert(e.id);
    in_sections += e.size;
  }
  for (const SectionGroup& g : Groups()) {
    uint64_t bytes = 0;
    for (const SectionId id : g.ids) bytes += by_id[static_cast<uint32_t>(id)];
    if (bytes > 0) r.sections.push_back({g.key, g.label, bytes});
  }
  if (r.bytes > in_sections) {
    r.sections.push_back({"header", "header, table, padding", r.bytes - in_sections});
  }
  if (h.format_major >= kDerivedFormatMajor) {
    if (!present.contains(static_cast<uint32_t>(SectionId::kTwins))) {
      r.derived_at_load.push_back("twins");
    }
    if (!present.contains(static_cast<uint32_t>(SectionId::kFaceBvh))) {
      r.derived_at_load.push_back("face BVH");
    }
  }
  std::stable_sort(
      r.sections.begin(), r.sections.end(),
      [](const ReportSection& a, const ReportSection& b) { return a.bytes > b.bytes; });
}

std::string ChecksJson(const std::vector<ReportCheck>& checks) {
  std::string out;
  for (size_t i = 0; i < checks.size(); ++i) {
    const ReportCheck& c = checks[i];
    absl::StrAppend(&out, i ? ",\n" : "\n", "      {\"key\": ", JsonString(c.key),
                    ", \"label\": ", JsonString(c.label),
                    ", \"measured\": ", JsonNumber(c.measured),
                    ", \"upper95\": ", JsonNumber(c.upper95), ", \"limit\": ", JsonNumber(c.limit),
                    ", \"pairs\": ", c.pairs, "}");
  }
  return checks.empty() ? out : out + "\n    ";
}

// The samples line: m and where it came from. A target build's m is the
// target's choice (a --samples or samples= given with a target is only its
// first round's m).
std::string SamplesText(const IndexReport& r) {
  const std::string repair =
      absl::StrFormat("%d added by the repair of the triangulation", r.samples_added_by_repair);
  if (r.target_asked && !r.target_rounds.empty()) {
    return absl::StrFormat("m = %d (chosen by the target; rounds m = %s), %s", r.samples,
                           absl::StrJoin(r.target_rounds, ", "), repair);
  }
  return absl::StrFormat("m = %d: %d requested, %s", r.samples, r.requested_samples, repair);
}

// The judged checks, one line each: measured, then the 95% upper limit the
// target judges and its limit.
std::string ChecksText(const IndexReport& r) {
  std::string out = "                judged by the target: measured (95% upper limit / limit)\n";
  for (const ReportCheck& c : r.checks) {
    absl::StrAppendFormat(
        &out, "                  %-24s %9s %s\n", c.label,
        c.pairs > 0 ? FormatPercent(c.measured) : std::string("no pairs"),
        c.pairs > 0 ? absl::StrFormat("(%s / %s)%s", FormatPercent(c.upper95),
                                      FormatPercent(c.limit), c.upper95 > c.limit ? "  over" : "")
                    : std::string("(not judged)"));
  }
  return out;
}

// The p99 by L1000 band, which bands the target judges, and where the
// default mode's answers change from walked to O(1): the one place the
// index's own L appears, since that split is set in it.
std::string BandsTableText(const IndexReport& r) {
  std::string out = absl::StrFormat("                  %-10s %9s %9s  %-8s  %s\n", "L1000",
                                    "vertex", "interior", "target", "answered");
  for (const ReportBand& b : r.bands) {
    absl::StrAppendFormat(&out, "                  %-10s %9s %9s  %-8s  %s\n", b.label,
                          FormatPercent(b.p99[0]), FormatPercent(b.p99[1]),
                          std::isnan(b.p99_limit) ? "-" : "judged", b.answer);
  }
  if (!r.checks.empty()) {
    out += ChecksText(r);
  } else {
    absl::StrAppendFormat(&out, "                area-uniform pairs: RMS %s (limit %s)\n",
                          FormatPercent(r.uniform_rms), FormatPercent(r.target_error));
  }
  const double refine_l =
      r.scale_length > 0 ? r.refined_below * r.band_unit / r.scale_length : kNaN;
  absl::StrAppendFormat(
      &out,
      "                L1000 = %.4g, the spacing of 1000 samples on this surface; the target\n"
      "                judges the p99 from 8 L1000 (vertex and interior pairs apart) and the\n"
      "                uniform RMS. Answers are walked or exact below %.3g L1000 (%.3g L,\n"
      "                where L = %.4g is this index's own sample spacing), O(1) above.\n",
      r.band_unit, r.refined_below, refine_l, r.scale_length);
  return out;
}

// The accuracy section of a calibrated index: p99 by L1000 band and the
// judged checks; an index without bands (format < 4) by its own L.
std::string AccuracyText(const IndexReport& r) {
  std::string out = absl::StrFormat(
      "  accuracy      relative error of the default answer over %d held-out pairs from %d "
      "sources; p99 by distance\n",
      r.accuracy_pairs, r.accuracy_sources);
  if (!r.bands.empty()) return out + BandsTableText(r);
  absl::StrAppendFormat(&out,
                        "                  %-10s %9s %9s   (L = %.4g, the index's sample "
                        "spacing; this index has no L1000 bands)\n",
                        "distance", "RMS", "p99", r.scale_length);
  for (const ReportBin& b : r.bins) {
    absl::StrAppendFormat(&out, "                  %-10s %9s %9s\n", b.label, FormatPercent(b.rms),
                          FormatPercent(b.p99));
  }
  absl::StrAppendFormat(&out, "                area-uniform pairs: RMS %s (limit %s)\n",
                        FormatPercent(r.uniform_rms), FormatPercent(r.target_error));
  return out;
}

}  // namespace

std::vector<std::pair<std::string, std::string>> ParseReportEntries(std::string_view text) {
  std::vector<std::pair<std::string, std::string>> out;
  std::map<std::string, size_t> at;
  for (absl::string_view line : absl::StrSplit(absl::string_view(text.data(), text.size()), '\n')) {
    const size_t eq = line.find('=');
    if (eq == absl::string_view::npos) continue;
    std::string key(absl::StripAsciiWhitespace(line.substr(0, eq)));
    if (key.empty()) continue;
    std::string value(absl::StripAsciiWhitespace(line.substr(eq + 1)));
    const auto [it, inserted] = at.emplace(key, out.size());
    if (inserted) {
      out.emplace_back(std::move(key), std::move(value));
    } else {
      out[it->second].second = std::move(value);
    }
  }
  return out;
}

IndexReport MakeIndexReport(const Index& index) {
  IndexReport r;
  const FileHeader& h = index.header();
  r.format = absl::StrFormat("%d.%d", h.format_major, h.format_minor);
  r.builder = index.builder_version();
  r.entries = ParseReportEntries(index.report());
  r.index_vertices = index.num_vertices();
  r.index_faces = index.num_faces();
  r.split_midpoints = index.split_vertices();
  // The mesh file's counts, as core/query/engine/input_ids.h reads them: the
  // midpoints and the copies of split vertices are the last vertices; faces
  // are the input records, else the faces before the split.
  r.vertices = r.index_vertices - r.split_midpoints -
               static_cast<int64_t>(index.vertex_copies().size());
  r.faces = !index.input_faces().empty()   ? static_cast<int64_t>(index.input_faces().size())
            : index.split().split() ? static_cast<int64_t>(index.split().num_coarse_faces())
                                    : r.index_faces;
  r.repairs = RepairsMade(Find(r, "mesh_repairs"));
  for (const auto& [key, value] : r.entries) {
    double count = 0;
    if (key != "mesh_repairs" && absl::StartsWith(key, "mesh_") && key != "mesh_split" &&
        key != "mesh_refinement" /* the split's line in files built before it was named so */ &&
        absl::SimpleAtod(value, &count)) {
      r.repair_counts.emplace_back(key.substr(5), count);
    }
  }
  r.requested_samples = h.params.requested_samples;
  r.samples = index.num_samples();
  r.samples_added_by_repair = h.params.samples_added_by_repair;
  if (const std::string* repair = Find(r, "repair"); repair != nullptr) r.sample_repair = *repair;
  ReadEulerSamples(index, r);
  r.triangles = index.num_triangles();
  r.bytes = index.size_bytes();
  ReadSections(index, r);
  r.error_bounds = index.accuracy() != nullptr;
  for (int b = 0; b < 4; ++b) {
    r.bins[b].key = kBins[b].key;
    r.bins[b].label = kBins[b].label;
    r.bins[b].from_l = kBins[b].from_l;
    r.bins[b].to_l = kBins[b].to_l;
    r.bins[b].rms = r.bins[b].p99 = kNaN;
  }
  r.uniform_rms = r.uniform_far_p99 = kNaN;
  if (const AccuracyRecord* a = index.accuracy(); a != nullptr) {
    r.has_accuracy = true;
    r.accuracy_sources = a->num_sources;
    r.accuracy_pairs = a->num_pairs;
    r.scale_length = Tidy(a->scale_length);
    r.uniform_rms = Tidy(a->uniform_rms);
    r.uniform_far_p99 = Tidy(a->uniform_far_p99);
    for (int b = 0; b < 4; ++b) {
      r.bins[b].rms = Tidy(a->rms[b]);
      r.bins[b].p99 = Tidy(a->p99[b]);
    }
  }
  ReadTarget(r);
  ReadChecks(r);
  ReadBands(r);
  r.target_verdict = Verdict(r);
  return r;
}

std::string FormatPercent(double fraction) {
  if (std::isnan(fraction)) return "n/a";
  const double v = 100 * fraction;
  if (v == 0) return "0%";
  if (v < 0.001) return "<0.001%";
  const int decimals = v >= 100 ? 0 : v >= 10 ? 1 : v >= 1 ? 2 : v >= 0.1 ? 3 : v >= 0.01 ? 4 : 5;
  return absl::StrFormat("%.*f%%", decimals, v);
}

std::string FormatMiB(uint64_t bytes) {
  const double mib = static_cast<double>(bytes) / 1048576.0;
  // Two literal formats: StrFormat checks its format at compile time.
  if (mib >= 0.1 || bytes == 0) return absl::StrFormat("%.2f MiB", mib);
  return absl::StrFormat("%.3f MiB", mib);
}

std::string IndexReportText(const IndexReport& r, std::string_view title) {
  std::string out =
      absl::StrFormat("%s: geodex index, format %s, built by %s\n", title, r.format, r.builder);
  absl::StrAppendFormat(&out, "  mesh          %d vertices, %d faces", r.vertices, r.faces);
  if (r.index_vertices != r.vertices || r.index_faces != r.faces) {
    absl::StrAppendFormat(&out, " (answered on %d vertices, %d faces)", r.index_vertices,
                          r.index_faces);
  }
  absl::StrAppendFormat(&out, "\n  repairs       %s\n", r.repairs);
  absl::StrAppendFormat(
      &out, "  split         %s\n",
      r.split_midpoints == 0
          ? std::string("none (no edge longer than half the sample spacing)")
          : absl::StrFormat("%d midpoints (long edges split flat)", r.split_midpoints));
  absl::StrAppendFormat(&out, "  samples       %s\n", Wrap(SamplesText(r), 16, 100));
  if (r.euler_samples > 0) {
    std::vector<std::string> places;
    for (const PlacedSample& p : r.euler_sample_places) places.push_back(DescribePlace(p));
    if (r.euler_samples > static_cast<int64_t>(places.size())) places.push_back("...");
    absl::StrAppendFormat(&out,
                          "                %d of them for the topology the samples missed, at %s\n",
                          r.euler_samples, absl::StrJoin(places, ", "));
  }
  absl::StrAppendFormat(&out, "  triangles     %d geodesic triangles\n", r.triangles);
  absl::StrAppendFormat(&out, "  size          %s\n", FormatMiB(r.bytes));
  for (const ReportSection& s : r.sections) {
    const double share = 100.0 * static_cast<double>(s.bytes) / r.bytes;
    absl::StrAppendFormat(&out, "                  %-24s %10s %6s\n", s.label, FormatMiB(s.bytes),
                          share < 0.05 ? "<0.1%" : absl::StrFormat("%.1f%%", share));
  }
  if (!r.derived_at_load.empty()) {
    absl::StrAppendFormat(&out, "                  %s: not stored, derived at load\n",
                          absl::StrJoin(r.derived_at_load, ", "));
  }
  absl::StrAppendFormat(
      &out, "  error bounds  %s\n",
      r.error_bounds ? "yes (calibrated)" : "no (geodex-build calibrate adds them)");
  absl::StrAppendFormat(&out, "  error target  %s\n", Wrap(r.target_verdict, 16, 100));
  if (r.has_accuracy) out += AccuracyText(r);
  return out;
}

namespace {

// The input mesh, the mesh indexed and its repairs.
void AppendMeshJson(const IndexReport& r, std::string* out) {
  absl::StrAppend(out, "  \"mesh\": {\n    \"vertices\": ", r.vertices,
                  ",\n    \"faces\": ", r.faces, ",\n    \"index_vertices\": ", r.index_vertices,
                  ",\n    \"index_faces\": ", r.index_faces,
                  ",\n    \"split_midpoints\": ", r.split_midpoints,
                  ",\n    \"repairs\": ", JsonString(r.repairs), ",\n    \"repair_counts\": {");
  for (size_t i = 0; i < r.repair_counts.size(); ++i) {
    absl::StrAppend(out, i ? ", " : "", JsonString(r.repair_counts[i].first), ": ",
                    JsonNumber(r.repair_counts[i].second));
  }
  absl::StrAppend(out, "}\n  },\n");
}

// The samples asked for and made, and those added for the topology.
void AppendSamplesJson(const IndexReport& r, std::string* out) {
  absl::StrAppend(out, "  \"samples\": {\"requested\": ", r.requested_samples,
                  ", \"final\": ", r.samples, ", \"added_by_repair\": ", r.samples_added_by_repair,
                  ", \"repair\": ", JsonString(r.sample_repair),
                  ", \"added_for_topology\": ", r.euler_samples, ", \"topology_places\": [");
  for (size_t i = 0; i < r.euler_sample_places.size(); ++i) {
    const PlacedSample& p = r.euler_sample_places[i];
    absl::StrAppend(out, i ? ", " : "", "{\"sample\": ", p.sample,
                    ", \"vertex\": ", p.midpoint ? std::string("null") : absl::StrCat(p.vertex),
                    ", \"copy\": ", p.copy ? "true" : "false", ", \"position\": [",
                    JsonNumber(p.position[0]), ", ", JsonNumber(p.position[1]), ", ",
                    JsonNumber(p.position[2]), "]}");
  }
  absl::StrAppend(out, "]},\n");
}

// The file's size by section, and what the reader derives.
void AppendSizeJson(const IndexReport& r, std::string* out) {
  absl::StrAppend(out, "  \"size\": {\"bytes\": ", r.bytes, ", \"sections\": [");
  for (size_t i = 0; i < r.sections.size(); ++i) {
    absl::StrAppend(out, i ? ",\n" : "\n", "    {\"key\": ", JsonString(r.sections[i].key),
                    ", \"label\": ", JsonString(r.sections[i].label),
                    ", \"bytes\": ", r.sections[i].bytes, "}");
  }
  absl::StrAppend(out, "], \"derived_at_load\": [");
  for (size_t i = 0; i < r.derived_at_load.size(); ++i) {
    absl::StrAppend(out, i ? ", " : "", JsonString(r.derived_at_load[i]));
  }
  absl::StrAppend(out, "]},\n");
}

// The target error and how the rounds went.
void AppendTargetJson(const IndexReport& r, std::string* out) {
  absl::StrAppend(
      out, "  \"target\": {\n    \"error\": ", JsonNumber(r.target_error),
      ",\n    \"asked\": ", r.target_asked ? "true" : "false",
      ",\n    \"met\": ", r.target_asked ? (r.target_met ? "true" : "false") : "null",
      ",\n    \"stop\": ", JsonString(r.target_stop), ",\n    \"rounds\": [",
      absl::StrJoin(r.target_rounds, ", "),
      "],\n    \"closest_check\": ", JsonString(r.closest_check), ",\n    \"closest_upper95\": ",
      r.closest_check.empty() ? "null" : JsonNumber(r.closest_upper95),
      ",\n    \"closest_limit\": ", r.closest_check.empty() ? "null" : JsonNumber(r.closest_limit),
      ",\n    \"checks\": [", ChecksJson(r.checks), "]",
      ",\n    \"verdict\": ", JsonString(r.target_verdict), "\n  },\n");
}

// The calibration's figures by scale bin and fixed band; null without one.
void AppendAccuracyJson(const IndexReport& r, std::string* out) {
  if (!r.has_accuracy) {
    absl::StrAppend(out, "  \"accuracy\": null,\n");
    return;
  }
  absl::StrAppend(out, "  \"accuracy\": {\n    \"sources\": ", r.accuracy_sources,
                  ",\n    \"pairs\": ", r.accuracy_pairs,
                  ",\n    \"scale_length\": ", JsonNumber(r.scale_length),
                  ",\n    \"uniform_rms\": ", JsonNumber(r.uniform_rms),
                  ",\n    \"uniform_far_p99\": ", JsonNumber(r.uniform_far_p99),
                  ",\n    \"bins\": [");
  for (size_t b = 0; b < r.bins.size(); ++b) {
    const ReportBin& bin = r.bins[b];
    absl::StrAppend(out, b ? ",\n" : "\n", "      {\"key\": ", JsonString(bin.key),
                    ", \"label\": ", JsonString(bin.label),
                    ", \"from_L\": ", JsonNumber(bin.from_l), ", \"to_L\": ", JsonNumber(bin.to_l),
                    ", \"rms\": ", JsonNumber(bin.rms), ", \"p99\": ", JsonNumber(bin.p99),
                    ", \"p99_limit\": ", JsonNumber(bin.p99_limit), "}");
  }
  absl::StrAppend(
      out, "\n    ],\n    \"band_unit\": ", r.bands.empty() ? "null" : JsonNumber(r.band_unit),
      ",\n    \"refined_below\": ", r.bands.empty() ? "null" : JsonNumber(r.refined_below),
      ",\n    \"bands\": [");
  for (size_t b = 0; b < r.bands.size(); ++b) {
    const ReportBand& band = r.bands[b];
    absl::StrAppend(
        out, b ? ",\n" : "\n", "      {\"key\": ", JsonString(band.key),
        ", \"label\": ", JsonString(band.label), ", \"from\": ", JsonNumber(band.from),
        ", \"to\": ", JsonNumber(band.to), ", \"p99_vertex\": ", JsonNumber(band.p99[0]),
        ", \"p99_interior\": ", JsonNumber(band.p99[1]), ", \"pairs_vertex\": ", band.pairs[0],
        ", \"pairs_interior\": ", band.pairs[1], ", \"p99_limit\": ", JsonNumber(band.p99_limit),
        ", \"answer\": ", JsonString(band.answer), "}");
  }
  absl::StrAppend(out, r.bands.empty() ? "]\n  },\n" : "\n    ]\n  },\n");
}

// The build report's entries, and the closing brace of the document.
void AppendBuildReportJson(const IndexReport& r, std::string* out) {
  absl::StrAppend(out, "  \"build_report\": {");
  for (size_t i = 0; i < r.entries.size(); ++i) {
    absl::StrAppend(out, i ? ",\n" : "\n", "    ", JsonString(r.entries[i].first), ": ",
                    JsonString(r.entries[i].second));
  }
  absl::StrAppend(out, r.entries.empty() ? "}\n" : "\n  }\n", "}\n");
}

}  // namespace

std::string IndexReportJson(const IndexReport& r) {
  std::string out = "{\n";
  absl::StrAppend(&out, "  \"format\": ", JsonString(r.format), ",\n");
  absl::StrAppend(&out, "  \"builder\": ", JsonString(r.builder), ",\n");
  AppendMeshJson(r, &out);
  AppendSamplesJson(r, &out);
  absl::StrAppend(&out, "  \"triangles\": ", r.triangles, ",\n");
  AppendSizeJson(r, &out);
  absl::StrAppend(&out, "  \"error_bounds\": ", r.error_bounds ? "true" : "false", ",\n");
  AppendTargetJson(r, &out);
  AppendAccuracyJson(r, &out);
  AppendBuildReportJson(r, &out);
  return out;
}

}  // namespace geodex::index
