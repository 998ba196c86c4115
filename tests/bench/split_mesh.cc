// split_mesh: writes a mesh with every face split in four at its edge
// midpoints (mesh::gen::SplitFacesInFour), for builder and solver benchmarks
// at sizes the shared meshes do not reach. The surface and every exact
// geodesic distance are unchanged, so the result is a realistic large scan:
// igea_134k split once has 537K vertices, twice 2.1M.
//
//   split_mesh IN OUT [--times N]      (OUT: .obj or .ply, by extension)

#include <cstdio>
#include <string>

#include "CLI/CLI.hpp"
#include "absl/strings/match.h"
#include "core/mesh/generators.h"
#include "core/mesh/mesh_io.h"

int main(int argc, char** argv) {
  CLI::App app{"Split every face of a mesh in four (flat midpoint subdivision)"};
  std::string in, out;
  int times = 1;
  app.add_option("in", in, "input mesh (.obj, .ply, .off)")->required();
  app.add_option("out", out, "output mesh (.obj or .ply)")->required();
  app.add_option("--times", times, "how many times to split")->check(CLI::Range(0, 4));
  CLI11_PARSE(app, argc, argv);

  absl::StatusOr<geodex::mesh::Mesh> mesh = geodex::mesh::LoadMesh(in);
  if (!mesh.ok()) {
    std::fprintf(stderr, "split_mesh: %s\n", std::string(mesh.status().message()).c_str());
    return 1;
  }
  const geodex::mesh::Mesh split = geodex::mesh::gen::SplitFacesInFour(*mesh, times);
  const absl::Status written = absl::EndsWith(out, ".ply") ? geodex::mesh::WritePly(split, out)
                                                           : geodex::mesh::WriteObj(split, out);
  if (!written.ok()) {
    std::fprintf(stderr, "split_mesh: %s\n", std::string(written.message()).c_str());
    return 1;
  }
  std::printf("%s: %d vertices, %d faces\n", out.c_str(), split.num_vertices(), split.num_faces());
  return 0;
}
