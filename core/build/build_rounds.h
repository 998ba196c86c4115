#pragma once

// A build to a target error (core/validation/target_error.h says what a
// target asks), in rounds that keep what the rounds before computed:
//
//   round k  mesh_k: the repaired input refined for m_k (PrepareMesh).
//            Longest-edge bisection splits the longest edges first, so
//            mesh_k is mesh_{k-1} with more midpoints after its vertices,
//            which keep their ids.
//            plan_k: plan_{k-1}'s samples grown to m_k by farthest points,
//            then repaired (ExtendPlan).
//            rows: a full exact propagation for each new sample only; a
//            carried sample keeps its distances to the samples before it,
//            and its cell distances come from a propagation bounded to its
//            cells (ComputeRows' `carried`), a few percent of a full one.
//            Then the merge, and the validation against held-out exact
//            propagations (the index's calibration), judged as
//            target_error.h says.
//   next m   PredictSamples, from the figures of the rounds so far.
//
// Every round's index bytes are predicted from its mesh and plan before its
// rows are computed (PredictRoundBytes): a round that would not fit the
// budget is planned again with fewer samples, and a build whose next round
// cannot grow m within it stops at the round before. The build stops when
// the target is met, when a round brings no check closer to its limit than
// the closest round before (that closest round is the index), or at the cap
// or the budget.
//
// A round whose refined mesh does not begin with the earlier round's
// vertices (the split's vertex cap cut it off differently) starts
// afresh at its m.
//
// The same functions run one process's rounds (BuildToTarget) and the steps
// of a distributed build (build_pipeline.h: plan, then rows and merge again
// until merge says the target is met), so both give the same index.
//
// Thread safety: reentrant.

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/builder/builder.h"
#include "core/builder/prepared_mesh.h"
#include "core/index/index.h"
#include "core/mesh/mesh.h"
#include "core/validation/target_error.h"

