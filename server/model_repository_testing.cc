#include "server/model_repository_testing.h"

#include <stdlib.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <stdexcept>

#include "absl/strings/str_format.h"
#include "core/builder/builder.h"
#include "core/index/index.h"
#include "core/mesh/generators.h"
#include "core/build/build_testing.h"

namespace geodex::server::testing {
namespace fs = std::filesystem;

std::string BuildIndexBytes(const mesh::Mesh& mesh, int32_t samples, bool calibrate) {
  absl::StatusOr<std::string> bytes = geodex::testing::BuildTestIndex(mesh, samples, calibrate);
  if (!bytes.ok()) throw std::runtime_error(bytes.status().ToString());
  return *std::move(bytes);
}

const std::string& SphereIndexBytes() {
  static const std::string* bytes = new std::string(BuildIndexBytes(mesh::gen::Sphere(3, 1.0), 40));
  return *bytes;
}

const std::string& TorusIndexBytes() {
  static const std::string* bytes =
      new std::string(BuildIndexBytes(mesh::gen::Torus(24, 12, 2.0, 0.7), 40));
  return *bytes;
}

TempDir::TempDir() {
  const char* tmp = std::getenv("TMPDIR");
  std::string pattern =
      std::string(tmp != nullptr && *tmp ? tmp : "/tmp") + "/geodex_server_XXXXXX";
  if (mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
  path_ = pattern;
}

TempDir::~TempDir() {
  std::error_code ec;
  fs::remove_all(path_, ec);
}

void WriteModelVersion(const std::string& root, const std::string& model, int64_t version,
                       const std::string& bytes) {
  const fs::path dir = fs::path(root) / model / std::to_string(version);
  fs::create_directories(dir);
  const fs::path tmp = dir / ".index.gdx.tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    if (!out) throw std::runtime_error("cannot write " + tmp.string());
  }
  fs::rename(tmp, dir / "index.gdx");
}

void WriteModelConfig(const std::string& root, const std::string& model, const std::string& text) {
  const fs::path dir = fs::path(root) / model;
  fs::create_directories(dir);
  const fs::path tmp = dir / ".config.tmp";
  {
    std::ofstream out(tmp, std::ios::trunc);
    out << text;
  }
  fs::rename(tmp, dir / "config.textproto");
}

void RemoveModelVersion(const std::string& root, const std::string& model, int64_t version) {
  fs::remove_all(fs::path(root) / model / std::to_string(version));
}

void RemoveModel(const std::string& root, const std::string& model) {
  fs::remove_all(fs::path(root) / model);
}

std::vector<mesh::SurfacePoint> RandomPoints(int32_t num_faces, int count, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int32_t> face(0, num_faces - 1);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<mesh::SurfacePoint> points(count);
  for (mesh::SurfacePoint& p : points) {
    p.face = face(rng);
    double u = unit(rng), v = unit(rng);
    if (u + v > 1) {
      u = 1 - u;
      v = 1 - v;
    }
    p.w = {1 - u - v, u, v};
  }
  return points;
}

void PointsToProto(std::span<const mesh::SurfacePoint> points, v1::SurfacePoints* proto) {
  proto->Clear();
  for (const mesh::SurfacePoint& p : points) {
    proto->add_faces(p.face);
    for (double w : p.w) proto->add_weights(w);
  }
}

ServerProcess SpawnServer(std::vector<std::string> args) {
  int out[2];
  if (pipe(out) != 0) return {};
  const pid_t pid = fork();
  if (pid == 0) {
    dup2(out[1], STDOUT_FILENO);
    close(out[0]);
    close(out[1]);
    std::vector<char*> argv;
    for (std::string& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    execv(argv[0], argv.data());
    _exit(127);
  }
  close(out[1]);
  ServerProcess p;
  p.pid = pid;
  FILE* in = fdopen(out[0], "r");
  char line[256];
  while (std::fgets(line, sizeof(line), in) != nullptr) {
    if (std::sscanf(line, "listening on port %d", &p.port) == 1) break;
  }
  fclose(in);
  return p;
}

}  // namespace geodex::server::testing
