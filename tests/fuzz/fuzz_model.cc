#include "tests/fuzz/fuzz_model.h"

#include <cstdio>
#include <cstdlib>

#include "core/builder/builder.h"
#include "core/index/index.h"
#include "core/mesh/generators.h"
#include "core/validation/calibration.h"

namespace geodex::fuzz {
namespace {

[[noreturn]] void Die(const absl::Status& status) {
  std::fprintf(stderr, "fuzz model: %s\n", status.ToString().c_str());
  std::abort();
}

std::string BuildBytes() {
  // Small enough to build in a second under ASan, large enough for both near
  // pairs (refined) and far pairs (the O(1) unfolding).
  const mesh::Mesh mesh = mesh::gen::Sphere(2, 1.0);
  builder::BuildOptions options;
  options.num_samples = 20;
  options.threads = 1;
  builder::BuildSummary summary;
  absl::StatusOr<index::IndexData> data = builder::BuildIndex(mesh, options, &summary);
  if (!data.ok()) Die(data.status());
  if (absl::Status status = validation::AddCalibration(mesh, *data); !status.ok()) Die(status);
  absl::StatusOr<std::string> bytes = index::SerializeIndex(*data);
  if (!bytes.ok()) Die(bytes.status());
  return *std::move(bytes);
}

}  // namespace

const std::string& FuzzIndexBytes() {
  static const std::string* const bytes = new std::string(BuildBytes());
  return *bytes;
}

const query::InputQueries& FuzzQueries() {
  // Held for the process, like the server's loaded model (and reachable, so
  // LeakSanitizer does not count it).
  static const std::shared_ptr<const query::InputQueries>* const queries = [] {
    auto index = index::Index::FromBytes(FuzzIndexBytes());
    if (!index.ok()) Die(index.status());
    auto created = query::InputQueries::Create(*std::move(index));
    if (!created.ok()) Die(created.status());
    return new std::shared_ptr<const query::InputQueries>(*std::move(created));
  }();
  return **queries;
}

}  // namespace geodex::fuzz
