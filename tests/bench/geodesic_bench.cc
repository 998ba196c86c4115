// geodesic_bench: single-source exact geodesic propagation, ours against
// VTP (Qin et al. 2016, the fastest published exact solver) and CGAL's
// Surface_mesh_shortest_path, in the same run, on the same mesh and the same
// sources. Ours is two engines: the wavefront engine (VertexGeodesicSolver,
// vertex distances only: the builder's rows and sampling) and the window
// engine (ExactGeodesicSolver, which DistanceAt and PathTo need). Prints a
// Markdown table, one line per engine and mesh.
//
//   geodesic_bench [--mesh PATH]... [--sources K] [--cgal-large-sources K]
//                  [--large-vertices N] [--vtp-dir DIR] [--no-cgal]
//                  [--no-windows]
//
// Without --mesh: bunny_closed_30k.obj and igea_134k.obj from the shared mesh
// directory ($GEODEX_SHARED_MESHES, else GEODEX_SHARED_MESHES_DEFAULT), or,
// when neither is there, a generated icosphere (6 subdivisions, 40962
// vertices). A mesh of 500K vertices and more: `split_mesh` (igea_134k split
// once has 537K), with --no-cgal --no-windows.
//
// What is measured, per mesh: each algorithm runs in its own forked child
// process, so none sees another's heap.
//  - time: seconds per source, mean over the sources, as wall clock and as
//    CPU time of the child (steadier when the machine is shared). One source
//    is the propagation plus reading every vertex distance into a vector.
//    Setup (our solvers' per-mesh tables; CGAL's Surface_mesh copy) is not
//    included and is printed separately. The ratio to VTP is of CPU times:
//    VTP prints clock(), its CPU time.
//  - memory: the increase of the child's peak RSS (getrusage RUSAGE_SELF
//    ru_maxrss) from just before the solver is made to the end of the last
//    propagation. The mesh is loaded in the parent before the fork, so it is
//    in the baseline; CGAL's own copy of it (its Surface_mesh) is built
//    in the child before the baseline, as the counterpart of our Mesh. The
//    peak is reset to the current RSS at the baseline (/proc/self/clear_refs,
//    "5") so that transient allocations made earlier do not hide the increase.
//  - the largest relative difference between each engine's distance field
//    and VTP's, as a check that all are exact.
// CGAL's sequence tree needs ~9 GB on the 134k-vertex Igea, so on meshes with
// at least --large-vertices vertices CGAL runs only --cgal-large-sources
// sources (default 1); ours still runs --sources.
//
// VTP is built from its sources (--vtp-dir, default the shared directory's
// anchors/vtp, with its own build.sh: g++ -O3 -march=native) into the working
// directory, and run as a process per source on the mesh as OBJ (written to
// a temporary file when the input is not one), as its command line does:
// whole mesh, every vertex distance written to a file. Measured per source:
// its own printed propagation time, the wall time of the whole process, and
// the process's peak RSS (wait4), mesh included; its distances are compared
// with ours. Skipped, with a note, when its directory is absent.

#include <sys/resource.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include "CLI/CLI.hpp"
#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/match.h"
#include "absl/strings/str_format.h"
#include "core/geodesic/exact_geodesic.h"
#include "core/geodesic/vertex_geodesic.h"
#include "core/mesh/generators.h"
#include "core/mesh/mesh.h"
#include "core/mesh/mesh_io.h"
#include "tests/integration/cgal_reference.h"

