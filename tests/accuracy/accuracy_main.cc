// geodex-accuracy: the full accuracy run.
//
//   geodex-accuracy MESH... --samples 250,500,1000,2000 [--points N] [--sources S]
//                   [--index-dir DIR] [--threads T]
//
// For each mesh and each m: builds the index (or reuses DIR/<mesh>-m<M>.gdx),
// then measures the query engine against exact geodesics on area-uniform
// random point pairs and prints one Markdown row. MESH may be builtin:NAME.

#include <cstdio>
#include <filesystem>

#include "CLI/CLI.hpp"
#include "absl/strings/str_format.h"
#include "core/builder/builder.h"
#include "core/common/status_macros.h"
#include "core/mesh/generators.h"
#include "core/mesh/mesh_io.h"
#include "tests/accuracy/accuracy.h"

namespace geodex {
namespace {

absl::StatusOr<mesh::Mesh> LoadInput(const std::string& path) {
  if (path == "builtin:sphere") return mesh::gen::Sphere(5, 1.0);
  if (path == "builtin:torus") return mesh::gen::Torus(96, 48, 2.0, 0.7);
  if (path == "builtin:folded") return mesh::gen::FoldedSheet(40, 24, 2.0, 1.0, 1.1);
  if (path == "builtin:cylinder") return mesh::gen::Cylinder(64, 24, 1.0, 3.0);
  return mesh::LoadMesh(path);
}

absl::Status Run(const std::vector<std::string>& meshes, const std::vector<int32_t>& samples,
                 const accuracy::AccuracyOptions& options, const std::string& index_dir,
                 int threads, const query::QueryOptions& engine_options) {
  std::printf("%s", accuracy::AccuracyReport::MarkdownHeader().c_str());
  for (const std::string& path : meshes) {
    GEODEX_ASSIGN_OR_RETURN(const mesh::Mesh m, LoadInput(path));
    const std::string name = std::filesystem::path(path).stem().string();
    for (int32_t count : samples) {
      const std::string file =
          absl::StrFormat("%s/%s-m%d.gdx", index_dir.empty() ? "/tmp" : index_dir, name, count);
      if (index_dir.empty() || !std::filesystem::exists(file)) {
        builder::BuildOptions build_options;
        build_options.num_samples = count;
        build_options.threads = threads;
        builder::BuildSummary summary;
        GEODEX_ASSIGN_OR_RETURN(const auto data, builder::BuildIndex(m, build_options, &summary));
        GEODEX_RETURN_IF_ERROR(index::WriteIndexFile(data, file));
        std::fprintf(stderr, "built %s: %s", file.c_str(), summary.ToText().c_str());
      }
      GEODEX_ASSIGN_OR_RETURN(auto index, index::Index::Open(file));
      GEODEX_ASSIGN_OR_RETURN(const accuracy::Engines engines,
                              accuracy::MakeEngines(index, engine_options));
      const auto report = accuracy::MeasureAccuracy(m, engines, options);
      std::printf("%s", report.ToMarkdownRow(absl::StrFormat("%s m=%d", name, count)).c_str());
      std::fflush(stdout);
    }
  }
  return absl::OkStatus();
}

}  // namespace
}  // namespace geodex

int main(int argc, char** argv) {
  CLI::App app{"geodex-accuracy: query accuracy against exact geodesics."};
  std::vector<std::string> meshes;
  std::vector<int32_t> samples = {250, 500, 1000};
  geodex::accuracy::AccuracyOptions options;
  std::string index_dir;
  int threads = 0;
  app.add_option("meshes", meshes, "Mesh files or builtin:NAME")->required();
  app.add_option("--samples", samples, "Values of m")->delimiter(',');
  app.add_option("--points", options.num_points, "Random points");
  app.add_option("--sources", options.num_sources, "Exact propagations (pairs = sources x points)");
  app.add_option("--paths", options.num_paths, "Pairs whose paths are measured");
  app.add_option("--near-points", options.num_near_points,
                 "Points drawn per source in its own and the adjacent geodesic triangles");
  app.add_option("--seed", options.seed, "Random seed");
  app.add_option("--index-dir", index_dir, "Cache built indexes here");
  app.add_option("--threads", threads, "Builder threads (0: all)");
  geodex::query::QueryOptions engine_options;
  app.add_option("--exact-path-corridor", engine_options.exact_path_corridor,
                 "Paths: also solve exactly within this many edge steps of the trace (0: off)");
  CLI11_PARSE(app, argc, argv);
  const absl::Status status =
      geodex::Run(meshes, samples, options, index_dir, threads, engine_options);
  if (!status.ok()) {
    std::fprintf(stderr, "geodex-accuracy: %s\n", status.ToString().c_str());
    return 1;
  }
  return 0;
}
