#include "core/builder/build_rounds.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>

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
constexpr char kTargetMagic[8] = {'G', 'D', 'X', 'T', 'A', 'R', 'G', '1'};

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

}  // namespace

int32_t SampleCap(const mesh::Mesh& coarse, const RoundsOptions& options) {
  int32_t referenced = 0;
  for (int32_t v = 0; v < coarse.num_vertices(); ++v) referenced += coarse.IsReferenced(v);
  // Samples are vertices: without the long-edge split the mesh's own
  // vertices bound m (by default half of them); with it, midpoints make room
  // for more.
  const bool refine = options.build.refine_long_edges;
  const int32_t bound = refine ? validation::kDefaultMaxSamples : referenced;
  const int32_t default_cap = refine ? validation::kDefaultMaxSamples : std::max(3, referenced / 2);
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
  return WithRetries(std::min(std::max(options.build.num_samples, 3), cap), cap,
                     [&](int32_t m) -> absl::StatusOr<RoundPlan> {
                       BuildOptions build = options.build;
                       build.num_samples = m;
                       GEODEX_ASSIGN_OR_RETURN(
                           PreparedMesh prepared,
                           PrepareMesh(coarse, repair, m, build.refine_long_edges));
                       build.input_vertex_ids = InputVertexIds(prepared);
                       GEODEX_ASSIGN_OR_RETURN(Plan plan, MakePlan(prepared.mesh, build));
                       return RoundPlan{std::move(prepared), std::move(plan), {}};
                     });
}

absl::StatusOr<RoundPlan> PlanNextRound(const mesh::Mesh& coarse, const RepairRecord& repair,
                                        const RoundPlan& previous, std::vector<SampleRow> rows,
                                        int32_t num_samples, const RoundsOptions& options) {
  const int32_t m = previous.plan.num_samples();
  std::sort(rows.begin(), rows.end(),
            [](const SampleRow& x, const SampleRow& y) { return x.sample < y.sample; });
  bool in_order = static_cast<int32_t>(rows.size()) == m;
  for (int32_t a = 0; in_order && a < m; ++a) in_order = rows[a].sample == a;
  return WithRetries(
      num_samples, SampleCap(coarse, options), [&](int32_t n) -> absl::StatusOr<RoundPlan> {
        BuildOptions build = options.build;
        build.num_samples = n;
        GEODEX_ASSIGN_OR_RETURN(PreparedMesh prepared,
                                PrepareMesh(coarse, repair, n, build.refine_long_edges));
        build.input_vertex_ids = InputVertexIds(prepared);
        if (!in_order || m > n || !KeepsVertices(previous.prepared.mesh, prepared.mesh)) {
          GEODEX_ASSIGN_OR_RETURN(Plan plan, MakePlan(prepared.mesh, build));
          return RoundPlan{std::move(prepared), std::move(plan), {}};
        }
        GEODEX_ASSIGN_OR_RETURN(Plan plan, ExtendPlan(prepared.mesh, previous.plan.samples, build));
        std::vector<SampleRow> carried(m);
        for (int32_t a = 0; a < m; ++a) {
          // Cell distances are of the earlier cells: the carried rows' are redone.
          carried[a].sample = a;
          carried[a].to_samples = std::move(rows[a].to_samples);
        }
        return RoundPlan{std::move(prepared), std::move(plan), std::move(carried)};
      });
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
  validation::Calibration calibration;
  GEODEX_RETURN_IF_ERROR(validation::AddCalibration(round.prepared.mesh, result.data,
                                                    calibration_options, &calibration));
  result.validation_seconds = SecondsSince(start);
  result.figures = validation::FiguresOf(calibration, round.plan.num_samples());
  return result;
}

NextStep DecideNext(const std::vector<TargetFigures>& rounds, int32_t requested_samples,
                    int32_t cap, double target, int64_t index_bytes) {
  NextStep next;
  if (validation::TargetMet(rounds.back(), target)) {
    next.done = next.reached = true;
    return next;
  }
  const int32_t samples = rounds.back().samples;
  // 3% of the budget spare: the refined mesh, and with it the bytes beside
  // the matrix, grow a little faster than m (bunny_closed_30k: an index
  // predicted to fit came out 1% over).
  const int32_t fits =
      validation::SamplesWithinBytes(validation::kMaxIndexBytes * 97 / 100, samples, index_bytes);
  const validation::PredictionOptions prediction;
  next.num_samples = validation::PredictSamples(rounds, target, std::min(cap, fits), prediction);
  // A round that cannot grow m by the least growth a prediction asks is not
  // worth its rows: stop at the budget.
  const bool at_budget = fits < samples * prediction.min_growth;
  // At the cap (the repair may have added samples beyond it): nothing more to try.
  next.done = requested_samples >= cap || next.num_samples <= samples || at_budget;
  if (next.done) {
    next.stop = at_budget && fits < cap ? absl::StrFormat("the index size budget of %d MiB",
                                                          validation::kMaxIndexBytes >> 20)
                                        : absl::StrFormat("the cap of %d samples", cap);
  }
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
  const TargetFigures& last = rounds.back();
  std::string out = absl::StrFormat(
      "target_error = %.6g\ntarget_error_reached = %s\ntarget_error_rounds = %d\n", target,
      next.reached ? "yes" : absl::StrFormat("no (%s)", next.stop), rounds.size());
  for (size_t k = 0; k < rounds.size(); ++k) {
    out += absl::StrFormat("target_error_round_%d = %s\n", k + 1,
                           validation::FiguresText(rounds[k], target));
  }
  const int far = 1 + validation::BinConfidence::kInterior * validation::kNumScaleBins +
                  validation::kNumScaleBins - 1;
  const int worst = validation::WorstCheck(last, target);
  out += absl::StrFormat(
      "target_error_rms_upper95 = %.6g\ntarget_error_far_p99_upper95 = %.6g\n"
      "target_error_worst = %s %.6g of %.6g\n",
      last.upper[0], last.upper[far], validation::TargetCheckName(worst), last.upper[worst],
      validation::TargetLimit(worst, target));
  return out + validation::CalibrationText(accuracy);
}

