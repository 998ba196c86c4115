#include "core/tools/geodesic_cli.h"

#include <atomic>
#include <ctime>
#include <map>
#include <thread>
#include <tuple>

#include "absl/strings/str_cat.h"
#include "core/common/file_util.h"
#include "core/common/status_macros.h"
#include "core/geodesic/exact_geodesic.h"
#include "core/geodesic/vertex_geodesic.h"

namespace geodex::tools {
namespace {

// The pairs that share a first point.
struct Group {
  mesh::SurfacePoint source;
  std::vector<int64_t> pairs;  // indices into the pair list
};

std::vector<Group> GroupBySource(const std::vector<mesh::PointPair>& pairs) {
  std::map<std::tuple<int32_t, double, double, double>, int64_t> group_of;
  std::vector<Group> groups;
  for (int64_t i = 0; i < static_cast<int64_t>(pairs.size()); ++i) {
    const mesh::SurfacePoint& a = pairs[i].a;
    const auto key = std::make_tuple(a.face, a.w[0], a.w[1], a.w[2]);
    auto [it, inserted] = group_of.emplace(key, static_cast<int64_t>(groups.size()));
    if (inserted) groups.push_back({a, {}});
    groups[it->second].pairs.push_back(i);
  }
  return groups;
}

std::string DistanceLines(const std::vector<double>& distances) {
  std::string text;
  text.reserve(distances.size() * 20);
  for (double d : distances) {
    text += mesh::FormatDistance(d);
    text += '\n';
  }
  return text;
}

// Every vertex's exact distance from `v` with `engine`; with `stats`, the
// propagation's CPU time and window counts printed there.
absl::StatusOr<std::vector<double>> VertexDistances(const mesh::Mesh& mesh, int32_t v,
                                                    const std::string& engine, std::FILE* stats) {
  std::vector<double> distances;
  // CPU time of the process, as VTP prints it: steadier than the wall clock
  // on a shared machine.
  const std::clock_t start = std::clock();
  int64_t windows = 0, peak = 0;
  if (engine == "windows") {
    GEODEX_ASSIGN_OR_RETURN(const mesh::SurfacePoint point, mesh::VertexPoint(mesh, v));
    geodesic::ExactGeodesicSolver solver(mesh);
    GEODEX_RETURN_IF_ERROR(solver.Propagate({point}));
    distances = solver.VertexDistances();
    windows = peak = solver.stats().windows_created;
  } else {
    geodesic::VertexGeodesicSolver solver(mesh);
    GEODEX_RETURN_IF_ERROR(solver.Propagate({v}));
    distances = solver.VertexDistances();
    windows = solver.stats().windows_created;
    peak = solver.stats().peak_windows;
  }
  if (stats != nullptr) {
    std::fprintf(stats, "engine %s: %.3f s, %lld windows created, %lld at most alive\n",
                 engine.c_str(), static_cast<double>(std::clock() - start) / CLOCKS_PER_SEC,
                 static_cast<long long>(windows), static_cast<long long>(peak));
  }
  return distances;
}

}  // namespace

GeodesicCommandLine::GeodesicCommandLine()
    : app_("Exact geodesic distances (ICH window propagation, the builder's engine).") {
  GeodesicToolArgs& a = args_;
  app_.add_option("mesh", a.mesh_path, "Mesh file (.obj, .ply, .off, .stl, .gltf, .glb)")
      ->required();
  app_.add_option("--weld", a.read.weld_tolerance,
                  "STL and glTF: weld corners closer than EPS times the bounding-box diagonal "
                  "(default 0: exactly equal positions)")
      ->check(CLI::Range(0.0, 1.0));
  pairs_ = app_.add_option("--pairs", a.pairs_path,
                           "File of lines 'fa a0 a1 a2 fb b0 b1 b2' ('-' for standard input)");
  source_ = app_.add_option("--source-vertex", a.source_vertex,
                            "Every vertex's distance from this vertex (0-based, file order)");
  pairs_->excludes(source_);
  app_.add_option("--out", a.out, "With --source-vertex: output file ('-': standard output)")
      ->needs(source_);
  app_.add_option("--engine", a.engine,
                  "With --source-vertex: 'wavefront' (the builder's rows engine) or 'windows'")
      ->check(CLI::IsMember({"wavefront", "windows"}))
      ->needs(source_);
  app_.add_flag("--stats", a.stats, "With --source-vertex: print time and window counts to stderr")
      ->needs(source_);
  app_.add_option("--threads", a.threads, "Worker threads (--pairs)")->check(CLI::Range(1, 256));
}

GeodesicJob GeodesicCommandLine::job() const {
  if (pairs_->count() > 0) return GeodesicJob::kPairs;
  if (source_->count() > 0) return GeodesicJob::kFromVertex;
  return GeodesicJob::kNone;
}

absl::StatusOr<std::vector<double>> ExactPairDistances(const mesh::Mesh& mesh,
                                                       const std::vector<mesh::PointPair>& pairs,
                                                       int threads) {
  const std::vector<Group> groups = GroupBySource(pairs);
  std::vector<double> result(pairs.size(), geodesic::kInfinity);
  std::atomic<int64_t> next{0};
  std::vector<absl::Status> errors(threads);
  auto worker = [&](int id) {
    geodesic::ExactGeodesicSolver solver(mesh);
    for (int64_t g; (g = next.fetch_add(1)) < static_cast<int64_t>(groups.size());) {
      geodesic::GeodesicOptions options;
      for (int64_t i : groups[g].pairs) options.stop_points.push_back(pairs[i].b);
      const absl::Status status = solver.Propagate({&groups[g].source, 1}, options);
      if (!status.ok()) {
        errors[id] = absl::Status(
            status.code(),
            absl::StrCat("line ", pairs[groups[g].pairs[0]].line, ": ", status.message()));
        return;
      }
      for (int64_t i : groups[g].pairs) result[i] = solver.DistanceAt(pairs[i].b);
    }
  };
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t) pool.emplace_back(worker, t);
  for (std::thread& t : pool) t.join();
  for (const absl::Status& status : errors) GEODEX_RETURN_IF_ERROR(status);
  return result;
}

