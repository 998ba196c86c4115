#pragma once

// The build report of an index, for people and for scripts.
//
// An index stores its builder's report as "key = value" lines
// (SectionId::kReport) beside the header's counts and the accuracy
// calibration. MakeIndexReport gathers them into one IndexReport: the mesh,
// its repairs, the samples, the index size by section, whether the error
// target was met (and why not), and the relative error by distance.
// IndexReportText renders it as a few lines and a table with units (%, MiB);
// IndexReportJson as one JSON object whose keys are documented in
// core/index/README.md ("The build report"). geodex-query --info, geodex-build's
// closing lines, the server's GetModel (ModelInfo.report_json), the viewer
// and the Python package all show this one report.
//
//   absl::StatusOr<std::shared_ptr<const Index>> index = Index::Open("x.gdx");
//   const IndexReport report = MakeIndexReport(**index);
//   std::string text = IndexReportText(report, "x.gdx");
//   std::string json = IndexReportJson(report);
//
// Relative errors are fractions (0.01 is 1%) everywhere but in the text,
// which shows percentages. Every function is a pure function of its
// arguments; thread-safe.

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/index/index.h"

namespace geodex::index {

// The error target the builder builds to when not given a sample count
// (core/validation/target_error.h's kDefaultTargetError): the report of an
// index built with a fixed m compares its figures with this one's limits.
inline constexpr double kReportDefaultTargetError = 0.005;

// One bin of the calibration, by exact distance in units of the sample
// spacing L.
struct ReportBin {
  std::string key;    // "below_L", "L_3L", "3L_10L", "beyond_10L"
  std::string label;  // "d < L", "L-3L", "3L-10L", ">= 10L"
  double from_l = 0;  // the bin's distances, in units of L: [from_l, to_l)
  double to_l = 0;    // +infinity for the last bin
  double rms = 0;     // relative error of the default answer: RMS
  double p99 = 0;     // and 99th percentile
  // The limit a target of earlier formats read this bin's p99 against: 2E
  // below 3L (answers walked or exact), 4E from 3L. Today's target judges
  // the bands from 8 L1000 (ReportBand) and not the bins: kept for the
  // charts and the JSON, not shown in the text.
  double p99_limit = 0;
};

// One band of distances in a unit fixed by the surface, L1000 (the spacing
// of 1000 samples on it), whatever m: what a user gets at a distance.
struct ReportBand {
  std::string key;    // "0_0.5", "0.5_1", ..., "8_16", "16_inf"
  std::string label;  // "0-0.5", ..., ">=16" (L1000)
  double from = 0;    // [from, to) L1000
  double to = 0;
  // p99 of the default answer's relative error, vertex pairs [0] and
  // interior pairs [1]; NaN without pairs.
  double p99[2] = {0, 0};
  int64_t pairs[2] = {0, 0};
  // 4E for the bands the target judges (from 8 L1000), NaN for the others.
  double p99_limit = 0;
  // How the default mode answers this band: "walked or exact", "O(1)", or
  // both with the distance in between.
  std::string answer;
};

// One check the error target judges (core/validation/target_error.h), as
// the build measured it on held-out pairs: the verdict and the report's
// "judged" lines both read these, so they cannot disagree.
struct ReportCheck {
  std::string key;    // "uniform_rms", "vertex_far_p99", "interior_far_p99"
  std::string label;  // "uniform RMS", "vertex >=8 L1000 p99", "interior >=8 L1000 p99"
  double measured = 0;
  double upper95 = 0;  // its 95% upper confidence limit, what is judged
  double limit = 0;    // E or 4E of the report's target_error
  int64_t pairs = 0;   // 0: no pairs (not judged)
};

// Bytes of one group of sections (the distance matrix, the mesh, ...).
struct ReportSection {
  std::string key;    // "distance_matrix", "mesh", ...
  std::string label;  // "distance matrix", "mesh", ...
  uint64_t bytes = 0;
};

// A sample's place: its vertex in the mesh file's ids (`copy_of` for a copy
// the repair made of a non-manifold vertex, `midpoint` for a split's
// midpoint, which the file does not have) and its position.
struct PlacedSample {
  int64_t sample = 0;
  int64_t vertex = 0;  // the file's id; for a copy, the vertex it copies; -1 for a midpoint
  bool copy = false;
  bool midpoint = false;
  std::array<double, 3> position = {0, 0, 0};
};
inline constexpr int kReportedEulerSamples = 5;

struct IndexReport {
  std::string format;  // "2.1"
  std::string builder;
  // The mesh file's counts, and those of the mesh the index answers on
  // (repaired, refined).
  int64_t vertices = 0;
  int64_t faces = 0;
  int64_t index_vertices = 0;
  int64_t index_faces = 0;
  int64_t split_midpoints = 0;
  // The repairs of the input mesh: one phrase per repair made ("none" when
  // none was), and every count the report has ("mesh_" keys without it).
  std::string repairs;
  std::vector<std::pair<std::string, double>> repair_counts;
  int64_t requested_samples = 0;
  int64_t samples = 0;
  int64_t samples_added_by_repair = 0;
  std::string sample_repair;  // the triangulation's repair, as the builder says it
  // The samples the repair added for a wrong Euler characteristic: how many,
  // and where the first kReportedEulerSamples lie (the handles, tunnels and
  // pinches the requested samples missed).
  int64_t euler_samples = 0;
  std::vector<PlacedSample> euler_sample_places;
  int64_t triangles = 0;
  uint64_t bytes = 0;                   // the whole file
  std::vector<ReportSection> sections;  // non-empty groups, largest first
  // What the file leaves out and the reader derives at load (format 6.0):
  // "twins", "face BVH".
  std::vector<std::string> derived_at_load;
  bool error_bounds = false;            // calibrated: per-answer bounds and tolerances
  // The error target: `target_asked` when the index was built to one
  // (--target-error, or no --samples); otherwise target_error is the default
  // target, which the figures are compared with.
  double target_error = kReportDefaultTargetError;
  bool target_asked = false;
  bool target_met = false;             // a target-error build only
  std::string target_stop;             // why m stopped short of the target, when it did
  std::vector<int64_t> target_rounds;  // m of each round
  // The check closest to (or furthest over) its limit, with its 95% upper
  // confidence limit and the limit (a target-error build only).
  std::string closest_check;
  double closest_upper95 = 0;
  double closest_limit = 0;
  // The judged checks, stored by builds since the report's check_* lines
  // (empty before: the verdict then reads the bands).
  std::vector<ReportCheck> checks;
  // One sentence: met, or not and why (every build with a calibration).
  std::string target_verdict;
  // The calibration (has_accuracy), over held-out exact propagations.
  bool has_accuracy = false;
  int64_t accuracy_sources = 0;
  int64_t accuracy_pairs = 0;
  double scale_length = 0;  // L, in mesh units
  double uniform_rms = 0;   // over area-uniform pairs
  double uniform_far_p99 = 0;
  std::array<ReportBin, 4> bins;
  // The target's bands (a build of format 4 or later with a calibration;
  // empty for older indexes), L1000 in mesh units, and the distance below
  // which the default answer is walked or exact, in L1000.
  std::vector<ReportBand> bands;
  double band_unit = 0;
  double refined_below = 0;
  // Every "key = value" line of the stored report, in order (a key given
  // twice keeps its last value, at its first place).
  std::vector<std::pair<std::string, std::string>> entries;
};

// The "key = value" lines of a stored report; other lines are skipped, keys
// and values trimmed; a key given twice keeps its last value at its first
// place.
std::vector<std::pair<std::string, std::string>> ParseReportEntries(std::string_view text);

// The report of a loaded index: its header, section table, calibration and
// stored report. Never fails: figures the index lacks (an older format, a
// build without calibration) are absent (has_accuracy false, counts 0).
IndexReport MakeIndexReport(const Index& index);

// A few lines and a table for a person, headed by `title` (a file or model
// name): relative errors in %, sizes in MiB. Ends with a newline.
std::string IndexReportText(const IndexReport& report, std::string_view title);

// One JSON object, pretty-printed with two-space indents (keys:
// core/index/README.md). Numbers are the shortest decimals that read back to the
// same double; a figure the index lacks is null.
std::string IndexReportJson(const IndexReport& report);

// `fraction` as a percentage with three significant digits and no exponent
// ("1.31%", "0.00780%", "643%"; "<0.001%" below that, "0%" for 0, "n/a" for
// NaN). The viewer and the client format the same way.
std::string FormatPercent(double fraction);

// `bytes` in MiB with two decimals ("1.54 MiB").
std::string FormatMiB(uint64_t bytes);

}  // namespace geodex::index