namespace geodex {
namespace {

using mesh::Mesh;
using mesh::SurfacePoint;

// What a child reports back through its pipe.
struct ChildResult {
  std::string error;  // empty on success
  double setup_seconds = 0;
  std::vector<double> seconds;                 // per source, wall clock
  std::vector<double> cpu_seconds;             // per source, CPU time of the child
  int64_t baseline_kb = 0;                     // ru_maxrss just before the algorithm
  int64_t peak_kb = 0;                         // ru_maxrss after the last propagation
  int64_t windows = 0;                         // ours: windows created, summed over sources
  std::vector<std::vector<double>> distances;  // the first few sources'
};

// --- a minimal byte stream for the pipe ------------------------------------
class Writer {
 public:
  template <typename T>
  void Put(const T& value) {
    bytes_.append(reinterpret_cast<const char*>(&value), sizeof(T));
  }
  void PutDoubles(const std::vector<double>& values) {
    Put<int64_t>(values.size());
    bytes_.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(double));
  }
  void PutString(const std::string& s) {
    Put<int64_t>(s.size());
    bytes_.append(s);
  }
  const std::string& bytes() const { return bytes_; }

 private:
  std::string bytes_;
};

class Reader {
 public:
  explicit Reader(std::string bytes) : bytes_(std::move(bytes)) {}
  template <typename T>
  bool Get(T& value) {
    if (pos_ + sizeof(T) > bytes_.size()) return false;
    std::memcpy(&value, bytes_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return true;
  }
  bool GetDoubles(std::vector<double>& values) {
    int64_t n = 0;
    if (!Get(n) || n < 0 || pos_ + n * sizeof(double) > bytes_.size()) return false;
    values.resize(n);
    std::memcpy(values.data(), bytes_.data() + pos_, n * sizeof(double));
    pos_ += n * sizeof(double);
    return true;
  }
  bool GetString(std::string& s) {
    int64_t n = 0;
    if (!Get(n) || n < 0 || pos_ + n > bytes_.size()) return false;
    s.assign(bytes_.data() + pos_, n);
    pos_ += n;
    return true;
  }

 private:
  std::string bytes_;
  size_t pos_ = 0;
};

std::string Serialize(const ChildResult& r) {
  Writer w;
  w.PutString(r.error);
  w.Put(r.setup_seconds);
  w.PutDoubles(r.seconds);
  w.PutDoubles(r.cpu_seconds);
  w.Put(r.baseline_kb);
  w.Put(r.peak_kb);
  w.Put(r.windows);
  w.Put<int64_t>(r.distances.size());
  for (const auto& d : r.distances) w.PutDoubles(d);
  return w.bytes();
}

absl::StatusOr<ChildResult> Deserialize(std::string bytes) {
  Reader in(std::move(bytes));
  ChildResult r;
  int64_t n = 0;
  bool ok = in.GetString(r.error) && in.Get(r.setup_seconds) && in.GetDoubles(r.seconds) &&
            in.GetDoubles(r.cpu_seconds) && in.Get(r.baseline_kb) && in.Get(r.peak_kb) &&
            in.Get(r.windows) && in.Get(n);
  for (int64_t i = 0; ok && i < n; ++i) {
    r.distances.emplace_back();
    ok = in.GetDoubles(r.distances.back());
  }
  if (!ok) return absl::InternalError("truncated result from child process");
  return r;
}

// --- measurement -----------------------------------------------------------
int64_t MaxRssKb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss;  // kilobytes on Linux
}

// Resets the peak RSS to the current RSS (Linux >= 4.0). Returns false when
// not supported; the baseline is then the earlier peak.
bool ResetPeakRss() {
  std::ofstream clear_refs("/proc/self/clear_refs");
  clear_refs << "5";
  clear_refs.flush();
  return static_cast<bool>(clear_refs);
}

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

// CPU time of this process: less sensitive than wall time to other jobs on a
// shared machine.
double CpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

// Runs `work` in a forked child and returns what it reports.
absl::StatusOr<ChildResult> InChild(const std::function<ChildResult()>& work) {
  int fds[2];
  if (pipe(fds) != 0) return absl::InternalError(std::strerror(errno));
  std::fflush(stdout);
  std::fflush(stderr);
  const pid_t pid = fork();
  if (pid < 0) return absl::InternalError(std::strerror(errno));
  if (pid == 0) {
    close(fds[0]);
    const std::string bytes = Serialize(work());
    size_t done = 0;
    while (done < bytes.size()) {
      const ssize_t n = write(fds[1], bytes.data() + done, bytes.size() - done);
      if (n <= 0) _exit(2);
      done += n;
    }
    close(fds[1]);
    _exit(0);
  }
  close(fds[1]);
  std::string bytes;
  char buffer[1 << 16];
  for (ssize_t n; (n = read(fds[0], buffer, sizeof(buffer))) != 0;) {
    if (n < 0) {
      if (errno == EINTR) continue;
      break;
    }
    bytes.append(buffer, n);
  }
  close(fds[0]);
  int wstatus = 0;
  waitpid(pid, &wstatus, 0);
  if (!WIFEXITED(wstatus) || WEXITSTATUS(wstatus) != 0) {
    return absl::InternalError(
        WIFSIGNALED(wstatus)
            ? absl::StrFormat("child killed by signal %d (%s)", WTERMSIG(wstatus),
                              strsignal(WTERMSIG(wstatus)))
            : absl::StrFormat("child exited with status %d", WEXITSTATUS(wstatus)));
  }
  return Deserialize(std::move(bytes));
}

// Ours: the window engine (ExactGeodesicSolver, which DistanceAt and PathTo
// need) or the wavefront engine (VertexGeodesicSolver, the builder's rows).
ChildResult RunOurs(const Mesh& m, const std::vector<int32_t>& sources, bool wavefront,
                    int keep) {
  ChildResult r;
  ResetPeakRss();
  r.baseline_kb = MaxRssKb();
  auto start = std::chrono::steady_clock::now();
  std::unique_ptr<geodesic::ExactGeodesicSolver> windows;
  std::unique_ptr<geodesic::VertexGeodesicSolver> front;
  if (wavefront) {
    front = std::make_unique<geodesic::VertexGeodesicSolver>(m);
  } else {
    windows = std::make_unique<geodesic::ExactGeodesicSolver>(m);
  }
  r.setup_seconds = Seconds(start);
  std::vector<std::vector<double>> kept;
  for (size_t i = 0; i < sources.size(); ++i) {
    start = std::chrono::steady_clock::now();
    const double cpu_start = CpuSeconds();
    absl::Status status;
    std::vector<double> distances;
    if (wavefront) {
      status = front->Propagate({sources[i]});
      distances = front->VertexDistances();
    } else {
      status = windows->Propagate({*mesh::VertexPoint(m, sources[i])});
      distances = windows->VertexDistances();
    }
    r.cpu_seconds.push_back(CpuSeconds() - cpu_start);
    r.seconds.push_back(Seconds(start));
    if (!status.ok()) {
      r.error = std::string(status.message());
      return r;
    }
    r.windows += wavefront ? front->stats().windows_created : windows->stats().windows_created;
    if (static_cast<int>(i) < keep) kept.push_back(std::move(distances));
  }
  r.peak_kb = MaxRssKb();
  r.distances = std::move(kept);
  return r;
}

ChildResult RunCgal(const Mesh& m, const std::vector<SurfacePoint>& sources) {
  ChildResult r;
  auto start = std::chrono::steady_clock::now();
  auto cgal = cgal_reference::CgalShortestPaths::Create(m);
  r.setup_seconds = Seconds(start);
  if (!cgal.ok()) {
    r.error = std::string(cgal.status().message());
    return r;
  }
  ResetPeakRss();
  r.baseline_kb = MaxRssKb();
  std::vector<std::vector<double>> kept;
  for (const SurfacePoint& source : sources) {
    start = std::chrono::steady_clock::now();
    const double cpu_start = CpuSeconds();
    absl::StatusOr<std::vector<double>> distances = (*cgal)->Distances(source);
    r.cpu_seconds.push_back(CpuSeconds() - cpu_start);
    r.seconds.push_back(Seconds(start));
    if (!distances.ok()) {
      r.error = std::string(distances.status().message());
      return r;
    }
    // Free the tree outside the timed region (the next build would free it
    // first anyway, so the peak is that of one tree).
    (*cgal)->Release();
    kept.push_back(*std::move(distances));
  }
  r.peak_kb = MaxRssKb();
  r.distances = std::move(kept);
  return r;
}

// --- VTP, as a process per source -----------------------------------------
struct VtpResult {
  std::vector<double> propagation_seconds;  // VTP's own figure
  std::vector<double> process_seconds;      // wall time of the whole process
  int64_t peak_kb = 0;                      // largest peak RSS of the processes
  std::vector<std::vector<double>> distances;
};

// Builds VTP with its build.sh into `binary` unless it is there already.
absl::Status BuildVtp(const std::string& vtp_dir, const std::string& binary) {
  if (std::filesystem::exists(binary)) return absl::OkStatus();
  const std::string command =
      absl::StrFormat("bash '%s/build.sh' '%s' > /dev/null 2>&1", vtp_dir, binary);
  if (std::system(command.c_str()) != 0 || !std::filesystem::exists(binary)) {
    return absl::InternalError("building VTP failed: " + command);
  }
  return absl::OkStatus();
}

// Runs `vtp -m obj -s v -o out` for each source vertex.
absl::StatusOr<VtpResult> RunVtp(const std::string& binary, const std::string& obj,
                                 const std::vector<int32_t>& vertices, int32_t num_vertices) {
  VtpResult r;
  const std::string out = std::filesystem::temp_directory_path() /
                          absl::StrFormat("geodesic_bench_vtp_%d.txt", getpid());
  const std::string log = out + ".log";
  for (int32_t v : vertices) {
    const auto start = std::chrono::steady_clock::now();
    const pid_t pid = fork();
    if (pid < 0) return absl::InternalError(std::strerror(errno));
    if (pid == 0) {
      if (!std::freopen(log.c_str(), "w", stdout)) _exit(127);
      const std::string source = std::to_string(v);
      execl(binary.c_str(), binary.c_str(), "-m", obj.c_str(), "-s", source.c_str(), "-o",
            out.c_str(), static_cast<char*>(nullptr));
      _exit(127);
    }
    int wstatus = 0;
    rusage usage{};
    if (wait4(pid, &wstatus, 0, &usage) != pid || !WIFEXITED(wstatus) ||
        WEXITSTATUS(wstatus) != 0) {
      return absl::InternalError(absl::StrFormat("VTP failed on source vertex %d", v));
    }
    r.process_seconds.push_back(Seconds(start));
    r.peak_kb = std::max<int64_t>(r.peak_kb, usage.ru_maxrss);
    std::ifstream printed(log);
    std::string word;
    double propagation = -1;
    while (printed >> word) {
      if (word == "took" && printed >> propagation) break;
    }
    if (propagation < 0) return absl::InternalError("VTP printed no propagation time");
    r.propagation_seconds.push_back(propagation);
    std::ifstream in(out);
    std::vector<double> distances;
    distances.reserve(num_vertices);
    for (double d; in >> d;) distances.push_back(d);
    if (static_cast<int32_t>(distances.size()) != num_vertices) {
      return absl::InternalError(absl::StrFormat("VTP wrote %d distances for %d vertices",
                                                 distances.size(), num_vertices));
    }
    r.distances.push_back(std::move(distances));
  }
  std::filesystem::remove(out);
  std::filesystem::remove(log);
  return r;
}

// The largest relative difference between two distance fields.
double MaxRelativeDifference(const std::vector<double>& a, const std::vector<double>& b) {
  double max_relative = 0;
  for (size_t v = 0; v < std::min(a.size(), b.size()); ++v) {
    if (a[v] == b[v]) continue;
    const double rel = std::isinf(a[v]) || std::isinf(b[v])
                           ? std::numeric_limits<double>::infinity()
                           : std::abs(a[v] - b[v]) / std::max(std::abs(a[v]), std::abs(b[v]));
    max_relative = std::max(max_relative, rel);
  }
  return max_relative;
}

// --- the harness -----------------------------------------------------------
struct Options {
  std::vector<std::string> meshes;
  int sources = 3;
  int cgal_large_sources = 1;
  int large_vertices = 50000;
  std::string vtp_dir;  // empty: the shared directory's anchors/vtp
  bool cgal = true;
  bool windows = true;  // also the window engine
};

std::string SharedMeshDir() {
  if (const char* env = std::getenv("GEODEX_SHARED_MESHES"); env != nullptr && *env != '\0') {
    return env;
  }
  return GEODEX_SHARED_MESHES_DEFAULT;
}

// K source vertices spread pseudo-randomly (fixed seed) over referenced vertices.
std::vector<int32_t> PickSources(const Mesh& m, int k) {
  std::vector<int32_t> sources;
  uint64_t state = 0x9E3779B97F4A7C15ull;
  while (static_cast<int>(sources.size()) < k) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    const int32_t v = static_cast<int32_t>((state >> 33) % m.num_vertices());
    if (m.IsReferenced(v)) sources.push_back(v);
  }
  return sources;
}

