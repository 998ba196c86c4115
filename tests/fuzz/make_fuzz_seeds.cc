// Writes the seeds of tests/fuzz/corpus that are binary: a valid index (for
// fuzz_index) and requests against the fuzz model (for fuzz_request).
//
//   make_fuzz_seeds CORPUS_DIR    (writes CORPUS_DIR/{index,request}/seed_*)

#include <cstdio>
#include <fstream>
#include <string>

#include "core/builder/builder.h"
#include "core/index/index.h"
#include "core/mesh/generators.h"
#include "core/validation/calibration.h"
#include "geodex/v1/geodex.pb.h"

namespace {

void Write(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!out) std::fprintf(stderr, "cannot write %s\n", path.c_str());
}

// An index of a 2x2 grid with 4 samples, small enough to mutate; with
// `calibrate`, with its accuracy section (format 1.1).
std::string TinyIndex(bool calibrate) {
  geodex::builder::BuildOptions options;
  options.num_samples = 4;
  options.threads = 1;
  geodex::builder::BuildSummary summary;
  auto data =
      geodex::builder::BuildIndex(geodex::mesh::gen::Grid(2, 2, 1.0, 1.0), options, &summary);
  if (!data.ok()) return "";
  if (calibrate &&
      !geodex::validation::AddCalibration(geodex::mesh::gen::Grid(2, 2, 1.0, 1.0), *data).ok()) {
    return "";
  }
  auto bytes = geodex::index::SerializeIndex(*data);
  return bytes.ok() ? *bytes : "";
}

void AddPoint(int32_t face, double w0, double w1, double w2, geodex::v1::SurfacePoints* points) {
  points->add_faces(face);
  points->add_weights(w0);
  points->add_weights(w1);
  points->add_weights(w2);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_fuzz_seeds CORPUS_DIR\n");
    return 2;
  }
  const std::string dir = argv[1];
  Write(dir + "/index/seed_grid", TinyIndex(false));
  Write(dir + "/index/seed_grid_calibrated", TinyIndex(true));

  // One far pair, one near pair and a vertex-on-vertex pair.
  geodex::v1::DistanceRequest distance;
  AddPoint(0, 1.0 / 3, 1.0 / 3, 1.0 / 3, distance.mutable_a());
  AddPoint(50, 0.2, 0.3, 0.5, distance.mutable_b());
  AddPoint(1, 0.5, 0.5, 0.0, distance.mutable_a());
  AddPoint(2, 0.1, 0.1, 0.8, distance.mutable_b());
  AddPoint(3, 1.0, 0.0, 0.0, distance.mutable_a());
  AddPoint(3, 1.0, 0.0, 0.0, distance.mutable_b());
  Write(dir + "/request/seed_distance", std::string(1, '\0') + distance.SerializeAsString());
  distance.set_near_pairs(geodex::v1::NEAR_PAIRS_EXACT);
  distance.set_tolerance(0.01);
  distance.set_error_bounds(true);
  Write(dir + "/request/seed_distance_exact", std::string(1, '\0') + distance.SerializeAsString());

  geodex::v1::LocateRequest locate;
  for (double v : {0.0, 0.0, 1.5, 0.3, -0.2, 0.1, 0.0, 0.0, 0.0}) {
    locate.mutable_positions()->add_xyz(v);
  }
  Write(dir + "/request/seed_locate", std::string(1, '\1') + locate.SerializeAsString());
  return 0;
}