absl::StatusOr<TargetBuild> BuildToTarget(const mesh::Mesh& coarse, const RepairRecord& repair,
                                          const RoundsOptions& options,
                                          const std::function<void(const std::string&)>& log) {
  const int32_t cap = SampleCap(coarse, options);
  GEODEX_ASSIGN_OR_RETURN(RoundPlan round, PlanFirstRound(coarse, repair, options));
  std::vector<TargetFigures> figures;
  BuildSummary totals;
  for (int32_t k = 0;; ++k) {
    std::vector<int32_t> all(round.plan.num_samples());
    for (int32_t a = 0; a < round.plan.num_samples(); ++a) all[a] = a;
    const auto start = std::chrono::steady_clock::now();
    GEODEX_ASSIGN_OR_RETURN(
        std::vector<SampleRow> rows,
        ComputeRows(round.prepared.mesh, round.plan, all, options.build, round.carried));
    const double rows_seconds = SecondsSince(start);
    round.carried = {};
    GEODEX_ASSIGN_OR_RETURN(RoundResult result, FinishRound(round, &rows, options));
    figures.push_back(result.figures);
    totals.sampling_seconds += round.plan.sampling_seconds;
    totals.triangulation_seconds += round.plan.triangulation_seconds;
    totals.rows_seconds += rows_seconds;
    totals.merge_seconds += result.summary.merge_seconds;
    if (log) {
      log(RoundLine(k, result.figures, options.target) +
          absl::StrFormat(" (rows %.1fs, validation %.1fs)", rows_seconds,
                          result.validation_seconds));
    }
    GEODEX_ASSIGN_OR_RETURN(const std::string bytes, index::SerializeIndex(result.data));
    const NextStep next = DecideNext(figures, round.plan.requested_samples, cap, options.target,
                                     static_cast<int64_t>(bytes.size()));
    if (next.done) {
      TargetBuild build{std::move(round.prepared.mesh),
                        std::move(round.plan),
                        std::move(result.data),
                        result.summary,
                        std::move(figures),
                        next};
      build.summary.sampling_seconds = totals.sampling_seconds;
      build.summary.triangulation_seconds = totals.triangulation_seconds;
      build.summary.rows_seconds = totals.rows_seconds;
      build.summary.merge_seconds = totals.merge_seconds;
      build.data.report +=
          TargetReport(build.rounds, build.last, options.target, build.data.accuracy[0]);
      return build;
    }
    GEODEX_ASSIGN_OR_RETURN(
        round, PlanNextRound(coarse, repair, round, std::move(rows), next.num_samples, options));
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
  w.Put<uint8_t>(state.refine ? 1 : 0);
  w.Put(state.round);
  w.PutVector(state.rounds);
  return SaveSealedFile(TargetPath(workdir), kTargetMagic, w.bytes());
}

absl::StatusOr<TargetState> LoadTargetState(const std::string& workdir) {
  const std::string path = TargetPath(workdir);
  GEODEX_ASSIGN_OR_RETURN(const std::string payload, LoadSealedFile(path, kTargetMagic));
  ByteReader r(payload, path);
  TargetState state;
  uint8_t refine = 0;
  GEODEX_RETURN_IF_ERROR(r.Get(&state.target));
  GEODEX_RETURN_IF_ERROR(r.Get(&state.cap));
  GEODEX_RETURN_IF_ERROR(r.Get(&state.validation_sources));
  GEODEX_RETURN_IF_ERROR(r.Get(&state.seed));
  GEODEX_RETURN_IF_ERROR(r.Get(&refine));
  GEODEX_RETURN_IF_ERROR(r.Get(&state.round));
  GEODEX_RETURN_IF_ERROR(r.GetVector(&state.rounds));
  if (!r.AtEnd()) return absl::DataLossError(absl::StrFormat("%s has trailing bytes", path));
  state.refine = refine != 0;
  if (!(state.target > 0) || state.cap < 3 || state.validation_sources < 1 || state.round < 0 ||
      static_cast<int32_t>(state.rounds.size()) != state.round) {
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
