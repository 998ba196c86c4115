// geodesic_bench: single-source exact geodesic propagation, ours
// (ExactGeodesicSolver) against CGAL's Surface_mesh_shortest_path and VTP
// (Qin et al. 2016, the fastest published exact solver), in the same run, on
// the same mesh and the same sources. Prints a Markdown table.
//
//   geodesic_bench [--mesh PATH]... [--sources K] [--cgal-large-sources K]
//                  [--large-vertices N] [--vtp-dir DIR] [--no-cgal]
//
// Without --mesh: bunny_closed_30k.obj and igea_134k.obj from the shared mesh
// directory ($GEODEX_SHARED_MESHES, else GEODEX_SHARED_MESHES_DEFAULT), or,
// when neither is there, a generated icosphere (6 subdivisions, 40962
// vertices).
//
// What is measured, per mesh: each algorithm runs in its own forked child
// process, so neither sees the other's heap.
//  - time: seconds per source, mean over the sources, as wall clock and as
//    CPU time of the child (steadier when the machine is shared). One source
//    is the propagation plus reading every vertex distance into a vector.
//    Setup (our solver's per-mesh tables; CGAL's Surface_mesh copy) is not
//    included and is printed separately.
//  - memory: the increase of the child's peak RSS (getrusage RUSAGE_SELF
//    ru_maxrss) from just before the algorithm to the end of the last
//    propagation. The mesh is loaded in the parent before the fork, so it is
//    in the baseline of both; CGAL's own copy of it (its Surface_mesh) is built
//    in the child before the baseline, as the counterpart of our Mesh. The
//    peak is reset to the current RSS at the baseline (/proc/self/clear_refs,
//    "5") so that transient allocations made earlier do not hide the increase.
//    Our increase includes the solver's per-mesh tables.
//  - the ratio ours/CGAL of both, over the sources both ran; and the largest
//    relative difference between the two distance fields, as a sanity check.
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
#include <string>
#include <tuple>
#include <vector>

#include "CLI/CLI.hpp"
#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/match.h"
#include "absl/strings/str_format.h"
#include "core/geodesic/exact_geodesic.h"
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

