#include "core/builder/workdir.h"

#include <xxhash.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <regex>

#include "absl/strings/str_format.h"
#include "core/builder/mesh_arrays.h"
#include "core/builder/prepared_mesh.h"
#include "core/common/file_util.h"
#include "core/common/status_macros.h"
#include "core/mesh/mesh_io.h"

namespace geodex::builder {
namespace {

// The last byte of a magic is the format version. Plan versions: 1 initial;
// 2 adds kEdgesCross to the repair report (9 counters), the crossings found
// and the figures of the traced geodesic edges; 3 adds the cell radii (2 is
// still read, without them); 4 adds the samples added for a wrong Euler
// characteristic (3 is still read, without them).
constexpr char kPlanMagic[8] = {'G', 'D', 'X', 'P', 'L', 'A', 'N', '4'};
constexpr char kPlanMagicV3[8] = {'G', 'D', 'X', 'P', 'L', 'A', 'N', '3'};
constexpr char kPlanMagicV2[8] = {'G', 'D', 'X', 'P', 'L', 'A', 'N', '2'};
constexpr char kRowsMagic[8] = {'G', 'D', 'X', 'R', 'O', 'W', 'S', '1'};
// 2 adds the long-edge split (coarse faces, pieces, midpoint count); 1 is
// still read.
constexpr char kRepairMagic[8] = {'G', 'D', 'X', 'R', 'E', 'P', 'R', '2'};
constexpr char kRepairMagicV1[8] = {'G', 'D', 'X', 'R', 'E', 'P', 'R', '1'};

constexpr char kCarriedMagic[8] = {'G', 'D', 'X', 'C', 'A', 'R', 'R', '1'};

std::string PlanPath(const std::string& workdir) { return workdir + "/plan.bin"; }
std::string CarriedPath(const std::string& workdir) { return workdir + "/carried.bin"; }
std::string CoarseMeshPath(const std::string& workdir) { return workdir + "/coarse.ply"; }
std::string CoarseRepairPath(const std::string& workdir) { return workdir + "/coarse-repair.bin"; }
std::string RepairPath(const std::string& workdir) { return workdir + "/repair.bin"; }

std::string RowsPath(const std::string& workdir, int32_t shard, int32_t num_shards) {
  return absl::StrFormat("%s/rows-%05d-of-%05d.bin", workdir, shard, num_shards);
}

// Appends the checksum of everything written so far.
void Seal(ByteWriter& writer) {
  writer.Put<uint64_t>(XXH64(writer.bytes().data(), writer.bytes().size(), 0));
}

// Checks magic and trailing checksum; returns the payload after the magic.
absl::StatusOr<std::string_view> Unseal(const std::string& bytes, const char (&magic)[8],
                                        const std::string& path) {
  constexpr size_t kKind = sizeof(magic) - 1;  // the magic without its version byte
  if (bytes.size() < sizeof(magic) + sizeof(uint64_t) ||
      std::memcmp(bytes.data(), magic, kKind) != 0) {
    return absl::DataLossError(absl::StrFormat("%s is not a geodex work file", path));
  }
  if (bytes[kKind] != magic[kKind]) {
    return absl::FailedPreconditionError(
        absl::StrFormat("%s has format version %c, this geodex-build reads version %c: redo the "
                        "step that wrote it",
                        path, bytes[kKind], magic[kKind]));
  }
  uint64_t stored;
  std::memcpy(&stored, bytes.data() + bytes.size() - sizeof(stored), sizeof(stored));
  if (XXH64(bytes.data(), bytes.size() - sizeof(stored), 0) != stored) {
    return absl::DataLossError(absl::StrFormat("%s: checksum mismatch", path));
  }
  return std::string_view(bytes).substr(sizeof(magic),
                                        bytes.size() - sizeof(magic) - sizeof(stored));
}

// A mesh the work directory holds, as the builder repaired it: zero-area
// faces are part of it.
absl::StatusOr<mesh::Mesh> LoadWorkMesh(const std::string& path) {
  GEODEX_ASSIGN_OR_RETURN(mesh::RawMesh raw, mesh::LoadRawMeshFile(path));
  mesh::MeshOptions mesh_options;
  mesh_options.allow_zero_area_faces = true;
  return mesh::Mesh::Create(std::move(raw.positions), std::move(raw.triangles), raw.name,
                            mesh_options);
}

absl::Status SaveRepairStamped(const RepairRecord& record, uint64_t mesh_hash,
                               const std::string& path);
absl::StatusOr<RepairRecord> LoadRepairStamped(uint64_t mesh_hash, const std::string& path,
                                               const std::string& owner);

}  // namespace

std::string PlanMeshPath(const std::string& workdir) { return workdir + "/mesh.ply"; }

std::vector<int32_t> ShardSamples(int32_t num_samples, int32_t shard, int32_t num_shards) {
  std::vector<int32_t> out;
  for (int32_t a = shard; a < num_samples; a += num_shards) out.push_back(a);
  return out;
}

absl::Status SavePlan(const mesh::Mesh& mesh, const Plan& plan, const std::string& workdir) {
  std::error_code error;
  std::filesystem::create_directories(workdir, error);
  if (error) {
    return absl::InternalError(absl::StrFormat("cannot create %s: %s", workdir, error.message()));
  }
  GEODEX_RETURN_IF_ERROR(mesh::WritePly(mesh, PlanMeshPath(workdir)));
  ByteWriter w;
  w.bytes().append(kPlanMagic, sizeof(kPlanMagic));
  w.Put(plan.mesh_hash);
  w.Put(plan.requested_samples);
  w.Put(plan.seed);
  w.PutVector(plan.samples);
  w.PutVector(plan.nearest);
  w.PutVector(plan.cell_radius);
  w.PutVector(plan.triangles);
  w.PutVector(plan.neighbors);
  w.Put(plan.repair.rounds);
  w.Put(plan.repair.samples_added);
  w.Put(plan.repair.added_for);
  w.Put(plan.repair.crossings_found);
  w.Put(plan.edge_stats.count);
  w.Put(plan.edge_stats.total_length);
  w.Put(plan.edge_stats.longest);
  w.Put(plan.edge_stats.max_relative_error);
  w.Put(plan.sampling_seconds);
  w.Put(plan.triangulation_seconds);
  w.PutVector(plan.repair.euler_samples);
  Seal(w);
  return AtomicWriteFile(PlanPath(workdir), w.bytes());
}

absl::StatusOr<std::pair<mesh::Mesh, Plan>> LoadPlan(const std::string& workdir) {
  GEODEX_ASSIGN_OR_RETURN(mesh::Mesh mesh, LoadWorkMesh(PlanMeshPath(workdir)));
  const std::string path = PlanPath(workdir);
  GEODEX_ASSIGN_OR_RETURN(const std::string bytes, ReadWholeFile(path));
  auto is = [&](const char(&magic)[8]) {
    return bytes.size() >= sizeof(magic) && std::memcmp(bytes.data(), magic, sizeof(magic)) == 0;
  };
  const bool v2 = is(kPlanMagicV2);
  const bool v3 = is(kPlanMagicV3);
  GEODEX_ASSIGN_OR_RETURN(
      const std::string_view payload,
      Unseal(bytes, v2 ? kPlanMagicV2 : (v3 ? kPlanMagicV3 : kPlanMagic), path));
  ByteReader r(payload, path);
  Plan plan;
  GEODEX_RETURN_IF_ERROR(r.Get(&plan.mesh_hash));
  GEODEX_RETURN_IF_ERROR(r.Get(&plan.requested_samples));
  GEODEX_RETURN_IF_ERROR(r.Get(&plan.seed));
  GEODEX_RETURN_IF_ERROR(r.GetVector(&plan.samples));
  GEODEX_RETURN_IF_ERROR(r.GetVector(&plan.nearest));
  if (!v2) GEODEX_RETURN_IF_ERROR(r.GetVector(&plan.cell_radius));
  GEODEX_RETURN_IF_ERROR(r.GetVector(&plan.triangles));
  GEODEX_RETURN_IF_ERROR(r.GetVector(&plan.neighbors));
  GEODEX_RETURN_IF_ERROR(r.Get(&plan.repair.rounds));
  GEODEX_RETURN_IF_ERROR(r.Get(&plan.repair.samples_added));
  GEODEX_RETURN_IF_ERROR(r.Get(&plan.repair.added_for));
  GEODEX_RETURN_IF_ERROR(r.Get(&plan.repair.crossings_found));
  GEODEX_RETURN_IF_ERROR(r.Get(&plan.edge_stats.count));
  GEODEX_RETURN_IF_ERROR(r.Get(&plan.edge_stats.total_length));
  GEODEX_RETURN_IF_ERROR(r.Get(&plan.edge_stats.longest));
  GEODEX_RETURN_IF_ERROR(r.Get(&plan.edge_stats.max_relative_error));
  GEODEX_RETURN_IF_ERROR(r.Get(&plan.sampling_seconds));
  GEODEX_RETURN_IF_ERROR(r.Get(&plan.triangulation_seconds));
  if (!v2 && !v3) GEODEX_RETURN_IF_ERROR(r.GetVector(&plan.repair.euler_samples));
  if (!r.AtEnd()) return absl::DataLossError(absl::StrFormat("%s has trailing bytes", path));
  if (index::MeshHash(FlatPositions(mesh), FlatFaces(mesh)) != plan.mesh_hash) {
    return absl::FailedPreconditionError(
        absl::StrFormat("%s does not belong to %s", path, PlanMeshPath(workdir)));
  }
  const int32_t m = plan.num_samples();
  bool valid = static_cast<int32_t>(plan.nearest.size()) == mesh.num_vertices() &&
               plan.neighbors.size() == plan.triangles.size() &&
               (plan.cell_radius.empty() || static_cast<int32_t>(plan.cell_radius.size()) == m);
  for (double r : plan.cell_radius) valid &= r >= 0 && std::isfinite(r);
  for (int32_t v : plan.samples) valid &= v >= 0 && v < mesh.num_vertices();
  for (int32_t a : plan.repair.euler_samples) valid &= a >= 0 && a < m;
  for (int32_t a : plan.nearest) valid &= a >= mesh::kNone && a < m;
  for (const auto& t : plan.triangles) {
    for (int32_t a : t) valid &= a >= 0 && a < m;
  }
  for (const auto& n : plan.neighbors) {
    for (int32_t t : n)
      valid &= t >= mesh::kNone && t < static_cast<int32_t>(plan.triangles.size());
  }
  if (!valid) return absl::DataLossError(absl::StrFormat("%s holds inconsistent data", path));
  return std::make_pair(std::move(mesh), std::move(plan));
}

absl::Status SaveRows(const Plan& plan, const std::vector<SampleRow>& rows, int32_t shard,
                      int32_t num_shards, const std::string& workdir) {
  ByteWriter w;
  w.bytes().append(kRowsMagic, sizeof(kRowsMagic));
  w.Put(plan.mesh_hash);
  w.Put(plan.num_samples());
  w.Put(shard);
  w.Put(num_shards);
  w.Put<uint64_t>(rows.size());
  for (const SampleRow& row : rows) {
    w.Put(row.sample);
    w.PutVector(row.to_samples);
    w.PutVector(row.to_cell_vertices);
  }
  Seal(w);
  return AtomicWriteFile(RowsPath(workdir, shard, num_shards), w.bytes());
}

absl::StatusOr<std::vector<SampleRow>> LoadAllRows(const Plan& plan, const std::string& workdir) {
  const std::regex pattern(R"(rows-(\d{5})-of-(\d{5})\.bin)");
  std::vector<std::pair<int32_t, int32_t>> found;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(workdir, error)) {
    std::smatch match;
    const std::string name = entry.path().filename().string();
    if (std::regex_match(name, match, pattern)) {
      found.push_back({std::stoi(match[1]), std::stoi(match[2])});
    }
  }
  if (error) {
    return absl::NotFoundError(absl::StrFormat("cannot list %s: %s", workdir, error.message()));
  }
  if (found.empty()) return absl::NotFoundError(absl::StrFormat("no rows files in %s", workdir));
  std::sort(found.begin(), found.end());
  const int32_t num_shards = found.front().second;
  for (const auto& [shard, count] : found) {
    if (count != num_shards) {
      return absl::InvalidArgumentError(
          absl::StrFormat("%s mixes shardings (%d and %d shards)", workdir, num_shards, count));
    }
  }
  if (static_cast<int32_t>(found.size()) != num_shards) {
    std::string missing;
    for (int32_t s = 0, k = 0; s < num_shards; ++s) {
      if (k < static_cast<int32_t>(found.size()) && found[k].first == s) {
        ++k;
      } else {
        missing += absl::StrFormat(" %d", s);
      }
    }
    return absl::NotFoundError(
        absl::StrFormat("%s: shards missing of %d:%s", workdir, num_shards, missing));
  }
  std::vector<SampleRow> rows;
  for (int32_t shard = 0; shard < num_shards; ++shard) {
    const std::string path = RowsPath(workdir, shard, num_shards);
    GEODEX_ASSIGN_OR_RETURN(const std::string bytes, ReadWholeFile(path));
    GEODEX_ASSIGN_OR_RETURN(const std::string_view payload, Unseal(bytes, kRowsMagic, path));
    ByteReader r(payload, path);
    uint64_t hash = 0, count = 0;
    int32_t m = 0, s = 0, n = 0;
    GEODEX_RETURN_IF_ERROR(r.Get(&hash));
    GEODEX_RETURN_IF_ERROR(r.Get(&m));
    GEODEX_RETURN_IF_ERROR(r.Get(&s));
    GEODEX_RETURN_IF_ERROR(r.Get(&n));
    GEODEX_RETURN_IF_ERROR(r.Get(&count));
    if (hash != plan.mesh_hash || m != plan.num_samples() || s != shard || n != num_shards) {
      return absl::FailedPreconditionError(
          absl::StrFormat("%s was computed for another plan", path));
    }
    const std::vector<int32_t> expected = ShardSamples(m, shard, num_shards);
    if (count != expected.size()) {
      return absl::DataLossError(
          absl::StrFormat("%s holds %d rows, expected %d", path, count, expected.size()));
    }
    for (uint64_t k = 0; k < count; ++k) {
      SampleRow row;
      GEODEX_RETURN_IF_ERROR(r.Get(&row.sample));
      GEODEX_RETURN_IF_ERROR(r.GetVector(&row.to_samples));
      GEODEX_RETURN_IF_ERROR(r.GetVector(&row.to_cell_vertices));
      if (row.sample != expected[k]) {
        return absl::DataLossError(absl::StrFormat("%s: unexpected sample %d", path, row.sample));
      }
      rows.push_back(std::move(row));
    }
    if (!r.AtEnd()) return absl::DataLossError(absl::StrFormat("%s has trailing bytes", path));
  }
  return rows;
}

