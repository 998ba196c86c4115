#include "tests/bench/near_profile.h"

#include <algorithm>
#include <cstdio>
#include <vector>

#include "absl/strings/str_format.h"
#include "tests/bench/bench_table.h"
#include "tests/bench/bench_timing.h"

namespace geodex::bench {

using Points = std::vector<mesh::SurfacePoint>;
namespace {

// How the refinement answered one pair, read from the scratch's counts
// before and after its call.
enum NearClass {
  kShot1,
  kShot2,
  kShot3,
  kShot4,
  kStraight,
  kReleased,
  kTraced,
  kExactWalked,
  kExactUnwalked,
  kO1,
  kClasses
};
constexpr const char* kNearClassNames[kClasses] = {
    "straight at shot 1", "straight at shot 2", "straight at shot 3", "straight at shot 4",
    "straight walk",      "walk with releases", "gradient trace",     "exact, pruned by a walk",
    "exact, no walk",     "O(1), not refined"};

NearClass ClassOf(const query::NearPairStats& before, const query::NearPairStats& after) {
  if (after.pairs == before.pairs) return kO1;
  if (after.exact_solves > before.exact_solves) {
    return after.exact_with_walk > before.exact_with_walk ? kExactWalked : kExactUnwalked;
  }
  if (after.traces > before.traces) return kTraced;
  for (int k = 0; k < 4; ++k) {
    if (after.straight_at_shot[k] > before.straight_at_shot[k]) return NearClass(kShot1 + k);
  }
  return after.releases > before.releases ? kReleased : kStraight;
}

}  // namespace

// The pairs (x[i], y[i]) one Distance call each under `options`, each
// timed (the least of three calls: the machine is shared, a call preempted
// once is not its cost) and sorted by how the refinement answered it: a
// row a class, then a total row named `total_how`.
void PrintProfileRows(const std::string& label, const query::QueryEngine& engine, const Points& x,
                      const Points& y, const query::DistanceOptions& options,
                      const std::string& total_how) {
  query::QueryScratch scratch;
  // The engine's exact mesh and the scratch's solvers, made before the clocks
  // run.
  (void)engine.Distance(x[0], y[0], {.near_pairs = query::NearPairs::kExact}, &scratch);
  const size_t all = x.size();
  std::vector<NearClass> cls(all);
  std::vector<double> seconds(all, 1e300);
  NearProfileRow rows[kClasses];
  for (int pass = 0; pass < 3; ++pass) {
    for (size_t i = 0; i < all; ++i) {
      const query::NearPairStats before = scratch.near_pair_stats();
      const Clock::time_point start = Clock::now();
      const absl::StatusOr<double> d = engine.Distance(x[i], y[i], options, &scratch);
      seconds[i] = std::min(seconds[i], SecondsSince(start));
      if (!d.ok() || pass > 0) continue;
      const query::NearPairStats& after = scratch.near_pair_stats();
      cls[i] = ClassOf(before, after);
      NearProfileRow& row = rows[cls[i]];
      row.faces_crossed += static_cast<double>(after.faces_crossed - before.faces_crossed);
      row.faces_unfolded += static_cast<double>(after.faces_unfolded - before.faces_unfolded);
      row.releases += static_cast<double>(after.releases - before.releases);
      row.exact_rounds += static_cast<double>(after.exact_rounds - before.exact_rounds);
      row.exact_region_faces +=
          static_cast<double>(after.exact_region_faces - before.exact_region_faces);
    }
  }
  NearProfileRow total;
  total.how = total_how;
  for (size_t i = 0; i < all; ++i) {
    ++rows[cls[i]].count;
    rows[cls[i]].us += 1e6 * seconds[i];
  }
  for (NearProfileRow& row : rows) {
    total.count += row.count;
    total.us += row.us;
    total.faces_crossed += row.faces_crossed;
    total.faces_unfolded += row.faces_unfolded;
    total.releases += row.releases;
    total.exact_rounds += row.exact_rounds;
    total.exact_region_faces += row.exact_region_faces;
  }
  for (int c = 0; c <= kClasses; ++c) {
    NearProfileRow& row = c < kClasses ? rows[c] : total;
    if (row.count == 0) continue;
    if (c < kClasses) row.how = kNearClassNames[c];
    const double count = static_cast<double>(row.count);
    row.share = count / static_cast<double>(all);
    row.us /= count;
    row.faces_crossed /= count;
    row.faces_unfolded /= count;
    row.releases /= count;
    row.exact_rounds /= count;
    row.exact_region_faces /= count;
    std::printf("%s\n", NearProfileRowText(label, row).c_str());
  }
}

std::string NearProfileHeader(const std::string& pairs) {
  return "\n" + pairs + ", one Distance call each (least of 3), by how they were answered\n" +
         MarkdownHeader({"index", "how", "pairs", "share", "us a pair", "faces crossed",
                         "faces unfolded", "releases", "exact rounds", "exact region faces",
                         "us a face crossed"});
}

std::string NearProfileRowText(const std::string& label, const NearProfileRow& row) {
  return MarkdownRow({
      label,
      row.how,
      absl::StrFormat("%zu", row.count),
      absl::StrFormat("%.1f%%", 100 * row.share),
      absl::StrFormat("%.2f", row.us),
      absl::StrFormat("%.1f", row.faces_crossed),
      absl::StrFormat("%.1f", row.faces_unfolded),
      absl::StrFormat("%.2f", row.releases),
      absl::StrFormat("%.2f", row.exact_rounds),
      absl::StrFormat("%.0f", row.exact_region_faces),
      row.faces_crossed > 0 && row.exact_rounds == 0
          ? absl::StrFormat("%.3f", row.us / row.faces_crossed)
          : std::string("-"),
  });
}

}  // namespace geodex::bench