ChildResult RunOurs(const Mesh& m, const std::vector<SurfacePoint>& sources, int keep) {
  ChildResult r;
  ResetPeakRss();
  r.baseline_kb = MaxRssKb();
  auto start = std::chrono::steady_clock::now();
  geodesic::ExactGeodesicSolver solver(m);
  r.setup_seconds = Seconds(start);
  std::vector<std::vector<double>> kept;
  for (size_t i = 0; i < sources.size(); ++i) {
    start = std::chrono::steady_clock::now();
    const double cpu_start = CpuSeconds();
    const absl::Status status = solver.Propagate({sources[i]});
    std::vector<double> distances = solver.VertexDistances();
    r.cpu_seconds.push_back(CpuSeconds() - cpu_start);
    r.seconds.push_back(Seconds(start));
    if (!status.ok()) {
      r.error = std::string(status.message());
      return r;
    }
    r.windows += solver.stats().windows_created;
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
  std::string cells;
  std::vector<std::string> notes;
};

std::string VtpDir(const Options& options) {
  if (!options.vtp_dir.empty()) return options.vtp_dir;
  return (std::filesystem::path(SharedMeshDir()) / ".." / "anchors" / "vtp").lexically_normal();
}

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

  std::fprintf(stderr, "%s: ours, %d source(s)...\n", label.c_str(), options.sources);
  absl::StatusOr<ChildResult> ours =
      InChild([&] { return RunOurs(m, sources, options.sources); });
  if (!ours.ok()) return ours.status();
  if (!ours->error.empty()) return absl::InternalError("ours: " + ours->error);
  const double ours_mean = Mean(ours->seconds, ours->seconds.size());
  const double ours_cpu = Mean(ours->cpu_seconds, ours->cpu_seconds.size());
  const int64_t ours_kb = ours->peak_kb - ours->baseline_kb;

  std::string cgal_cells = "| - | - | - | - |";
  if (k_cgal > 0) {
    std::fprintf(stderr, "%s: CGAL, %d source(s)...\n", label.c_str(), k_cgal);
    absl::StatusOr<ChildResult> cgal = InChild([&] { return RunCgal(m, cgal_sources); });
    if (!cgal.ok()) return absl::InternalError("CGAL: " + std::string(cgal.status().message()));
    if (!cgal->error.empty()) return absl::InternalError("CGAL: " + cgal->error);
    double max_relative = 0;
    for (int s = 0; s < k_cgal; ++s) {
      max_relative = std::max(max_relative,
                              MaxRelativeDifference(ours->distances[s], cgal->distances[s]));
    }
    const double cgal_mean = Mean(cgal->seconds, k_cgal);
    const double cgal_cpu = Mean(cgal->cpu_seconds, k_cgal);
    const int64_t cgal_kb = cgal->peak_kb - cgal->baseline_kb;
    cgal_cells = absl::StrFormat("| %.3f (%.3f) | %.3f (%.3f) | %s | %.1e |", cgal_mean, cgal_cpu,
                                 Mean(ours->seconds, k_cgal) / cgal_mean,
                                 Mean(ours->cpu_seconds, k_cgal) / cgal_cpu, Megabytes(cgal_kb),
                                 max_relative);
    row.notes.push_back(absl::StrFormat(
        "%s: setup ours %.3f s (solver tables), CGAL %.3f s (Surface_mesh copy); peak RSS of "
        "the children: ours %s, CGAL %s (baselines %s, %s); CGAL/ours memory %.2f",
        label, ours->setup_seconds, cgal->setup_seconds, Megabytes(ours->peak_kb),
        Megabytes(cgal->peak_kb), Megabytes(ours->baseline_kb), Megabytes(cgal->baseline_kb),
        static_cast<double>(cgal_kb) / ours_kb));
    if (k_cgal < options.sources) {
      row.notes.push_back(absl::StrFormat(
          "%s: CGAL ran %d of the %d sources (>= %d vertices); its ratios use those %d only",
          label, k_cgal, options.sources, options.large_vertices, k_cgal));
    }
  }

  std::string vtp_cells = "| - | - | - | - |";
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
    absl::StatusOr<VtpResult> vtp = RunVtp(binary, obj, source_vertices, m.num_vertices());
    if (temporary_obj) std::filesystem::remove(obj);
    if (!vtp.ok()) return vtp.status();
    double max_relative = 0;
    for (int s = 0; s < options.sources; ++s) {
      max_relative = std::max(max_relative,
                              MaxRelativeDifference(ours->distances[s], vtp->distances[s]));
    }
    const double vtp_mean = Mean(vtp->propagation_seconds, options.sources);
    vtp_cells = absl::StrFormat("| %.3f (%.3f) | %.2f | %s | %.1e |", vtp_mean,
                                Mean(vtp->process_seconds, options.sources), ours_mean / vtp_mean,
                                Megabytes(vtp->peak_kb), max_relative);
  }
  row.cells = absl::StrFormat("| %s | %d | %d / %d | %.3f (%.3f) | %s ", label, m.num_vertices(),
                              options.sources, k_cgal, ours_mean, ours_cpu, Megabytes(ours_kb)) +
              cgal_cells.substr(0, cgal_cells.size() - 1) + vtp_cells;
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
    rows.push_back(row->cells);
    notes.insert(notes.end(), row->notes.begin(), row->notes.end());
  }

  std::printf(
      "| mesh | vertices | sources ours / CGAL | ours s/source wall (CPU) | ours peak RSS "
      "increase | CGAL s/source wall (CPU) | time ours/CGAL wall (CPU) | CGAL peak RSS increase | "
      "max rel. diff CGAL | VTP s/source propagation (whole process) | time ours/VTP | VTP "
      "process peak RSS | max rel. diff VTP |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const std::string& row : rows) std::printf("%s\n", row.c_str());
  std::printf("\n");
  for (const std::string& note : notes) std::printf("- %s\n", note.c_str());
  std::printf(
      "- vertex sources (fixed seed), the same for all three; ours and CGAL: propagation + "
      "reading all vertex distances, mean over sources, wall clock and (in parentheses) CPU time "
      "of the child, memory = increase of ru_maxrss from just before the algorithm to the end, "
      "each in its own forked child (the mesh is in the baseline); VTP: its own printed "
      "propagation time and (in parentheses) the wall time of its whole process (reading the OBJ, "
      "writing every distance), memory = peak RSS of that process, mesh included; time ours/VTP "
      "= ours wall / VTP propagation\n");
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
  CLI11_PARSE(app, argc, argv);
  options.cgal = !no_cgal;
  return geodex::Run(std::move(options));
}