absl::Status SaveRepair(const RepairRecord& record, const Plan& plan, const std::string& workdir) {
  return SaveRepairStamped(record, plan.mesh_hash, RepairPath(workdir));
}

absl::StatusOr<RepairRecord> LoadRepair(const Plan& plan, const std::string& workdir) {
  return LoadRepairStamped(plan.mesh_hash, RepairPath(workdir), PlanPath(workdir));
}

absl::Status SaveCarriedRows(const Plan& plan, const std::vector<SampleRow>& carried,
                             const std::string& workdir) {
  ByteWriter w;
  w.bytes().append(kCarriedMagic, sizeof(kCarriedMagic));
  w.Put(plan.mesh_hash);
  w.Put(plan.num_samples());
  w.Put<uint64_t>(carried.size());
  for (const SampleRow& row : carried) w.PutVector(row.to_samples);
  Seal(w);
  return AtomicWriteFile(CarriedPath(workdir), w.bytes());
}

absl::StatusOr<std::vector<SampleRow>> LoadCarriedRows(const Plan& plan,
                                                       const std::string& workdir) {
  const std::string path = CarriedPath(workdir);
  absl::StatusOr<std::string> bytes = ReadWholeFile(path);
  if (absl::IsNotFound(bytes.status())) return std::vector<SampleRow>{};
  GEODEX_RETURN_IF_ERROR(bytes.status());
  GEODEX_ASSIGN_OR_RETURN(const std::string_view payload, Unseal(*bytes, kCarriedMagic, path));
  ByteReader r(payload, path);
  uint64_t hash = 0, count = 0;
  int32_t m = 0;
  GEODEX_RETURN_IF_ERROR(r.Get(&hash));
  GEODEX_RETURN_IF_ERROR(r.Get(&m));
  GEODEX_RETURN_IF_ERROR(r.Get(&count));
  if (hash != plan.mesh_hash || m != plan.num_samples()) {
    return absl::FailedPreconditionError(absl::StrFormat("%s was carried into another plan", path));
  }
  if (count > static_cast<uint64_t>(m)) {
    return absl::DataLossError(absl::StrFormat("%s holds %d rows for %d samples", path, count, m));
  }
  std::vector<SampleRow> carried(count);
  for (uint64_t a = 0; a < count; ++a) {
    carried[a].sample = static_cast<int32_t>(a);
    GEODEX_RETURN_IF_ERROR(r.GetVector(&carried[a].to_samples));
    if (carried[a].to_samples.size() <= a ||
        carried[a].to_samples.size() > static_cast<size_t>(m)) {
      return absl::DataLossError(absl::StrFormat("%s: row %d has the wrong size", path, a));
    }
  }
  if (!r.AtEnd()) return absl::DataLossError(absl::StrFormat("%s has trailing bytes", path));
  return carried;
}

