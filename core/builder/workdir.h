#pragma once

// The shared work directory of a distributed build:
//
//   geodex-build plan MESH --samples M -o WORKDIR   writes mesh.ply, repair.bin, plan.bin
//   geodex-build rows WORKDIR --shard I/N           writes rows-I-of-N.bin
//   geodex-build merge WORKDIR -o OUT.gdx           reads them all
//
// Every file is written atomically and carries a magic, a version, the mesh
// hash and an XXH64 checksum, so a half-copied or stale file is rejected
// (DataLoss / FailedPrecondition) instead of merged.

#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/builder/builder.h"
#include "core/builder/prepared_mesh.h"
#include "core/mesh/mesh.h"

namespace geodex::builder {

std::string PlanMeshPath(const std::string& workdir);

// Samples of shard `shard` of `num_shards`: a with a % num_shards == shard.
std::vector<int32_t> ShardSamples(int32_t num_samples, int32_t shard, int32_t num_shards);

// Writes the mesh (PlanMeshPath, binary PLY) and the plan (plan.bin; the traced
// edge paths are left out, their figures kept) into `workdir`, created if
// missing. Each file is replaced atomically (AtomicWriteFile), the mesh first.
// Errors: Internal if `workdir` cannot be created; AtomicWriteFile's errors
// (NotFound, PermissionDenied, Internal), naming the file.
// Thread safety: reentrant; concurrent saves into one `workdir` may leave the
// mesh of one and the plan of the other (LoadPlan then fails
// FailedPrecondition).
absl::Status SavePlan(const mesh::Mesh& mesh, const Plan& plan, const std::string& workdir);
// Loads the mesh and plan of a work directory.
absl::StatusOr<std::pair<mesh::Mesh, Plan>> LoadPlan(const std::string& workdir);

// Writes what the repair of the plan's mesh did (RecordRepair) as
// `workdir`/repair.bin, atomically, stamped with the plan's mesh hash; the
// directory must exist (SavePlan makes it). Errors: AtomicWriteFile's.
absl::Status SaveRepair(const RepairRecord& record, const Plan& plan, const std::string& workdir);
// Reads it back. A work directory without repair.bin (made before repairs
// were recorded) gives an empty record: nothing was repaired. Errors:
// DataLoss for a corrupt file, FailedPrecondition for one of another plan.
absl::StatusOr<RepairRecord> LoadRepair(const Plan& plan, const std::string& workdir);

// Writes the rows of shard `shard` of `num_shards` (those of ShardSamples) as
// `workdir`/rows-SHARD-of-NUM.bin, atomically, stamped with the plan's mesh
// hash so that LoadAllRows rejects rows of another plan.
// Errors: AtomicWriteFile's errors (NotFound if `workdir` does not exist,
// PermissionDenied, Internal), naming the file.
// Thread safety: reentrant; different shards may be saved at once.
absl::Status SaveRows(const Plan& plan, const std::vector<SampleRow>& rows, int32_t shard,
                      int32_t num_shards, const std::string& workdir);
// Loads the rows of every shard. Errors: NotFound / InvalidArgument if shards
// are missing, mixed (different shard counts) or do not cover every sample
// exactly once; DataLoss for corrupt files; FailedPrecondition for rows of
// another plan.
absl::StatusOr<std::vector<SampleRow>> LoadAllRows(const Plan& plan, const std::string& workdir);
// Removes every rows file (a round of a target-error build that planned the
// next one is done with them). Errors: Internal.
absl::Status RemoveRows(const std::string& workdir);

// A target-error build's work directory also holds, between its rounds:
//
//   coarse.ply, coarse-repair.bin   the repaired input before the
//                                   long-edge split, split again for each round
//   carried.bin                     the rows the current plan carries from
//                                   the round before (ComputeRows' carried)
//   target.bin                      the target and the figures of the rounds
//                                   so far (core/build/build_rounds.h)

// Writes the coarse mesh and its repair record (RecordRepair), atomically,
// into `workdir` (created if missing). Errors: as SavePlan's.
absl::Status SaveCoarseMesh(const mesh::Mesh& mesh, const RepairRecord& record,
                            const std::string& workdir);
// Reads them back. Errors: NotFound without them; DataLoss for a corrupt file;
// FailedPrecondition for a record of another mesh.
absl::StatusOr<std::pair<mesh::Mesh, RepairRecord>> LoadCoarseMesh(const std::string& workdir);

// Writes the to_samples of `carried` (rows of the first carried.size()
// samples of `plan`) atomically, stamped with the plan's mesh hash and
// sample count. Errors: AtomicWriteFile's.
absl::Status SaveCarriedRows(const Plan& plan, const std::vector<SampleRow>& carried,
                             const std::string& workdir);
// Reads them back: none when there is no carried.bin (the first round, or a
// plan that carries nothing). Errors: DataLoss for a corrupt file;
// FailedPrecondition for rows carried into another plan.
absl::StatusOr<std::vector<SampleRow>> LoadCarriedRows(const Plan& plan,
                                                       const std::string& workdir);
absl::Status RemoveCarriedRows(const std::string& workdir);

// A file of `payload` behind `magic` (its last byte the version) and a
// checksum, written atomically; and read back (the payload). Errors:
// AtomicWriteFile's; on reading NotFound, DataLoss for another kind of file
// or a checksum mismatch, FailedPrecondition for another version.
absl::Status SaveSealedFile(const std::string& path, const char (&magic)[8],
                            const std::string& payload);
absl::StatusOr<std::string> LoadSealedFile(const std::string& path, const char (&magic)[8]);

}  // namespace geodex::builder