absl::StatusOr<std::string> PairDistancesText(const GeodesicToolArgs& args) {
  GEODEX_ASSIGN_OR_RETURN(const mesh::Mesh mesh, mesh::LoadMesh(args.mesh_path, args.read));
  GEODEX_ASSIGN_OR_RETURN(const std::string text, mesh::ReadFileOrStdin(args.pairs_path));
  GEODEX_ASSIGN_OR_RETURN(std::vector<mesh::PointPair> pairs, mesh::ParsePairs(text));
  const std::vector<mesh::SurfacePoint> lowest = mesh::LowestFacePoints(mesh);
  GEODEX_RETURN_IF_ERROR(mesh::ResolveVertices(
      [&](int32_t v) { return mesh::VertexPointOf(lowest, v); }, &pairs));
  GEODEX_RETURN_IF_ERROR(mesh::ValidatePairs(mesh, pairs));
  GEODEX_ASSIGN_OR_RETURN(const std::vector<double> distances,
                          ExactPairDistances(mesh, pairs, args.threads));
  return DistanceLines(distances);
}

absl::Status WriteDistancesFromVertex(const GeodesicToolArgs& args, std::FILE* stats) {
  GEODEX_ASSIGN_OR_RETURN(const mesh::Mesh mesh, mesh::LoadMesh(args.mesh_path, args.read));
  if (args.source_vertex < 0 || args.source_vertex >= mesh.num_vertices()) {
    return absl::OutOfRangeError(absl::StrCat("--source-vertex ", args.source_vertex,
                                              " is not a vertex of ", args.mesh_path, " (it has ",
                                              mesh.num_vertices(), " vertices, numbered from 0)"));
  }
  GEODEX_ASSIGN_OR_RETURN(const std::vector<double> distances,
                          VertexDistances(mesh, static_cast<int32_t>(args.source_vertex),
                                          args.engine, args.stats ? stats : nullptr));
  const std::string text = DistanceLines(distances);
  if (args.out == "-") {
    if (std::fwrite(text.data(), 1, text.size(), stdout) != text.size() ||
        std::fflush(stdout) != 0) {
      return absl::DataLossError("cannot write to standard output");
    }
    return absl::OkStatus();
  }
  return AtomicWriteFile(args.out, text);
}

int GeodesicExitCode(const absl::Status& status) {
  if (status.ok()) return 0;
  return status.code() == absl::StatusCode::kInvalidArgument ||
                 status.code() == absl::StatusCode::kOutOfRange
             ? 2
             : 1;
}

}  // namespace geodex::tools
