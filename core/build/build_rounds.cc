#include "core/build/build_rounds.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <optional>
#include <span>

#include "absl/strings/str_format.h"
#include "core/builder/workdir.h"
#include "core/common/file_util.h"
#include "core/common/status_macros.h"
#include "core/validation/calibration.h"

namespace geodex::builder {
namespace {

using validation::TargetFigures;

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// The version is the last byte.
constexpr char kTargetMagic[8] = {'G', 'D', 'X', 'T', 'A', 'R', 'G', '2'};

// The report's lines a round's index adds after its rows (the target's
// rounds, bands and calibration): a generous estimate, bytes.
constexpr int64_t kReportAllowance = 16 << 10;

// A round is worth its rows only when it grows m at least this much.
constexpr double kLeastGrowth = 1.05;

// The m at which the far band of the shared meshes' default builds came
// closest to the default target (tests/bench/building.md): every one of
// them then ends in one or two rounds. The same m for every mesh: the
// target is in L1000, so a mesh's area is in it already, and no statistic
// of the mesh predicted which builds need a second round
// (building.md, "The first round's m").
constexpr double kFirstRoundAtDefaultTarget = 1200;

std::string TargetPath(const std::string& workdir) { return workdir + "/target.bin"; }

// Whether `fine` begins with `coarse`'s vertices, at the same positions (so
// that sample ids of `coarse` are the same points of `fine`).
bool KeepsVertices(const mesh::Mesh& coarse, const mesh::Mesh& fine) {
  if (fine.num_vertices() < coarse.num_vertices()) return false;
  for (int32_t v = 0; v < coarse.num_vertices(); ++v) {
    if (coarse.position(v) != fine.position(v)) return false;
    if (coarse.IsReferenced(v) != fine.IsReferenced(v)) return false;
  }
  return true;
}

// make(m) for m = `num_samples`, then 10% more twice (at most `cap`) while
// it fails FailedPrecondition: the repair of a triangulation can fail to
// converge at one m and succeed a few samples on (the symmetric grids of
// generated meshes, at some m).
absl::StatusOr<RoundPlan> WithRetries(
    int32_t num_samples, int32_t cap,
    const std::function<absl::StatusOr<RoundPlan>(int32_t)>& make) {
  int32_t m = num_samples;
  for (int attempt = 0;; ++attempt) {
    absl::StatusOr<RoundPlan> round = make(m);
    const int32_t more = std::min(cap, static_cast<int32_t>(std::ceil(m * 1.1)));
    if (round.ok() || !absl::IsFailedPrecondition(round.status()) || attempt == 2 || more <= m) {
      return round;
    }
    m = more;
  }
}

// make(m) within `budget` bytes: while the round's predicted index is over
// it, make(m') for the m' that SamplesWithinBytes predicts fits (a little
// less each time). ResourceExhausted when m' falls below `least`.
absl::StatusOr<RoundPlan> WithinBudget(
    int32_t num_samples, int32_t least, int64_t budget,
    const std::function<absl::StatusOr<RoundPlan>(int32_t)>& make) {
  int32_t m = num_samples;
  for (int attempt = 0;; ++attempt) {
    GEODEX_ASSIGN_OR_RETURN(RoundPlan round, make(m));
    const int64_t bytes = PredictRoundBytes(round);
    if (bytes <= budget) return round;
    const int32_t samples = round.plan.num_samples();
    const double share = 0.97 - 0.05 * std::min(attempt, 4);
    const int32_t fits = std::min(
        samples - 1,
        validation::SamplesWithinBytes(static_cast<int64_t>(share * budget), samples, bytes));
    if (fits < least || attempt == 8) {
      return absl::ResourceExhaustedError(absl::StrFormat(
          "the index size budget of %s: %d samples would take %.1f MiB", BudgetText(budget),
          samples, bytes / 1048576.0));
    }
    m = fits;
  }
}

}  // namespace

std::string BudgetText(int64_t budget) {
  return budget % (1 << 20) == 0 ? absl::StrFormat("%d MiB", budget >> 20)
                                 : absl::StrFormat("%.2f MiB", budget / 1048576.0);
}

int32_t FirstRoundSamples(double target, int32_t cap) {
  const double m = kFirstRoundAtDefaultTarget *
                   std::pow(validation::kDefaultTargetError / target, 1 / 0.8);
  return static_cast<int32_t>(std::clamp<double>(std::round(m), std::min(50, cap), cap));
}

int64_t PredictRoundBytes(const RoundPlan& round) {
  index::IndexData data;
  AddMeshAndTriangulation(round.prepared.mesh, round.plan, &data);
  AddRepair(round.prepared.record, &data);
  data.vertices.resize(round.prepared.mesh.num_vertices());
  data.sample_matrix = index::MatrixLayout::kCoded;
  data.accuracy.resize(1);
  data.spread_bounds.resize(1);
  return static_cast<int64_t>(index::PredictIndexBytes(data)) + kReportAllowance;
}

int32_t SampleCap(const mesh::Mesh& coarse, const RoundsOptions& options) {
  int32_t referenced = 0;
  for (int32_t v = 0; v < coarse.num_vertices(); ++v) referenced += coarse.IsReferenced(v);
  // Samples are vertices: without the long-edge split the mesh's own
  // vertices bound m (by default half of them); with it, midpoints make room
  // for more.
  const bool split = options.build.split_long_edges;
  const int32_t bound = split ? validation::kDefaultMaxSamples : referenced;
  const int32_t default_cap = split ? validation::kDefaultMaxSamples : std::max(3, referenced / 2);
  return std::min(bound, options.max_samples > 0
                             ? options.max_samples
                             : std::min(default_cap, validation::kDefaultMaxSamples));
}

absl::StatusOr<RoundPlan> PlanFirstRound(const mesh::Mesh& coarse, const RepairRecord& repair,
                                         const RoundsOptions& options) {
  if (!(options.target > 0)) {
    return absl::InvalidArgumentError(
        absl::StrFormat("the target error must be > 0 (got %g)", options.target));
  }
  const int32_t cap = SampleCap(coarse, options);
  const int32_t first = options.build.num_samples > 0
                            ? options.build.num_samples
                            : FirstRoundSamples(options.target, cap);
  auto make = [&](int32_t m) -> absl::StatusOr<RoundPlan> {
    BuildOptions build = options.build;
    build.num_samples = m;
    GEODEX_ASSIGN_OR_RETURN(PreparedMesh prepared,
                            PrepareMesh(coarse, repair, m, build.split_long_edges));
    build.input_vertex_ids = InputVertexIds(prepared);
    GEODEX_ASSIGN_OR_RETURN(Plan plan, MakePlan(prepared.mesh, build));
    return RoundPlan{std::move(prepared), std::move(plan), {}};
  };
  return WithinBudget(std::min(std::max(first, 3), cap), 3, options.max_index_bytes,
                      [&](int32_t m) { return WithRetries(m, cap, make); });
}

absl::StatusOr<RoundPlan> PlanNextRound(const mesh::Mesh& coarse, const RepairRecord& repair,
                                        const RoundPlan& previous, std::vector<SampleRow> rows,
                                        int32_t num_samples, const RoundsOptions& options) {
  const int32_t m = previous.plan.num_samples();
  std::sort(rows.begin(), rows.end(),
            [](const SampleRow& x, const SampleRow& y) { return x.sample < y.sample; });
  bool in_order = static_cast<int32_t>(rows.size()) == m;
  for (int32_t a = 0; in_order && a < m; ++a) in_order = rows[a].sample == a;
  // Planned and predicted first; the rows are carried only into the round
  // that fits.
  auto make = [&](int32_t n) -> absl::StatusOr<RoundPlan> {
    BuildOptions build = options.build;
    build.num_samples = n;
    GEODEX_ASSIGN_OR_RETURN(PreparedMesh prepared,
                            PrepareMesh(coarse, repair, n, build.split_long_edges));
    build.input_vertex_ids = InputVertexIds(prepared);
    if (!in_order || m > n || !KeepsVertices(previous.prepared.mesh, prepared.mesh)) {
      GEODEX_ASSIGN_OR_RETURN(Plan plan, MakePlan(prepared.mesh, build));
      return RoundPlan{std::move(prepared), std::move(plan), {}};
    }
    GEODEX_ASSIGN_OR_RETURN(Plan plan, ExtendPlan(prepared.mesh, previous.plan.samples, build));
    // A marker: the rows are carried once the round is chosen.
    return RoundPlan{std::move(prepared), std::move(plan), std::vector<SampleRow>(1)};
  };
  const int32_t cap = SampleCap(coarse, options);
  const int32_t least = std::min(cap, static_cast<int32_t>(std::ceil(m * kLeastGrowth)));
  GEODEX_ASSIGN_OR_RETURN(RoundPlan round,
                          WithinBudget(num_samples, least, options.max_index_bytes,
                                       [&](int32_t n) { return WithRetries(n, cap, make); }));
  if (!round.carried.empty()) {
    round.carried.assign(m, SampleRow{});
    for (int32_t a = 0; a < m; ++a) {
      // Cell distances are of the earlier cells: the carried rows' are redone.
      round.carried[a].sample = a;
      round.carried[a].to_samples = std::move(rows[a].to_samples);
    }
  }
  return round;
}

absl::StatusOr<RoundResult> FinishRound(const RoundPlan& round, std::vector<SampleRow>* rows,
                                        const RoundsOptions& options) {
  RoundResult result;
  GEODEX_ASSIGN_OR_RETURN(result.data,
                          MergeKeepingRows(round.prepared.mesh, round.plan, rows, &result.summary));
  AddRepair(round.prepared.record, &result.data);
  const auto start = std::chrono::steady_clock::now();
  validation::CalibrationOptions calibration_options;
  calibration_options.pairs.threads = options.build.threads;
  calibration_options.pairs.num_sources = options.validation_sources;
  const int32_t m = round.plan.num_samples();
  auto settled = [&](const validation::Calibration& c) {
    return validation::TargetSettled(validation::FiguresOf(c, m), options.target);
  };
  validation::Calibration calibration;
  GEODEX_RETURN_IF_ERROR(validation::AddCalibrationUntil(
      round.prepared.mesh, result.data, calibration_options,
      std::max(options.validation_sources, options.max_validation_sources), settled,
      &calibration));
  result.validation_seconds = SecondsSince(start);
  result.figures = validation::FiguresOf(calibration, m);
  return result;
}

namespace {

// The round closest to the target among `rounds` (the earliest of equals).
int32_t Closest(std::span<const TargetFigures> rounds, double target) {
  int32_t best = 0;
  for (size_t k = 1; k < rounds.size(); ++k) {
    if (validation::Distance(rounds[k], target) < validation::Distance(rounds[best], target)) {
      best = static_cast<int32_t>(k);
    }
  }
  return best;
}

}  // namespace

NextStep DecideNext(const std::vector<TargetFigures>& rounds, int32_t requested_samples,
                    int32_t cap, double target, int64_t index_bytes, int64_t budget) {
  NextStep next;
  const int32_t last = static_cast<int32_t>(rounds.size()) - 1;
  next.keep = last;
  if (validation::TargetMet(rounds.back(), target)) {
    next.done = next.reached = true;
    return next;
  }
  // More samples that bring no check closer spend rows for nothing: the
  // sampling noise of a round is as large as what a few more samples gain,
  // or the mesh's error is in what the O(1) answer cannot reach. One check
  // that stays put (a uniform RMS set by a few corners) while another falls
  // under its limit is progress.
  if (last > 0) {
    const int32_t before =
        Closest(std::span<const TargetFigures>(rounds.data(), rounds.size() - 1), target);
    bool closer = false;
    for (int c = 0; c < validation::kNumTargetChecks; ++c) {
      const TargetFigures &now = rounds.back(), &then = rounds[before];
      if (now.pairs[c] > 0 && then.pairs[c] > 0 && now.upper[c] < then.upper[c]) closer = true;
    }
    if (!closer) {
      next.done = true;
      next.keep = before;
      next.stop = absl::StrFormat("round %d came no closer to the target than round %d",
                                  last + 1, before + 1);
      return next;
    }
  }
  const int32_t samples = rounds.back().samples;
  // 3% of the budget spare: the split mesh, and with it the bytes beside
  // the matrix, grow a little faster than m; each round's bytes are also
  // predicted exactly before its rows (PlanNextRound).
  const int32_t fits = validation::SamplesWithinBytes(budget * 97 / 100, samples, index_bytes);
  const validation::PredictionOptions prediction;
  next.num_samples = validation::PredictSamples(rounds, target, std::min(cap, fits), prediction);
  // A round that cannot grow m by the least growth a prediction asks is not
  // worth its rows: stop at the budget.
  const bool at_budget = fits < samples * prediction.min_growth;
  // At the cap (the repair may have added samples beyond it): nothing more to try.
  next.done = requested_samples >= cap || next.num_samples <= samples || at_budget;
  if (next.done) {
    next.stop = at_budget && fits < cap
                    ? absl::StrFormat("the index size budget of %s", BudgetText(budget))
                    : absl::StrFormat("the cap of %d samples", cap);
  }
  return next;
}

NextStep AtBudget(const std::vector<TargetFigures>& rounds, int64_t budget) {
  NextStep next;
  next.done = true;
  next.keep = static_cast<int32_t>(rounds.size()) - 1;
  next.stop = absl::StrFormat("the index size budget of %s", BudgetText(budget));
  return next;
}

std::string RoundLine(int32_t round, const TargetFigures& figures, double target) {
  const int worst = validation::WorstCheck(figures, target);
  return absl::StrFormat("[target-error] round %d: %s; worst %s at %.2fx its limit", round + 1,
                         validation::FiguresText(figures, target),
                         validation::TargetCheckName(worst),
                         figures.upper[worst] / validation::TargetLimit(worst, target));
}

std::string TargetReport(const std::vector<TargetFigures>& rounds, const NextStep& next,
                         double target, const index::AccuracyRecord& accuracy) {
  const TargetFigures& kept = rounds[next.keep];
  std::string out = absl::StrFormat(
      "target_error = %.6g\ntarget_error_reached = %s\ntarget_error_rounds = %d\n"
      "target_error_kept_round = %d\n",
      target, next.reached ? "yes" : absl::StrFormat("no (%s)", next.stop), rounds.size(),
      next.keep + 1);
  for (size_t k = 0; k < rounds.size(); ++k) {
    out += absl::StrFormat("target_error_round_%d = %s\n", k + 1,
                           validation::FiguresText(rounds[k], target));
  }
  const int worst = validation::WorstCheck(kept, target);
  out += absl::StrFormat(
      "target_error_rms_upper95 = %.6g\ntarget_error_far_p99_upper95 = %.6g\n"
      "target_error_worst = %s %.6g of %.6g\n",
      kept.upper[0], std::max(kept.upper[1], kept.upper[2]), validation::TargetCheckName(worst),
      kept.upper[worst], validation::TargetLimit(worst, target));
  return out + validation::BandsText(kept, accuracy.scale_length) +
         validation::CalibrationText(accuracy);
}

absl::StatusOr<TargetBuild> BuildToTarget(const mesh::Mesh& coarse, const RepairRecord& repair,
                                          const RoundsOptions& options,
                                          const std::function<void(const std::string&)>& log) {
  const int32_t cap = SampleCap(coarse, options);
  GEODEX_ASSIGN_OR_RETURN(RoundPlan round, PlanFirstRound(coarse, repair, options));
  std::vector<TargetFigures> figures;
  BuildSummary totals;
  // The closest round so far: what is written when a later one is not closer.
  std::optional<TargetBuild> closest;
  auto finish = [&](NextStep next) {
    TargetBuild build = *std::move(closest);
    build.rounds = std::move(figures);
    build.last = next;
    build.summary.sampling_seconds = totals.sampling_seconds;
    build.summary.triangulation_seconds = totals.triangulation_seconds;
    build.summary.rows_seconds = totals.rows_seconds;
    build.summary.merge_seconds = totals.merge_seconds;
    build.summary.validation_seconds = totals.validation_seconds;
    build.data.report +=
        TargetReport(build.rounds, build.last, options.target, build.data.accuracy[0]);
    return build;
  };
  for (int32_t k = 0;; ++k) {
    std::vector<int32_t> all(round.plan.num_samples());
    for (int32_t a = 0; a < round.plan.num_samples(); ++a) all[a] = a;
    const auto start = std::chrono::steady_clock::now();
    GEODEX_ASSIGN_OR_RETURN(const std::optional<index::CoarseSurface> surface,
                            CoarseSurfaceOf(round.prepared.mesh, round.prepared.record));
    GEODEX_ASSIGN_OR_RETURN(std::vector<SampleRow> rows,
                            ComputeRows(round.prepared.mesh, round.plan, all, options.build,
                                        round.carried, surface ? &*surface : nullptr));
    const double rows_seconds = SecondsSince(start);
    round.carried = {};
    GEODEX_ASSIGN_OR_RETURN(RoundResult result, FinishRound(round, &rows, options));
    figures.push_back(result.figures);
    totals.sampling_seconds += round.plan.sampling_seconds;
    totals.triangulation_seconds += round.plan.triangulation_seconds;
    totals.rows_seconds += rows_seconds;
    totals.merge_seconds += result.summary.merge_seconds;
    totals.validation_seconds += result.validation_seconds;
    if (log) {
      log(RoundLine(k, result.figures, options.target) +
          absl::StrFormat(" (rows %.1fs, validation %.1fs)", rows_seconds,
                          result.validation_seconds));
    }
    const int64_t bytes = static_cast<int64_t>(index::PredictIndexBytes(result.data));
    const NextStep next = DecideNext(figures, round.plan.requested_samples, cap, options.target,
                                     bytes, options.max_index_bytes);
    if (next.keep == k) {
      closest = TargetBuild{round.prepared.mesh, round.plan, std::move(result.data),
                            result.summary, {}, {}};
    }
    if (next.done) return finish(next);
    absl::StatusOr<RoundPlan> following =
        PlanNextRound(coarse, repair, round, std::move(rows), next.num_samples, options);
    if (absl::IsResourceExhausted(following.status())) return finish(AtBudget(figures, options.max_index_bytes));
    GEODEX_RETURN_IF_ERROR(following.status());
    round = *std::move(following);
  }
}

std::string RoundDirectory(const std::string& workdir, int32_t round) {
  return absl::StrFormat("%s/round-%03d", workdir, round);
}

absl::Status SaveTargetState(const TargetState& state, const std::string& workdir) {
  ByteWriter w;
  w.Put(state.target);
  w.Put(state.cap);
  w.Put(state.validation_sources);
  w.Put(state.seed);
  w.Put<uint8_t>(state.split ? 1 : 0);
  w.Put(state.max_index_bytes);
  w.Put(state.round);
  w.PutVector(state.rounds);
  w.Put(state.closest);
  return SaveSealedFile(TargetPath(workdir), kTargetMagic, w.bytes());
}

absl::StatusOr<TargetState> LoadTargetState(const std::string& workdir) {
  const std::string path = TargetPath(workdir);
  GEODEX_ASSIGN_OR_RETURN(const std::string payload, LoadSealedFile(path, kTargetMagic));
  ByteReader r(payload, path);
  TargetState state;
  uint8_t split = 0;
  GEODEX_RETURN_IF_ERROR(r.Get(&state.target));
  GEODEX_RETURN_IF_ERROR(r.Get(&state.cap));
  GEODEX_RETURN_IF_ERROR(r.Get(&state.validation_sources));
  GEODEX_RETURN_IF_ERROR(r.Get(&state.seed));
  GEODEX_RETURN_IF_ERROR(r.Get(&split));
  GEODEX_RETURN_IF_ERROR(r.Get(&state.max_index_bytes));
  GEODEX_RETURN_IF_ERROR(r.Get(&state.round));
  GEODEX_RETURN_IF_ERROR(r.GetVector(&state.rounds));
  GEODEX_RETURN_IF_ERROR(r.Get(&state.closest));
  if (!r.AtEnd()) return absl::DataLossError(absl::StrFormat("%s has trailing bytes", path));
  state.split = split != 0;
  if (!(state.target > 0) || state.cap < 3 || state.validation_sources < 1 || state.round < 0 ||
      static_cast<int32_t>(state.rounds.size()) != state.round || state.max_index_bytes <= 0 ||
      state.closest < -1 || state.closest >= state.round) {
    return absl::DataLossError(absl::StrFormat("%s holds inconsistent data", path));
  }
  return state;
}

absl::Status RemoveTargetState(const std::string& workdir) {
  std::error_code error;
  std::filesystem::remove(TargetPath(workdir), error);
  if (error) {
    return absl::InternalError(
        absl::StrFormat("cannot remove %s: %s", TargetPath(workdir), error.message()));
  }
  return absl::OkStatus();
}

}  // namespace geodex::builder
