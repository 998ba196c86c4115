// geodex-geodesic: exact geodesic distances, with the engine the builder uses.
//
//   geodex-geodesic MESH --pairs FILE [--threads N] [--weld EPS]
//   geodex-geodesic MESH --source-vertex V [--out FILE] [--weld EPS]
//
// --pairs reads lines "fa a0 a1 a2 fb b0 b1 b2" (see core/mesh/pairs_io.h)
// and prints one exact distance per pair in input order ("inf" when
// unreachable). Pairs are grouped by their first point so that each distinct
// source is propagated once, stopping as soon as all of its targets are
// settled.
//
// --source-vertex writes every vertex's exact distance from vertex V
// (0-based, in the mesh file's order), one per line: the job an exact
// solver's command line does (VTP's, for one), so that the two compare as
// whole processes. The file is written beside its name and renamed into
// place; '-' (the default) is standard output. It runs the builder's rows
// engine (VertexGeodesicSolver); --engine windows runs ExactGeodesicSolver
// instead, the engine of --pairs. --stats prints the propagation's CPU seconds
// and window counts to standard error.

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <ctime>
#include <map>
#include <thread>

#include "CLI/CLI.hpp"
#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "core/common/file_util.h"
#include "core/common/status_macros.h"
#include "core/common/threads.h"
#include "core/geodesic/exact_geodesic.h"
#include "core/geodesic/vertex_geodesic.h"
#include "core/mesh/mesh_io.h"
#include "core/mesh/pairs_io.h"

namespace geodex {
namespace {

struct Group {
  mesh::SurfacePoint source;
  std::vector<int64_t> pairs;  // indices into the pair list
};

absl::Status Run(const std::string& mesh_path, const mesh::ReadOptions& read,
                 const std::string& pairs_path, int threads) {
  GEODEX_ASSIGN_OR_RETURN(const mesh::Mesh mesh, mesh::LoadMesh(mesh_path, read));
  GEODEX_ASSIGN_OR_RETURN(const std::string text, mesh::ReadFileOrStdin(pairs_path));
  GEODEX_ASSIGN_OR_RETURN(const std::vector<mesh::PointPair> pairs, mesh::ParsePairs(text));
  GEODEX_RETURN_IF_ERROR(mesh::ValidatePairs(mesh, pairs));

  std::map<std::tuple<int32_t, double, double, double>, int64_t> group_of;
  std::vector<Group> groups;
  for (int64_t i = 0; i < static_cast<int64_t>(pairs.size()); ++i) {
    const mesh::SurfacePoint& a = pairs[i].a;
    const auto key = std::make_tuple(a.face, a.w[0], a.w[1], a.w[2]);
    auto [it, inserted] = group_of.emplace(key, static_cast<int64_t>(groups.size()));
    if (inserted) groups.push_back({a, {}});
    groups[it->second].pairs.push_back(i);
  }

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

  std::string out;
  for (double d : result) {
    out += mesh::FormatDistance(d);
    out += '\n';
  }
  std::fwrite(out.data(), 1, out.size(), stdout);
  return absl::OkStatus();
}

absl::Status RunFromVertex(const std::string& mesh_path, const mesh::ReadOptions& read,
                           int64_t source, const std::string& out, const std::string& engine,
                           bool stats) {
  GEODEX_ASSIGN_OR_RETURN(const mesh::Mesh mesh, mesh::LoadMesh(mesh_path, read));
  if (source < 0 || source >= mesh.num_vertices()) {
    return absl::OutOfRangeError(absl::StrCat("--source-vertex ", source, " is not a vertex of ",
                                              mesh_path, " (it has ", mesh.num_vertices(),
                                              " vertices, numbered from 0)"));
  }
  const int32_t v = static_cast<int32_t>(source);
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
  if (stats) {
    std::fprintf(stderr, "engine %s: %.3f s, %lld windows created, %lld at most alive\n",
                 engine.c_str(), static_cast<double>(std::clock() - start) / CLOCKS_PER_SEC,
                 static_cast<long long>(windows), static_cast<long long>(peak));
  }
  std::string text;
  text.reserve(static_cast<size_t>(mesh.num_vertices()) * 20);
  for (double d : distances) {
    text += mesh::FormatDistance(d);
    text += '\n';
  }
  if (out == "-") {
    if (std::fwrite(text.data(), 1, text.size(), stdout) != text.size() ||
        std::fflush(stdout) != 0) {
      return absl::DataLossError("cannot write to standard output");
    }
    return absl::OkStatus();
  }
  return AtomicWriteFile(out, text);
}

}  // namespace
}  // namespace geodex

int main(int argc, char** argv) {
  CLI::App app{"Exact geodesic distances (ICH window propagation, the builder's engine)."};
  std::string mesh_path, pairs_path, out = "-";
  int64_t source_vertex = -1;
  int threads = geodex::common::ThreadCount(0);
  app.add_option("mesh", mesh_path, "Mesh file (.obj, .ply, .off, .stl, .gltf, .glb)")->required();
  geodex::mesh::ReadOptions read;
  app.add_option("--weld", read.weld_tolerance,
                 "STL and glTF: weld corners closer than EPS times the bounding-box diagonal "
                 "(default 0: exactly equal positions)")
      ->check(CLI::Range(0.0, 1.0));
  auto* pairs = app.add_option("--pairs", pairs_path,
                               "File of lines 'fa a0 a1 a2 fb b0 b1 b2' ('-' for standard input)");
  auto* source = app.add_option("--source-vertex", source_vertex,
                                "Every vertex's distance from this vertex (0-based, file order)");
  pairs->excludes(source);
  app.add_option("--out", out, "With --source-vertex: output file ('-': standard output)")
      ->needs(source);
  std::string engine = "wavefront";
  bool stats = false;
  app.add_option("--engine", engine,
                 "With --source-vertex: 'wavefront' (the builder's rows engine) or 'windows'")
      ->check(CLI::IsMember({"wavefront", "windows"}))
      ->needs(source);
  app.add_flag("--stats", stats, "With --source-vertex: print time and window counts to stderr")
      ->needs(source);
  app.add_option("--threads", threads, "Worker threads (--pairs)")->check(CLI::Range(1, 256));
  CLI11_PARSE(app, argc, argv);
  if (pairs->count() == 0 && source->count() == 0) {
    std::fprintf(stderr, "geodex-geodesic: give --pairs FILE or --source-vertex V\n");
    return 2;
  }
  const absl::Status status =
      pairs->count() > 0
          ? geodex::Run(mesh_path, read, pairs_path, threads)
          : geodex::RunFromVertex(mesh_path, read, source_vertex, out, engine, stats);
  if (!status.ok()) {
    std::fprintf(stderr, "geodex-geodesic: %s\n", status.ToString().c_str());
    return status.code() == absl::StatusCode::kInvalidArgument ||
                   status.code() == absl::StatusCode::kOutOfRange
               ? 2
               : 1;
  }
  return 0;
}
