#include "core/build/build_testing.h"

#include <stdexcept>

#include "core/builder/builder.h"
#include "core/builder/prepared_mesh.h"
#include "core/common/status_macros.h"
#include "core/validation/calibration.h"

namespace geodex::testing {

absl::StatusOr<std::string> BuildTestIndex(const mesh::Mesh& mesh, int32_t samples,
                                           bool calibrate, index::MatrixLayout matrix) {
  builder::BuildOptions options;
  options.num_samples = samples;
  options.threads = 2;
  builder::BuildSummary summary;
  GEODEX_ASSIGN_OR_RETURN(index::IndexData data, builder::BuildIndex(mesh, options, &summary));
  data.sample_matrix = matrix;
  if (calibrate) GEODEX_RETURN_IF_ERROR(validation::AddCalibration(mesh, data));
  return index::SerializeIndex(data);
}

absl::StatusOr<std::shared_ptr<const query::QueryEngine>> BuildTestEngine(
    const mesh::Mesh& mesh, int32_t samples, bool calibrate, query::QueryOptions options,
    index::MatrixLayout matrix) {
  GEODEX_ASSIGN_OR_RETURN(std::string bytes, BuildTestIndex(mesh, samples, calibrate, matrix));
  GEODEX_ASSIGN_OR_RETURN(auto index, index::Index::FromBytes(std::move(bytes)));
  return query::QueryEngine::Create(std::move(index), options);
}

std::shared_ptr<const query::QueryEngine> TestEngineOrThrow(const mesh::Mesh& mesh,
                                                            int32_t samples, bool calibrate,
                                                            query::QueryOptions options,
                                                            index::MatrixLayout matrix) {
  absl::StatusOr<std::shared_ptr<const query::QueryEngine>> engine =
      BuildTestEngine(mesh, samples, calibrate, options, matrix);
  if (!engine.ok()) throw std::runtime_error(engine.status().ToString());
  return *std::move(engine);
}

RepairedTestEngine RepairedTestEngineOrThrow(const mesh::RawMesh& raw, int32_t samples,
                                             bool split) {
  auto engine = [&]() -> absl::StatusOr<RepairedTestEngine> {
    GEODEX_ASSIGN_OR_RETURN(mesh::RepairedMesh repaired, mesh::RepairMesh(raw));
    GEODEX_ASSIGN_OR_RETURN(
        builder::PreparedMesh prepared,
        builder::PrepareMesh(repaired.mesh, builder::RecordRepair(repaired), samples, split));
    builder::BuildOptions options;
    options.num_samples = samples;
    options.threads = 2;
    builder::BuildSummary summary;
    GEODEX_ASSIGN_OR_RETURN(index::IndexData data,
                            builder::BuildPreparedIndex(prepared, options, &summary));
    GEODEX_ASSIGN_OR_RETURN(std::string bytes, index::SerializeIndex(data));
    GEODEX_ASSIGN_OR_RETURN(auto index, index::Index::FromBytes(std::move(bytes)));
    GEODEX_ASSIGN_OR_RETURN(auto query_engine, query::QueryEngine::Create(std::move(index)));
    return RepairedTestEngine{std::move(repaired), std::move(query_engine)};
  }();
  if (!engine.ok()) throw std::runtime_error(engine.status().ToString());
  return *std::move(engine);
}

}  // namespace geodex::testing
