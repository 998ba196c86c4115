// geodex-geodesic: exact geodesic distances between surface point pairs.
//
//   geodex-geodesic MESH --pairs FILE [--threads N]
//
// Reads lines "fa a0 a1 a2 fb b0 b1 b2" (see core/mesh/pairs_io.h) and prints
// one exact distance per pair in input order ("inf" when unreachable). Pairs
// are grouped by their first point so that each distinct source is propagated
// once, stopping as soon as all of its targets are settled.

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <map>
#include <thread>

#include "CLI/CLI.hpp"
#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "core/common/status_macros.h"
#include "core/geodesic/exact_geodesic.h"
#include "core/mesh/mesh_io.h"
#include "core/mesh/pairs_io.h"

namespace geodex {
namespace {

struct Group {
  mesh::SurfacePoint source;
  std::vector<int64_t> pairs;  // indices into the pair list
};

absl::Status Run(const std::string& mesh_path, const std::string& pairs_path, int threads) {
  GEODEX_ASSIGN_OR_RETURN(const mesh::Mesh mesh, mesh::LoadMesh(mesh_path));
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

}  // namespace
}  // namespace geodex

int main(int argc, char** argv) {
  CLI::App app{"Exact geodesic distances between surface point pairs (ICH window propagation)."};
  std::string mesh_path, pairs_path;
  int threads = std::max(1u, std::thread::hardware_concurrency());
  app.add_option("mesh", mesh_path, "Mesh file (.obj, .ply, .off)")->required();
  app.add_option("--pairs", pairs_path,
                 "File of lines 'fa a0 a1 a2 fb b0 b1 b2' ('-' for standard input)")
      ->required();
  app.add_option("--threads", threads, "Worker threads")->check(CLI::Range(1, 256));
  CLI11_PARSE(app, argc, argv);
  const absl::Status status = geodex::Run(mesh_path, pairs_path, threads);
  if (!status.ok()) {
    std::fprintf(stderr, "geodex-geodesic: %s\n", status.ToString().c_str());
    return status.code() == absl::StatusCode::kInvalidArgument ||
                   status.code() == absl::StatusCode::kOutOfRange
               ? 2
               : 1;
  }
  return 0;
}