double Mean(const std::vector<double>& x, size_t n) {
  n = std::min(n, x.size());
  double sum = 0;
  for (size_t i = 0; i < n; ++i) sum += x[i];
  return n == 0 ? 0 : sum / n;
}

std::string Megabytes(int64_t kb) { return absl::StrFormat("%.1f MB", kb / 1024.0); }

struct Row {
  std::vector<std::string> lines;  // table rows
  std::vector<std::string> notes;
};

std::string VtpDir(const Options& options) {
  if (!options.vtp_dir.empty()) return options.vtp_dir;
  return (std::filesystem::path(SharedMeshDir()) / ".." / "anchors" / "vtp").lexically_normal();
}

// One engine's figures, before the comparison columns.
struct Measured {
  std::string engine;
  int sources = 0;
  double wall = 0;  // mean seconds per source
  double cpu = 0;
  std::string memory;
  const std::vector<std::vector<double>>* distances = nullptr;
};

// `path`: the mesh file, or empty for a generated mesh (VTP then gets an OBJ
// written here).
absl::StatusOr<Row> BenchMesh(const std::string& label, const std::string& path, const Mesh& m,
                              const Options& options) {
  const int k_cgal = !options.cgal ? 0
                     : m.num_vertices() >= options.large_vertices
                         ? std::min(options.sources, options.cgal_large_sources)
                         : options.sources;
  const std::vector<int32_t> source_vertices = PickSources(m, options.sources);
  std::vector<SurfacePoint> sources;
  for (int32_t v : source_vertices) sources.push_back(*mesh::VertexPoint(m, v));
  const std::vector<SurfacePoint> cgal_sources(sources.begin(), sources.begin() + k_cgal);
  Row row;
  std::vector<Measured> measured;

  std::vector<ChildResult> ours(2);
  for (const bool wavefront : {true, false}) {
    const char* engine = wavefront ? "ours, wavefront (rows)" : "ours, windows";
    if (!wavefront && !options.windows) continue;
    std::fprintf(stderr, "%s: %s, %d source(s)...\n", label.c_str(), engine, options.sources);
    absl::StatusOr<ChildResult> r =
        InChild([&] { return RunOurs(m, source_vertices, wavefront, options.sources); });
    if (!r.ok()) return r.status();
    if (!r->error.empty()) return absl::InternalError(std::string(engine) + ": " + r->error);
    ours[wavefront ? 0 : 1] = *std::move(r);
    const ChildResult& o = ours[wavefront ? 0 : 1];
    measured.push_back({engine, options.sources, Mean(o.seconds, o.seconds.size()),
                        Mean(o.cpu_seconds, o.cpu_seconds.size()),
                        Megabytes(o.peak_kb - o.baseline_kb), &o.distances});
    row.notes.push_back(absl::StrFormat(
        "%s, %s: setup %.3f s (solver tables), %.3g windows created per source", label, engine,
        o.setup_seconds, static_cast<double>(o.windows) / options.sources));
  }

  ChildResult cgal;
  if (k_cgal > 0) {
    std::fprintf(stderr, "%s: CGAL, %d source(s)...\n", label.c_str(), k_cgal);
    absl::StatusOr<ChildResult> r = InChild([&] { return RunCgal(m, cgal_sources); });
    if (!r.ok()) return absl::InternalError("CGAL: " + std::string(r.status().message()));
    if (!r->error.empty()) return absl::InternalError("CGAL: " + r->error);
    cgal = *std::move(r);
    measured.push_back({"CGAL", k_cgal, Mean(cgal.seconds, k_cgal), Mean(cgal.cpu_seconds, k_cgal),
                        Megabytes(cgal.peak_kb - cgal.baseline_kb), &cgal.distances});
    row.notes.push_back(absl::StrFormat("%s, CGAL: setup %.3f s (Surface_mesh copy)", label,
                                        cgal.setup_seconds));
  }

  VtpResult vtp;
  bool have_vtp = false;
  const std::string vtp_dir = VtpDir(options);
  if (!std::filesystem::exists(std::filesystem::path(vtp_dir) / "build.sh")) {
    row.notes.push_back(absl::StrFormat("%s: VTP skipped: no %s/build.sh", label, vtp_dir));
  } else {
    const std::string binary = std::filesystem::absolute("geodesic_bench_vtp").string();
    if (absl::Status built = BuildVtp(vtp_dir, binary); !built.ok()) return built;
    std::string obj = path;
    const bool temporary_obj = !absl::EndsWith(path, ".obj");
    if (temporary_obj) {
      obj = (std::filesystem::temp_directory_path() /
             absl::StrFormat("geodesic_bench_%d.obj", getpid()))
                .string();
      if (absl::Status written = mesh::WriteObj(m, obj); !written.ok()) return written;
    }
    std::fprintf(stderr, "%s: VTP, %d source(s)...\n", label.c_str(), options.sources);
    absl::StatusOr<VtpResult> r = RunVtp(binary, obj, source_vertices, m.num_vertices());
    if (temporary_obj) std::filesystem::remove(obj);
    if (!r.ok()) return r.status();
    vtp = *std::move(r);
    have_vtp = true;
    const double propagation = Mean(vtp.propagation_seconds, options.sources);
    // VTP prints clock(), the process's CPU time: its figure sits in the CPU
    // column.
    measured.push_back({"VTP", options.sources, Mean(vtp.process_seconds, options.sources),
                        propagation, Megabytes(vtp.peak_kb) + " (process)", &vtp.distances});
    row.notes.push_back(absl::StrFormat(
        "%s, VTP: wall = its whole process (reading the OBJ, writing every distance); CPU = its "
        "printed propagation time; memory = the process's peak RSS, mesh included",
        label));
  }

  for (const Measured& e : measured) {
    auto ratio = [&](const std::string& engine) -> std::string {
      for (const Measured& other : measured) {
        if (other.engine == engine && &other != &e) return absl::StrFormat("%.2f", e.cpu / other.cpu);
      }
      return "-";
    };
    auto diff = [&](const Measured* other) -> std::string {
      if (other == nullptr || other == &e) return "-";
      double worst = 0;
      const size_t n = std::min(e.distances->size(), other->distances->size());
      for (size_t s = 0; s < n; ++s) {
        worst = std::max(worst, MaxRelativeDifference((*e.distances)[s], (*other->distances)[s]));
      }
      return n == 0 ? "-" : absl::StrFormat("%.1e", worst);
    };
    const Measured* vtp_row = nullptr;
    for (const Measured& other : measured) {
      if (other.engine == "VTP") vtp_row = &other;
    }
    row.lines.push_back(absl::StrFormat("| %s | %d | %s | %d | %.3f | %.3f | %s | %s | %s |", label,
                                        m.num_vertices(), e.engine, e.sources, e.wall, e.cpu,
                                        e.memory, ratio("VTP"),
                                        diff(e.engine == "VTP" ? &measured.front() : vtp_row)));
  }
  (void)have_vtp;
  return row;
}