absl::Status RemoveCarriedRows(const std::string& workdir) {
  std::error_code error;
  std::filesystem::remove(CarriedPath(workdir), error);
  if (error) {
    return absl::InternalError(
        absl::StrFormat("cannot remove %s: %s", CarriedPath(workdir), error.message()));
  }
  return absl::OkStatus();
}

absl::Status RemoveRows(const std::string& workdir) {
  const std::regex pattern(R"(rows-(\d{5})-of-(\d{5})\.bin)");
  std::error_code error;
  std::vector<std::filesystem::path> stale;
  for (const auto& entry : std::filesystem::directory_iterator(workdir, error)) {
    if (std::regex_match(entry.path().filename().string(), pattern)) stale.push_back(entry.path());
  }
  for (const auto& path : stale) std::filesystem::remove(path, error);
  if (error) {
    return absl::InternalError(
        absl::StrFormat("cannot remove the rows of %s: %s", workdir, error.message()));
  }
  return absl::OkStatus();
}

absl::Status SaveCoarseMesh(const mesh::Mesh& mesh, const RepairRecord& record,
                            const std::string& workdir) {
  std::error_code error;
  std::filesystem::create_directories(workdir, error);
  if (error) {
    return absl::InternalError(absl::StrFormat("cannot create %s: %s", workdir, error.message()));
  }
  GEODEX_RETURN_IF_ERROR(mesh::WritePly(mesh, CoarseMeshPath(workdir)));
  return SaveRepairStamped(record, index::MeshHash(FlatPositions(mesh), FlatFaces(mesh)),
                           CoarseRepairPath(workdir));
}