namespace geodex::builder {

// BuildOptions::num_samples of a build asked for no sample count: the first
// round's m is predicted (FirstRoundSamples).
inline constexpr int32_t kDefaultFirstRoundSamples = 0;

// The first round's m for target E: the m at which the shared meshes' far
// band (p99 beyond 8 L1000, the check that decides most builds) came
// closest to 4E from below, scaled as that p99 falls (m^-0.8), within
// [50, cap].
int32_t FirstRoundSamples(double target, int32_t cap);

struct RoundsOptions {
  // num_samples: the first round's m (kDefaultFirstRoundSamples: predicted);
  // seed, threads, the split, progress.
  BuildOptions build;
  double target = validation::kDefaultTargetError;
  // No index over this many bytes is written (geodex-build --max-index-mib).
  int64_t max_index_bytes = validation::kMaxIndexBytes;
  // Cap on m; 0: validation::kDefaultMaxSamples, and without the
  // long-edge split at most half the referenced vertices.
  int32_t max_samples = 0;
  // Held-out sources of each round's validation (and of the index's
  // calibration): a sequential measurement (validation::TargetSettled)
  // starts with validation_sources and doubles them, up to
  // max_validation_sources, while the round's figures are too close to the
  // target's limits to decide it. A source's pairs err together and sources
  // differ a lot, so the figures vary with the draw.
  int32_t validation_sources = 64;
  int32_t max_validation_sources = 512;
};

// "32 MiB", or "1.50 MiB" for a budget that is no whole number of MiB.
std::string BudgetText(int64_t budget);

// The cap on m for `coarse` (the repaired input).
int32_t SampleCap(const mesh::Mesh& coarse, const RoundsOptions& options);

// One round's mesh and plan, and the rows it carries from the round before
// (empty in the first round, or when it could not carry).
struct RoundPlan {
  PreparedMesh prepared;
  Plan plan;
  std::vector<SampleRow> carried;
};

// The bytes of the index `round` will make, from its mesh and plan (the
// report's own lines estimated).
int64_t PredictRoundBytes(const RoundPlan& round);

// Round 0: `coarse` split for options.build.num_samples (at most the cap),
// with `repair` (RecordRepair of the input), and its plan; with fewer
// samples when that index would not fit the budget. Errors:
// ResourceExhausted when no m fits it (the mesh alone is too large).
absl::StatusOr<RoundPlan> PlanFirstRound(const mesh::Mesh& coarse, const RepairRecord& repair,
                                         const RoundsOptions& options);

// The round after `previous`, whose rows (all of them, any order) are `rows`:
// `num_samples` samples, on `coarse` split for them, or fewer when that
// index would not fit the budget. Errors: ResourceExhausted when no round
// with enough more samples than `previous` to be worth its rows fits it
// (the build stops at `previous`).
absl::StatusOr<RoundPlan> PlanNextRound(const mesh::Mesh& coarse, const RepairRecord& repair,
                                        const RoundPlan& previous, std::vector<SampleRow> rows,
                                        int32_t num_samples, const RoundsOptions& options);

struct RoundResult {
  index::IndexData data;  // with the repair record and the calibration
  BuildSummary summary;
  validation::TargetFigures figures;
  double validation_seconds = 0;
};

// Merges the round (its plan and all its rows, left sorted in `rows` for
// the next round to carry) and validates the index.
absl::StatusOr<RoundResult> FinishRound(const RoundPlan& round, std::vector<SampleRow>* rows,
                                        const RoundsOptions& options);

// What comes after a finished round.
struct NextStep {
  bool done = false;        // the target is met, or m can grow no more
  bool reached = false;     // the target is met
  int32_t num_samples = 0;  // when not done: the next round's m
  // When done: the round whose index is written (the closest to the target).
  int32_t keep = 0;
  // When done and not reached: why m stops ("the cap of 8000 samples", "the
  // index size budget of 32 MiB", "round 3 came no closer to the target than
  // round 2").
  std::string stop;
};
// `index_bytes`: the size of the last round's index; m grows no further than
// `budget` bytes allow.
NextStep DecideNext(const std::vector<validation::TargetFigures>& rounds, int32_t requested_samples,
                    int32_t cap, double target, int64_t index_bytes, int64_t budget);
// The NextStep of a build whose next round found no m within `budget`.
NextStep AtBudget(const std::vector<validation::TargetFigures>& rounds, int64_t budget);

// The report lines of a target-error build (the target, whether it was
// reached, each round's figures, the fixed bands of the round kept and what
// answers each, the calibration's), for the index's report.
std::string TargetReport(const std::vector<validation::TargetFigures>& rounds, const NextStep& last,
                         double target, const index::AccuracyRecord& accuracy);
// The line geodex-build logs after a round.
std::string RoundLine(int32_t round, const validation::TargetFigures& figures, double target);

// All rounds in one process.
struct TargetBuild {
  mesh::Mesh mesh;  // the last round's (refined) mesh and plan
  Plan plan;
  index::IndexData data;
  BuildSummary summary;  // of the last round, its times summed over the rounds
  std::vector<validation::TargetFigures> rounds;
  NextStep last;  // done: whether the target was reached, else why m stopped
};
absl::StatusOr<TargetBuild> BuildToTarget(const mesh::Mesh& coarse, const RepairRecord& repair,
                                          const RoundsOptions& options,
                                          const std::function<void(const std::string&)>& log);

// A distributed target-error build's state between its steps, in its work
// directory (target.bin): the options the rounds need and the figures of the
// rounds so far. The current round's files are in RoundDirectory(workdir,
// round).
struct TargetState {
  double target = 0;
  int32_t cap = 0;
  int32_t validation_sources = 0;
  uint64_t seed = 0;
  bool split = true;
  int64_t max_index_bytes = 0;
  int32_t round = 0;                              // the current round
  std::vector<validation::TargetFigures> rounds;  // the finished ones
  // The finished round closest to the target; its directory is kept, for
  // the index when a later round comes no closer.
  int32_t closest = -1;
};
std::string RoundDirectory(const std::string& workdir, int32_t round);
// Writes target.bin atomically. Errors: AtomicWriteFile's.
absl::Status SaveTargetState(const TargetState& state, const std::string& workdir);
// NotFound when `workdir` holds a fixed-m build (no target.bin); DataLoss for
// a corrupt file.
absl::StatusOr<TargetState> LoadTargetState(const std::string& workdir);
// Removes target.bin (a fixed-m plan made in a work directory that held a
// target-error build). Errors: Internal.
absl::Status RemoveTargetState(const std::string& workdir);

}  // namespace geodex::builder