int Run(Options options) {
  std::vector<std::string> notes;
  std::vector<std::tuple<std::string, std::string, Mesh>> meshes;  // label, path, mesh
  if (options.meshes.empty()) {
    const std::filesystem::path dir = SharedMeshDir();
    for (const char* name : {"bunny_closed_30k.obj", "igea_134k.obj"}) {
      if (std::filesystem::exists(dir / name)) options.meshes.push_back((dir / name).string());
    }
    if (options.meshes.empty()) {
      notes.push_back(absl::StrFormat(
          "no shared meshes in '%s' (set GEODEX_SHARED_MESHES): using a generated icosphere "
          "(6 subdivisions)",
          dir.string()));
      meshes.emplace_back("icosphere_6", "", mesh::gen::Sphere(6, 1.0));
    }
  }
  for (const std::string& path : options.meshes) {
    absl::StatusOr<Mesh> m = mesh::LoadMesh(path);
    if (!m.ok()) {
      std::fprintf(stderr, "geodesic_bench: %s\n", std::string(m.status().message()).c_str());
      return 1;
    }
    meshes.emplace_back(std::filesystem::path(path).filename().string(), path, *std::move(m));
  }

  std::vector<std::string> rows;
  for (const auto& [label, path, m] : meshes) {
    absl::StatusOr<Row> row = BenchMesh(label, path, m, options);
    if (!row.ok()) {
      std::fprintf(stderr, "geodesic_bench: %s: %s\n", label.c_str(),
                   std::string(row.status().message()).c_str());
      return 1;
    }
    rows.insert(rows.end(), row->lines.begin(), row->lines.end());
    notes.insert(notes.end(), row->notes.begin(), row->notes.end());
  }

  std::printf(
      "| mesh | vertices | engine | sources | s/source wall | s/source CPU | peak RSS increase "
      "| CPU time / VTP's | max rel. diff vs VTP (VTP: vs ours, wavefront) |\n");
  std::printf("|---|---:|---|---:|---:|---:|---:|---:|---:|\n");
  for (const std::string& row : rows) std::printf("%s\n", row.c_str());
  std::printf("\n");
  for (const std::string& note : notes) std::printf("- %s\n", note.c_str());
  std::printf(
      "- vertex sources (fixed seed), the same for every engine; ours and CGAL: propagation + "
      "reading all vertex distances, mean over sources, each engine in its own forked child, "
      "memory = increase of ru_maxrss from just before the solver is made to the end (the mesh "
      "is in the baseline)\n");
  return 0;
}

}  // namespace
}  // namespace geodex

int main(int argc, char** argv) {
  geodex::Options options;
  CLI::App app{"Exact geodesics: ours vs CGAL's Surface_mesh_shortest_path"};
  app.add_option("--mesh", options.meshes, "mesh file (repeatable)")->check(CLI::ExistingFile);
  app.add_option("--sources", options.sources, "sources per mesh")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--cgal-large-sources", options.cgal_large_sources,
                 "CGAL sources on meshes with >= --large-vertices vertices")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--large-vertices", options.large_vertices,
                 "vertex count from which a mesh counts as large")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--vtp-dir", options.vtp_dir,
                 "VTP's sources (default: anchors/vtp beside the shared meshes)");
  bool no_cgal = false;
  app.add_flag("--no-cgal", no_cgal, "Skip CGAL (it needs ~9 GB on igea_134k)");
  bool no_windows = false;
  app.add_flag("--no-windows", no_windows,
               "Skip our window engine (it needs ~8 GB per source on 500K vertices)");
  CLI11_PARSE(app, argc, argv);
  options.cgal = !no_cgal;
  options.windows = !no_windows;
  return geodex::Run(std::move(options));
}
