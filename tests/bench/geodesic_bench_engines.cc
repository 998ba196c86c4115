#include "tests/bench/geodesic_bench_engines.h"

#include <sys/resource.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <utility>

#include "absl/strings/str_format.h"
#include "core/common/file_util.h"
#include "core/geodesic/exact_geodesic.h"
#include "core/geodesic/vertex_geodesic.h"
#include "tests/bench/bench_timing.h"
#include "tests/integration/cgal_reference.h"

namespace geodex::bench {
namespace {

using mesh::Mesh;
using mesh::SurfacePoint;

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

// The child's side of InChild: runs `work` and writes its result to `fd`.
[[noreturn]] void RunAndReport(const std::function<ChildResult()>& work, int fd) {
  const std::string bytes = SerializeChildResult(work());
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = write(fd, bytes.data() + done, bytes.size() - done);
    if (n <= 0) _exit(2);
    done += n;
  }
  close(fd);
  _exit(0);
}

// Everything readable from `fd` until its end.
std::string ReadAll(int fd) {
  std::string bytes;
  char buffer[1 << 16];
  for (ssize_t n; (n = read(fd, buffer, sizeof(buffer))) != 0;) {
    if (n < 0) {
      if (errno == EINTR) continue;
      break;
    }
    bytes.append(buffer, n);
  }
  return bytes;
}

// One VTP process from `source` into `out` (its printed lines into `log`).
// Returns its peak RSS (kB). Errors: Internal when it cannot start or fails.
absl::StatusOr<int64_t> RunVtpProcess(const std::string& binary, const std::string& obj,
                                      int32_t source, const std::string& out,
                                      const std::string& log) {
  const pid_t pid = fork();
  if (pid < 0) return absl::InternalError(std::strerror(errno));
  if (pid == 0) {
    if (!std::freopen(log.c_str(), "w", stdout)) _exit(127);
    const std::string vertex = std::to_string(source);
    execl(binary.c_str(), binary.c_str(), "-m", obj.c_str(), "-s", vertex.c_str(), "-o",
          out.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  int wstatus = 0;
  rusage usage{};
  if (wait4(pid, &wstatus, 0, &usage) != pid || !WIFEXITED(wstatus) || WEXITSTATUS(wstatus) != 0) {
    return absl::InternalError(absl::StrFormat("VTP failed on source vertex %d", source));
  }
  return usage.ru_maxrss;
}

// The plain figures of a ChildResult, written to the pipe in one piece.
struct ChildFigures {
  double setup_seconds;
  int64_t baseline_kb;
  int64_t peak_kb;
  int64_t windows;
};

}  // namespace

std::string SerializeChildResult(const ChildResult& r) {
  ByteWriter w;
  w.PutVector(std::vector<char>(r.error.begin(), r.error.end()));
  w.Put(ChildFigures{r.setup_seconds, r.baseline_kb, r.peak_kb, r.windows});
  for (const std::vector<double>* v : {&r.seconds, &r.cpu_seconds}) w.PutVector(*v);
  w.Put<uint64_t>(r.distances.size());
  for (const std::vector<double>& d : r.distances) w.PutVector(d);
  return std::move(w.bytes());
}

absl::StatusOr<ChildResult> DeserializeChildResult(std::string bytes) {
  ByteReader in(bytes, "result from child process");
  ChildResult r;
  std::vector<char> error;
  ChildFigures figures;
  uint64_t n = 0;
  bool ok = in.GetVector(&error).ok() && in.Get(&figures).ok() && in.GetVector(&r.seconds).ok() &&
            in.GetVector(&r.cpu_seconds).ok() && in.Get(&n).ok();
  for (uint64_t i = 0; ok && i < n; ++i) ok = in.GetVector(&r.distances.emplace_back()).ok();
  if (!ok) return absl::InternalError("truncated result from child process");
  r.error.assign(error.begin(), error.end());
  r.setup_seconds = figures.setup_seconds;
  r.baseline_kb = figures.baseline_kb;
  r.peak_kb = figures.peak_kb;
  r.windows = figures.windows;
  return r;
}

absl::StatusOr<ChildResult> InChild(const std::function<ChildResult()>& work) {
  int fds[2];
  if (pipe(fds) != 0) return absl::InternalError(std::strerror(errno));
  std::fflush(stdout);
  std::fflush(stderr);
  const pid_t pid = fork();
  if (pid < 0) return absl::InternalError(std::strerror(errno));
  if (pid == 0) {
    close(fds[0]);
    RunAndReport(work, fds[1]);
  }
  close(fds[1]);
  std::string bytes = ReadAll(fds[0]);
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
  return DeserializeChildResult(std::move(bytes));
}

ChildResult RunOurs(const Mesh& m, const std::vector<int32_t>& sources, bool wavefront, int keep) {
  ChildResult r;
  ResetPeakRss();
  r.baseline_kb = MaxRssKb();
  Clock::time_point start = Clock::now();
  std::unique_ptr<geodesic::ExactGeodesicSolver> windows;
  std::unique_ptr<geodesic::VertexGeodesicSolver> front;
  if (wavefront) {
    front = std::make_unique<geodesic::VertexGeodesicSolver>(m);
  } else {
    windows = std::make_unique<geodesic::ExactGeodesicSolver>(m);
  }
  r.setup_seconds = SecondsSince(start);
  std::vector<std::vector<double>> kept;
  for (size_t i = 0; i < sources.size(); ++i) {
    start = Clock::now();
    const double cpu_start = ProcessCpuSeconds();
    absl::Status status;
    std::vector<double> distances;
    if (wavefront) {
      status = front->Propagate({sources[i]});
      distances = front->VertexDistances();
    } else {
      status = windows->Propagate({*mesh::VertexPoint(m, sources[i])});
      distances = windows->VertexDistances();
    }
    r.cpu_seconds.push_back(ProcessCpuSeconds() - cpu_start);
    r.seconds.push_back(SecondsSince(start));
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
  Clock::time_point start = Clock::now();
  auto cgal = cgal_reference::CgalShortestPaths::Create(m);
  r.setup_seconds = SecondsSince(start);
  if (!cgal.ok()) {
    r.error = std::string(cgal.status().message());
    return r;
  }
  ResetPeakRss();
  r.baseline_kb = MaxRssKb();
  std::vector<std::vector<double>> kept;
  for (const SurfacePoint& source : sources) {
    start = Clock::now();
    const double cpu_start = ProcessCpuSeconds();
    absl::StatusOr<std::vector<double>> distances = (*cgal)->Distances(source);
    r.cpu_seconds.push_back(ProcessCpuSeconds() - cpu_start);
    r.seconds.push_back(SecondsSince(start));
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

absl::Status BuildVtp(const std::string& vtp_dir, const std::string& binary) {
  if (std::filesystem::exists(binary)) return absl::OkStatus();
  const std::string command =
      absl::StrFormat("bash '%s/build.sh' '%s' > /dev/null 2>&1", vtp_dir, binary);
  if (std::system(command.c_str()) != 0 || !std::filesystem::exists(binary)) {
    return absl::InternalError("building VTP failed: " + command);
  }
  return absl::OkStatus();
}

absl::StatusOr<VtpResult> RunVtp(const std::string& binary, const std::string& obj,
                                 const std::vector<int32_t>& vertices, int32_t num_vertices) {
  VtpResult r;
  const std::string out = std::filesystem::temp_directory_path() /
                          absl::StrFormat("geodesic_bench_vtp_%d.txt", getpid());
  const std::string log = out + ".log";
  for (int32_t v : vertices) {
    const Clock::time_point start = Clock::now();
    const absl::StatusOr<int64_t> peak_kb = RunVtpProcess(binary, obj, v, out, log);
    if (!peak_kb.ok()) return peak_kb.status();
    r.process_seconds.push_back(SecondsSince(start));
    r.peak_kb = std::max(r.peak_kb, *peak_kb);
    std::ifstream printed(log);
    const double propagation = VtpPropagationSeconds(printed);
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

double VtpPropagationSeconds(std::istream& printed) {
  std::string word;
  double propagation = -1;
  while (printed >> word) {
    if (word == "took" && printed >> propagation) break;
  }
  return propagation;
}

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

}  // namespace geodex::bench
