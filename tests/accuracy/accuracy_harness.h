#pragma once

// The geodex-accuracy harness (tests/accuracy/accuracy_main.cc): its flags,
// the indexes it builds or reuses, and the answer modes it measures by
// distance scale (accuracy.h).
//
//   AccuracyCommandLine  the CLI11 app, its flags bound to HarnessFlags
//   RunHarness           every mesh at every m: a header, then rows
//
// Thread safety: the functions are reentrant apart from their printing;
// an AccuracyCommandLine is used by one thread.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "CLI/CLI.hpp"
#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/index/index.h"
#include "core/mesh/mesh.h"
#include "core/query/engine/query_engine.h"
#include "core/validation/pair_sampling.h"

namespace geodex::accuracy {

// What geodex-accuracy is asked, as its flags say.
struct HarnessFlags {
  std::vector<std::string> meshes;  // files or builtin:NAME
  std::vector<int32_t> samples = {1000};
  validation::PairOptions pairs;  // sources, points, per-bin points, seed
  std::string index_dir;          // cache of built indexes; empty: none
  int threads = 0;
  std::vector<std::string> modes = {"unfold", "default", "bounds", "tol0.005"};
  bool no_split = false;
  bool error_driven = false;
  // An index file to measure (of the one mesh given) instead of building
  // one per --samples: a default build, say.
  std::string index_file;
  // > 0: also rows by fixed L1000 bin and the default target's checks for
  // this target error (core/validation/target_error.h), as measured here.
  double target_error = 0;
};

// The geodex-accuracy app: parsing it (CLI11_PARSE) fills flags().
class AccuracyCommandLine {
 public:
  AccuracyCommandLine();
  AccuracyCommandLine(const AccuracyCommandLine&) = delete;
  AccuracyCommandLine& operator=(const AccuracyCommandLine&) = delete;

  CLI::App& app() { return app_; }
  const HarnessFlags& flags() const { return flags_; }

 private:
  HarnessFlags flags_;
  CLI::App app_;
};

// The mesh of `path`: builtin:sphere, builtin:torus, builtin:folded and
// builtin:cylinder are generated; anything else is a mesh file
// (core/mesh/mesh_io.h, whose errors it returns).
absl::StatusOr<mesh::Mesh> LoadHarnessMesh(const std::string& path);

// How an answer mode (--modes) asks the queries.
struct AnswerMode {
  query::DistanceOptions options;
  bool bounds = false;  // also the error bound
  bool trace = false;   // the traced distance ("trace")
  bool nowalk = false;  // an engine without the walks of near pairs ("nowalk")
};

// unfold, default, exact, bounds, tolX (tolerance X, with bounds), belowX
// (default, refining below X L1000: DistanceOptions::refine_below_l1000;
// with bounds),
// trace, nowalk; X as std::stod reads it, which throws when it is no number.
// Errors: InvalidArgument "unknown mode M".
absl::StatusOr<AnswerMode> ParseAnswerMode(const std::string& mode);

// Where the index of mesh `name` with `count` samples is cached:
// DIR/<name>-m<count>[-noref]<suffix>.gdx, DIR being flags.index_dir or /tmp.
std::string CachedIndexPath(const HarnessFlags& flags, const std::string& name, int32_t count,
                            const std::string& suffix);

// The index of `m` for `count` samples: CachedIndexPath's file when
// flags.index_dir is set and it exists, else built (with `spacing_weight`
// when not empty) and written there; calibrated in memory when it has no
// calibration, as the builder would (its own seed, on the mesh it sampled),
// so that bounds can be measured. Notes what it built on stderr.
absl::StatusOr<std::shared_ptr<const index::Index>> IndexFor(
    const HarnessFlags& flags, const mesh::Mesh& m, const std::string& name, int32_t count,
    const std::string& suffix, const std::vector<double>& spacing_weight);

// Prints on stdout a Markdown row per bin and point kind for every mode of
// flags.modes, answering `pairs` (in the mesh file's ids) with `index`;
// with flags.target_error, also the rows of MarkdownFixedRows for L1000
// `unit`; timing on stderr. Errors: the queries' setup, ParseAnswerMode's (after
// the rows of the modes before).
absl::Status MeasureModes(const HarnessFlags& flags, const std::string& label,
                          const std::vector<validation::ExactPair>& pairs,
                          std::shared_ptr<const index::Index> index, double unit = 0);

// The whole run: the Markdown header, then for every mesh and m the rows of
// MeasureModes (and of the error-driven placement with
// flags.error_driven), or the rows of flags.index_file. Errors: the first
// mesh's, index's or mode's; InvalidArgument for an index file with other
// than one mesh.
absl::Status RunHarness(const HarnessFlags& flags);

}  // namespace geodex::accuracy