absl::StatusOr<std::pair<mesh::Mesh, RepairRecord>> LoadCoarseMesh(const std::string& workdir) {
  GEODEX_ASSIGN_OR_RETURN(mesh::Mesh mesh, LoadWorkMesh(CoarseMeshPath(workdir)));
  GEODEX_ASSIGN_OR_RETURN(RepairRecord record,
                          LoadRepairStamped(index::MeshHash(FlatPositions(mesh), FlatFaces(mesh)),
                                            CoarseRepairPath(workdir), CoarseMeshPath(workdir)));
  return std::make_pair(std::move(mesh), std::move(record));
}

absl::Status SaveSealedFile(const std::string& path, const char (&magic)[8],
                            const std::string& payload) {
  ByteWriter w;
  w.bytes().append(magic, sizeof(magic));
  w.bytes().append(payload);
  Seal(w);
  return AtomicWriteFile(path, w.bytes());
}

absl::StatusOr<std::string> LoadSealedFile(const std::string& path, const char (&magic)[8]) {
  GEODEX_ASSIGN_OR_RETURN(const std::string bytes, ReadWholeFile(path));
  GEODEX_ASSIGN_OR_RETURN(const std::string_view payload, Unseal(bytes, magic, path));
  return std::string(payload);
}

namespace {

absl::Status SaveRepairStamped(const RepairRecord& record, uint64_t mesh_hash,
                               const std::string& path) {
  ByteWriter w;
  w.bytes().append(kRepairMagic, sizeof(kRepairMagic));
  w.Put(mesh_hash);
  w.PutVector(record.input_faces);
  w.PutVector(record.vertex_copies);
  w.PutVector(record.coarse_faces);
  w.PutVector(record.split_faces);
  w.Put(record.split_vertices);
  w.PutVector(std::vector<char>(record.report.begin(), record.report.end()));
  Seal(w);
  return AtomicWriteFile(path, w.bytes());
}

// The record at `path`, stamped with `mesh_hash` (of the mesh at `owner`).
absl::StatusOr<RepairRecord> LoadRepairStamped(uint64_t mesh_hash, const std::string& path,
                                               const std::string& owner) {
  absl::StatusOr<std::string> bytes = ReadWholeFile(path);
  if (absl::IsNotFound(bytes.status())) return RepairRecord{};
  GEODEX_RETURN_IF_ERROR(bytes.status());
  const bool v1 = bytes->size() >= sizeof(kRepairMagicV1) &&
                  std::memcmp(bytes->data(), kRepairMagicV1, sizeof(kRepairMagicV1)) == 0;
  GEODEX_ASSIGN_OR_RETURN(const std::string_view payload,
                          Unseal(*bytes, v1 ? kRepairMagicV1 : kRepairMagic, path));
  ByteReader r(payload, path);
  uint64_t hash = 0;
  RepairRecord record;
  std::vector<char> report;
  GEODEX_RETURN_IF_ERROR(r.Get(&hash));
  GEODEX_RETURN_IF_ERROR(r.GetVector(&record.input_faces));
  GEODEX_RETURN_IF_ERROR(r.GetVector(&record.vertex_copies));
  if (!v1) {
    GEODEX_RETURN_IF_ERROR(r.GetVector(&record.coarse_faces));
    GEODEX_RETURN_IF_ERROR(r.GetVector(&record.split_faces));
    GEODEX_RETURN_IF_ERROR(r.Get(&record.split_vertices));
  }
  GEODEX_RETURN_IF_ERROR(r.GetVector(&report));
  if (!r.AtEnd()) return absl::DataLossError(absl::StrFormat("%s has trailing bytes", path));
  if (hash != mesh_hash) {
    return absl::FailedPreconditionError(absl::StrFormat("%s does not belong to %s", path, owner));
  }
  record.report.assign(report.begin(), report.end());
  return record;
}

}  // namespace

}  // namespace geodex::builder
