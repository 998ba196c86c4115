#pragma once

// Test fixtures for server tests and the server benchmark: small generated
// indexes, a temporary model repository, random surface points.
//
// Not thread-safe unless stated.

#include <sys/types.h>

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "core/mesh/mesh.h"
#include "geodex/v1/geodex.pb.h"

namespace geodex::server::testing {

// Bytes of an index built from mesh::gen::Sphere(3, 1.0) with 40 samples
// (built once per process; thread-safe).
const std::string& SphereIndexBytes();
// Bytes of an index of a small torus with 40 samples (a second, different
// model; built once per process; thread-safe).
const std::string& TorusIndexBytes();
// Bytes of an index of `mesh` with `samples` samples (seed 1, 2 threads),
// with its accuracy calibration unless `calibrate` is false.
std::string BuildIndexBytes(const mesh::Mesh& mesh, int32_t samples, bool calibrate = true);

// A fresh directory under $TMPDIR (or /tmp), removed with its contents.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

// Publishes `bytes` as ROOT/MODEL/VERSION/index.gdx the way an operator
// should: written beside it under another name, then renamed into place.
void WriteModelVersion(const std::string& root, const std::string& model, int64_t version,
                       const std::string& bytes);
void WriteModelConfig(const std::string& root, const std::string& model, const std::string& text);
void RemoveModelVersion(const std::string& root, const std::string& model, int64_t version);
void RemoveModel(const std::string& root, const std::string& model);

// `count` valid points on faces [0, num_faces): random face, random
// barycentric weights summing to 1.
std::vector<mesh::SurfacePoint> RandomPoints(int32_t num_faces, int count, uint32_t seed);
void PointsToProto(std::span<const mesh::SurfacePoint> points, v1::SurfacePoints* proto);

// A geodex-server child process.
struct ServerProcess {
  pid_t pid = -1;  // -1 if it could not be started
  int port = 0;    // 0 if it exited before printing "listening on port N"
};

// Starts `args[0]` (a geodex-server binary) with the other `args` and reads
// the port it prints on stdout. The caller waits for (or kills) the process.
ServerProcess SpawnServer(std::vector<std::string> args);

}  // namespace geodex::server::testing
