#include "client/cli/model_report.h"

#include <cmath>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "google/protobuf/struct.pb.h"
#include "google/protobuf/util/json_util.h"

namespace geodex::client::cli {
namespace {

using google::protobuf::Struct;
using google::protobuf::Value;

// Reads fields of the report's JSON; a missing or mistyped field sets `ok`
// false (and reads as 0, "" or an empty object), so that one check at the
// end refuses a malformed report.
class Fields {
 public:
  const Value& Get(const Struct& s, const std::string& key) {
    const auto it = s.fields().find(key);
    if (it == s.fields().end()) {
      ok = false;
      return Value::default_instance();
    }
    return it->second;
  }
  double Num(const Struct& s, const std::string& key) {
    const Value& v = Get(s, key);
    if (v.kind_case() == Value::kNullValue) return NAN;
    if (v.kind_case() != Value::kNumberValue) ok = false;
    return v.number_value();
  }
  int64_t Int(const Struct& s, const std::string& key) {
    return static_cast<int64_t>(std::llround(Num(s, key)));
  }
  std::string Str(const Struct& s, const std::string& key) {
    const Value& v = Get(s, key);
    if (v.kind_case() != Value::kStringValue) ok = false;
    return v.string_value();
  }
  bool Bool(const Struct& s, const std::string& key) {
    const Value& v = Get(s, key);
    if (v.kind_case() != Value::kBoolValue) ok = false;
    return v.bool_value();
  }
  const Struct& Obj(const Struct& s, const std::string& key) {
    const Value& v = Get(s, key);
    if (v.kind_case() != Value::kStructValue) ok = false;
    return v.struct_value();
  }
  std::vector<const Struct*> List(const Struct& s, const std::string& key) {
    const Value& v = Get(s, key);
    if (v.kind_case() != Value::kListValue) ok = false;
    std::vector<const Struct*> out;
    for (const Value& e : v.list_value().values()) {
      if (e.kind_case() != Value::kStructValue) ok = false;
      out.push_back(&e.struct_value());
    }
    return out;
  }
  bool ok = true;
};

std::string FormatMiB(double bytes) {
  const double mib = bytes / 1048576.0;
  // Two literal formats: StrFormat checks its format at compile time.
  if (mib >= 0.1 || bytes == 0) return absl::StrFormat("%.2f MiB", mib);
  return absl::StrFormat("%.3f MiB", mib);
}

// `text` broken between words into lines of at most `width` columns, the
// lines after the first indented by `indent`.
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

std::string Title(const ModelInfo& m) {
  return absl::StrFormat("model %s, version %d (%s)", m.name, m.version, StateName(m.state));
}

// A model without the report's JSON: what ModelInfo has.
std::string PlainReport(const ModelInfo& m) {
  std::string out = absl::StrCat(Title(m), m.reason.empty() ? "" : ": " + m.reason, "\n");
  if (m.state != ModelInfo::State::kServing) return out;
  absl::StrAppendFormat(&out, "  mesh          %d vertices, %d faces\n", m.num_vertices,
                        m.num_faces);
  absl::StrAppendFormat(&out, "  samples       m = %d: %d requested\n", m.num_samples,
                        m.requested_samples);
  absl::StrAppendFormat(&out, "  triangles     %d geodesic triangles\n", m.num_triangles);
  for (const auto& [key, value] : m.build_report) {
    absl::StrAppendFormat(&out, "  %s = %s\n", key, value);
  }
  return out;
}

// The samples line, as core/index/index_report.cc says it: a target
// build's m is the target's choice.
std::string SamplesText(Fields& f, const Struct& samples, const Struct& target) {
  const std::string repair = absl::StrFormat("%d added by the repair of the triangulation",
                                             f.Int(samples, "added_by_repair"));
  std::vector<int64_t> rounds;
  const Value& list = f.Get(target, "rounds");
  for (const Value& v : list.list_value().values()) {
    rounds.push_back(std::llround(v.number_value()));
  }
  if (f.Bool(target, "asked") && !rounds.empty()) {
    return absl::StrFormat("m = %d (chosen by the target; rounds m = %s), %s",
                           f.Int(samples, "final"), absl::StrJoin(rounds, ", "), repair);
  }
  return absl::StrFormat("m = %d: %d requested, %s", f.Int(samples, "final"),
                         f.Int(samples, "requested"), repair);
}

// The judged checks (reports since they were stored; none before).
std::string ChecksText(Fields& f, const Struct& target) {
  if (!target.fields().contains("checks")) return "";
  const std::vector<const Struct*> checks = f.List(target, "checks");
  if (checks.empty()) return "";
  std::string out = "                judged by the target: measured (95% upper limit / limit)\n";
  for (const Struct* c : checks) {
    const double upper = f.Num(*c, "upper95"), limit = f.Num(*c, "limit");
    absl::StrAppendFormat(
        &out, "                  %-24s %9s %s\n", f.Str(*c, "label"),
        f.Int(*c, "pairs") > 0 ? FormatPercent(f.Num(*c, "measured")) : std::string("no pairs"),
        f.Int(*c, "pairs") > 0
            ? absl::StrFormat("(%s / %s)%s", FormatPercent(upper), FormatPercent(limit),
                              upper > limit ? "  over" : "")
            : std::string("(not judged)"));
  }
  return out;
}

// The accuracy section: p99 by L1000 band, which bands the target judges,
// the judged checks, and the one mention of the index's own L, where it
// sets the walked / O(1) split; a report without bands by the bins of L.
std::string AccuracyText(Fields& f, const Struct& a, const Struct& target) {
  std::string out = absl::StrFormat(
      "  accuracy      relative error of the default answer over %d held-out pairs from %d "
      "sources; p99 by distance\n",
      f.Int(a, "pairs"), f.Int(a, "sources"));
  const double scale = f.Num(a, "scale_length");
  // The fixed L1000 bands: in reports since format 4.0, empty or absent before.
  const std::vector<const Struct*> bands =
      a.fields().contains("bands") ? f.List(a, "bands") : std::vector<const Struct*>();
  if (bands.empty()) {
    absl::StrAppendFormat(&out,
                          "                  %-10s %9s %9s   (L = %.4g, the index's sample "
                          "spacing; this index has no L1000 bands)\n",
                          "distance", "RMS", "p99", scale);
    for (const Struct* b : f.List(a, "bins")) {
      absl::StrAppendFormat(&out, "                  %-10s %9s %9s\n", f.Str(*b, "label"),
                            FormatPercent(f.Num(*b, "rms")), FormatPercent(f.Num(*b, "p99")));
    }
    return out + absl::StrFormat("                area-uniform pairs: RMS %s (limit %s)\n",
                                 FormatPercent(f.Num(a, "uniform_rms")),
                                 FormatPercent(f.Num(target, "error")));
  }
  absl::StrAppendFormat(&out, "                  %-10s %9s %9s  %-8s  %s\n", "L1000", "vertex",
                        "interior", "target", "answered");
  for (const Struct* b : bands) {
    absl::StrAppendFormat(&out, "                  %-10s %9s %9s  %-8s  %s\n", f.Str(*b, "label"),
                          FormatPercent(f.Num(*b, "p99_vertex")),
                          FormatPercent(f.Num(*b, "p99_interior")),
                          std::isnan(f.Num(*b, "p99_limit")) ? "-" : "judged", f.Str(*b, "answer"));
  }
  const std::string checks = ChecksText(f, target);
  out += !checks.empty()
             ? checks
             : absl::StrFormat("                area-uniform pairs: RMS %s (limit %s)\n",
                               FormatPercent(f.Num(a, "uniform_rms")),
                               FormatPercent(f.Num(target, "error")));
  const double unit = f.Num(a, "band_unit"), below = f.Num(a, "refined_below");
  absl::StrAppendFormat(
      &out,
      "                L1000 = %.4g, the spacing of 1000 samples on this surface; the target\n"
      "                judges the p99 from 8 L1000 (vertex and interior pairs apart) and the\n"
      "                uniform RMS. Answers are walked or exact below %.3g L1000 (%.3g L,\n"
      "                where L = %.4g is this index's own sample spacing), O(1) above.\n",
      unit, below, scale > 0 ? below * unit / scale : NAN, scale);
  return out;
}

}  // namespace

std::string FormatPercent(double fraction) {
  if (std::isnan(fraction)) return "n/a";
  const double v = 100 * fraction;
  if (v == 0) return "0%";
  if (v < 0.001) return "<0.001%";
  const int decimals = v >= 100 ? 0 : v >= 10 ? 1 : v >= 1 ? 2 : v >= 0.1 ? 3 : v >= 0.01 ? 4 : 5;
  return absl::StrFormat("%.*f%%", decimals, v);
}

absl::StatusOr<std::string> ModelReportText(const ModelInfo& m) {
  if (m.report_json.empty()) return PlainReport(m);
  Struct r;
  if (!google::protobuf::util::JsonStringToMessage(m.report_json, &r).ok()) {
    return absl::InvalidArgumentError("the server's build report is not a JSON object");
  }
  Fields f;
  const Struct& mesh = f.Obj(r, "mesh");
  const Struct& samples = f.Obj(r, "samples");
  const Struct& size = f.Obj(r, "size");
  const Struct& target = f.Obj(r, "target");
  std::string out = absl::StrFormat("%s: geodex index, format %s, built by %s\n", Title(m),
                                    f.Str(r, "format"), f.Str(r, "builder"));
  const int64_t vertices = f.Int(mesh, "vertices"), faces = f.Int(mesh, "faces");
  const int64_t index_vertices = f.Int(mesh, "index_vertices");
  const int64_t index_faces = f.Int(mesh, "index_faces");
  absl::StrAppendFormat(&out, "  mesh          %d vertices, %d faces", vertices, faces);
  if (index_vertices != vertices || index_faces != faces) {
    absl::StrAppendFormat(&out, " (answered on %d vertices, %d faces)", index_vertices,
                          index_faces);
  }
  absl::StrAppendFormat(&out, "\n  repairs       %s\n", f.Str(mesh, "repairs"));
  const int64_t midpoints = f.Int(mesh, "split_midpoints");
  absl::StrAppendFormat(&out, "  split         %s\n",
                        midpoints == 0
                            ? std::string("none (no edge longer than half the sample spacing)")
                            : absl::StrFormat("%d midpoints (long edges split flat)", midpoints));
  absl::StrAppendFormat(&out, "  samples       %s\n",
                        Wrap(SamplesText(f, samples, target), 16, 100));
  absl::StrAppendFormat(&out, "  triangles     %d geodesic triangles\n", f.Int(r, "triangles"));
  const double bytes = f.Num(size, "bytes");
  absl::StrAppendFormat(&out, "  size          %s\n", FormatMiB(bytes));
  for (const Struct* s : f.List(size, "sections")) {
    const double section = f.Num(*s, "bytes");
    const double share = 100.0 * section / bytes;
    absl::StrAppendFormat(&out, "                  %-24s %10s %6s\n", f.Str(*s, "label"),
                          FormatMiB(section),
                          share < 0.05 ? "<0.1%" : absl::StrFormat("%.1f%%", share));
  }
  // Since format 6.0; an older server's report has no such list.
  if (size.fields().contains("derived_at_load")) {
    std::vector<std::string> derived;
    const Value& list = f.Get(size, "derived_at_load");
    if (list.kind_case() != Value::kListValue) f.ok = false;
    for (const Value& v : list.list_value().values()) {
      if (v.kind_case() != Value::kStringValue) f.ok = false;
      derived.push_back(v.string_value());
    }
    if (!derived.empty()) {
      absl::StrAppendFormat(&out, "                  %s: not stored, derived at load\n",
                            absl::StrJoin(derived, ", "));
    }
  }
  absl::StrAppendFormat(
      &out, "  error bounds  %s\n",
      f.Bool(r, "error_bounds") ? "yes (calibrated)" : "no (geodex-build calibrate adds them)");
  absl::StrAppendFormat(&out, "  error target  %s\n", Wrap(f.Str(target, "verdict"), 16, 100));
  const Value& accuracy_value = f.Get(r, "accuracy");
  if (accuracy_value.kind_case() == Value::kStructValue) {
    out += AccuracyText(f, accuracy_value.struct_value(), target);
  }
  if (!f.ok) {
    return absl::InvalidArgumentError(
        "the server's build report lacks fields this client reads (core/index/README.md)");
  }
  return out;
}

}  // namespace geodex::client::cli
