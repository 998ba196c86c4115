#include "tests/bench/geodesic_bench_lib.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <tuple>
#include <utility>

#include "absl/strings/match.h"
#include "absl/strings/str_format.h"
#include "core/mesh/generators.h"
#include "core/mesh/mesh_io.h"
#include "tests/bench/bench_table.h"
#include "tests/bench/bench_timing.h"
#include "tests/bench/geodesic_bench_engines.h"

namespace geodex::bench {
namespace {

namespace fs = std::filesystem;
using mesh::Mesh;
using mesh::SurfacePoint;

// One mesh's table rows and notes as they are measured.
struct MeshReport {
  std::vector<Measured> measured;
  std::vector<std::string> notes;
};

std::string SharedMeshDir() {
  if (const char* env = std::getenv("GEODEX_SHARED_MESHES"); env != nullptr && *env != '\0') {
    return env;
  }
  return GEODEX_SHARED_MESHES_DEFAULT;
}

std::string VtpDir(const GeodesicBenchOptions& options) {
  if (!options.vtp_dir.empty()) return options.vtp_dir;
  return (fs::path(SharedMeshDir()) / ".." / "anchors" / "vtp").lexically_normal();
}

// Ours, the wavefront engine and (unless skipped) the window engine.
absl::Status MeasureOurs(const std::string& label, const Mesh& m,
                         const std::vector<int32_t>& sources, const GeodesicBenchOptions& options,
                         MeshReport* report) {
  for (const bool wavefront : {true, false}) {
    const char* engine = wavefront ? "ours, wavefront (rows)" : "ours, windows";
    if (!wavefront && options.no_windows) continue;
    std::fprintf(stderr, "%s: %s, %d source(s)...\n", label.c_str(), engine, options.sources);
    absl::StatusOr<ChildResult> r =
        InChild([&] { return RunOurs(m, sources, wavefront, options.sources); });
    if (!r.ok()) return r.status();
    if (!r->error.empty()) return absl::InternalError(std::string(engine) + ": " + r->error);
    report->notes.push_back(absl::StrFormat(
        "%s, %s: setup %.3f s (solver tables), %.3g windows created per source", label, engine,
        r->setup_seconds, static_cast<double>(r->windows) / options.sources));
    report->measured.push_back({engine, options.sources, Mean(r->seconds, r->seconds.size()),
                                Mean(r->cpu_seconds, r->cpu_seconds.size()),
                                Megabytes(r->peak_kb - r->baseline_kb), std::move(r->distances)});
  }
  return absl::OkStatus();
}

absl::Status MeasureCgal(const std::string& label, const Mesh& m,
                         const std::vector<SurfacePoint>& sources, MeshReport* report) {
  const int k = static_cast<int>(sources.size());
  std::fprintf(stderr, "%s: CGAL, %d source(s)...\n", label.c_str(), k);
  absl::StatusOr<ChildResult> r = InChild([&] { return RunCgal(m, sources); });
  if (!r.ok()) return absl::InternalError("CGAL: " + std::string(r.status().message()));
  if (!r->error.empty()) return absl::InternalError("CGAL: " + r->error);
  report->notes.push_back(
      absl::StrFormat("%s, CGAL: setup %.3f s (Surface_mesh copy)", label, r->setup_seconds));
  report->measured.push_back({"CGAL", k, Mean(r->seconds, k), Mean(r->cpu_seconds, k),
                              Megabytes(r->peak_kb - r->baseline_kb), std::move(r->distances)});
  return absl::OkStatus();
}

// VTP on `path`, or on an OBJ of `m` written for it when `path` is not one.
absl::StatusOr<VtpResult> RunVtpOnMesh(const std::string& binary, const std::string& path,
                                       const Mesh& m, const std::vector<int32_t>& sources) {
  std::string obj = path;
  const bool temporary_obj = !absl::EndsWith(path, ".obj");
  if (temporary_obj) {
    obj = (fs::temp_directory_path() / absl::StrFormat("geodesic_bench_%d.obj", getpid())).string();
    if (absl::Status written = mesh::WriteObj(m, obj); !written.ok()) return written;
  }
  absl::StatusOr<VtpResult> r = RunVtp(binary, obj, sources, m.num_vertices());
  if (temporary_obj) fs::remove(obj);
  return r;
}

// VTP, built here from its sources; a note when they are absent.
absl::Status MeasureVtp(const std::string& label, const std::string& path, const Mesh& m,
                        const std::vector<int32_t>& sources, const GeodesicBenchOptions& options,
                        MeshReport* report) {
  const std::string vtp_dir = VtpDir(options);
  if (!fs::exists(fs::path(vtp_dir) / "build.sh")) {
    report->notes.push_back(absl::StrFormat("%s: VTP skipped: no %s/build.sh", label, vtp_dir));
    return absl::OkStatus();
  }
  const std::string binary = fs::absolute("geodesic_bench_vtp").string();
  if (absl::Status built = BuildVtp(vtp_dir, binary); !built.ok()) return built;
  std::fprintf(stderr, "%s: VTP, %d source(s)...\n", label.c_str(), options.sources);
  absl::StatusOr<VtpResult> r = RunVtpOnMesh(binary, path, m, sources);
  if (!r.ok()) return r.status();
  // VTP prints clock(), the process's CPU time: its figure sits in the CPU
  // column.
  report->measured.push_back({"VTP", options.sources, Mean(r->process_seconds, options.sources),
                              Mean(r->propagation_seconds, options.sources),
                              Megabytes(r->peak_kb) + " (process)", std::move(r->distances)});
  report->notes.push_back(absl::StrFormat(
      "%s, VTP: wall = its whole process (reading the OBJ, writing every distance); CPU = its "
      "printed propagation time; memory = the process's peak RSS, mesh included",
      label));
  return absl::OkStatus();
}

// One mesh, every engine. `path`: the mesh file, or empty for a generated
// mesh (VTP then gets an OBJ written here).
absl::StatusOr<MeshReport> BenchMesh(const std::string& label, const std::string& path,
                                     const Mesh& m, const GeodesicBenchOptions& options) {
  const int k_cgal = CgalSourceCount(options, m.num_vertices());
  const std::vector<int32_t> source_vertices = PickSources(m, options.sources);
  std::vector<SurfacePoint> cgal_sources;
  for (int i = 0; i < k_cgal; ++i) {
    cgal_sources.push_back(*mesh::VertexPoint(m, source_vertices[i]));
  }
  MeshReport report;
  if (absl::Status s = MeasureOurs(label, m, source_vertices, options, &report); !s.ok()) return s;
  if (k_cgal > 0) {
    if (absl::Status s = MeasureCgal(label, m, cgal_sources, &report); !s.ok()) return s;
  }
  if (absl::Status s = MeasureVtp(label, path, m, source_vertices, options, &report); !s.ok()) {
    return s;
  }
  return report;
}

// The cell of `e`'s CPU time over VTP's.
std::string CpuRatio(const Measured& e, const Measured* vtp) {
  if (vtp == nullptr || vtp == &e) return "-";
  return absl::StrFormat("%.2f", e.cpu / vtp->cpu);
}

// The cell of the largest relative difference of `e`'s distances from
// `other`'s, over the sources both have.
std::string DifferenceCell(const Measured& e, const Measured* other) {
  if (other == nullptr || other == &e) return "-";
  double worst = 0;
  const size_t n = std::min(e.distances.size(), other->distances.size());
  for (size_t s = 0; s < n; ++s) {
    worst = std::max(worst, MaxRelativeDifference(e.distances[s], other->distances[s]));
  }
  return n == 0 ? "-" : absl::StrFormat("%.1e", worst);
}

using LabelledMesh = std::tuple<std::string, std::string, Mesh>;  // label, path, mesh

// --mesh's meshes, or the shared directory's, or an icosphere (with a note).
// Errors: a mesh that cannot be read.
absl::StatusOr<std::vector<LabelledMesh>> LoadMeshes(GeodesicBenchOptions& options,
                                                     std::vector<std::string>* notes) {
  std::vector<LabelledMesh> meshes;
  if (options.meshes.empty()) {
    const fs::path dir = SharedMeshDir();
    for (const char* name : {"bunny_closed_30k.obj", "igea_134k.obj"}) {
      if (fs::exists(dir / name)) options.meshes.push_back((dir / name).string());
    }
    if (options.meshes.empty()) {
      notes->push_back(absl::StrFormat(
          "no shared meshes in '%s' (set GEODEX_SHARED_MESHES): using a generated icosphere "
          "(6 subdivisions)",
          dir.string()));
      meshes.emplace_back("icosphere_6", "", mesh::gen::Sphere(6, 1.0));
    }
  }
  for (const std::string& path : options.meshes) {
    absl::StatusOr<Mesh> m = mesh::LoadMesh(path);
    if (!m.ok()) return m.status();
    meshes.emplace_back(fs::path(path).filename().string(), path, *std::move(m));
  }
  return meshes;
}

}  // namespace

std::unique_ptr<CLI::App> GeodesicBenchFlags(GeodesicBenchOptions* options) {
  auto app =
      std::make_unique<CLI::App>("Exact geodesics: ours vs CGAL's Surface_mesh_shortest_path");
  app->add_option("--mesh", options->meshes, "mesh file (repeatable)")->check(CLI::ExistingFile);
  app->add_option("--sources", options->sources, "sources per mesh")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app->add_option("--cgal-large-sources", options->cgal_large_sources,
                  "CGAL sources on meshes with >= --large-vertices vertices")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app->add_option("--large-vertices", options->large_vertices,
                  "vertex count from which a mesh counts as large")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app->add_option("--vtp-dir", options->vtp_dir,
                  "VTP's sources (default: anchors/vtp beside the shared meshes)");
  app->add_flag("--no-cgal", options->no_cgal, "Skip CGAL (it needs ~9 GB on igea_134k)");
  app->add_flag("--no-windows", options->no_windows,
                "Skip our window engine (it needs ~8 GB per source on 500K vertices)");
  return app;
}

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

int CgalSourceCount(const GeodesicBenchOptions& options, int32_t num_vertices) {
  if (options.no_cgal) return 0;
  return num_vertices >= options.large_vertices
             ? std::min(options.sources, options.cgal_large_sources)
             : options.sources;
}

std::string Megabytes(int64_t kb) { return absl::StrFormat("%.1f MB", kb / 1024.0); }

std::vector<std::string> ComparisonRows(const std::string& label, int32_t num_vertices,
                                        const std::vector<Measured>& measured) {
  const Measured* vtp = nullptr;
  for (const Measured& other : measured) {
    if (other.engine == "VTP") vtp = &other;
  }
  std::vector<std::string> rows;
  for (const Measured& e : measured) {
    const Measured* reference = e.engine == "VTP" ? &measured.front() : vtp;
    rows.push_back(MarkdownRow({label, absl::StrFormat("%d", num_vertices), e.engine,
                                absl::StrFormat("%d", e.sources), absl::StrFormat("%.3f", e.wall),
                                absl::StrFormat("%.3f", e.cpu), e.memory, CpuRatio(e, vtp),
                                DifferenceCell(e, reference)}));
  }
  return rows;
}

std::string ResultsReport(const std::vector<std::string>& rows,
                          const std::vector<std::string>& notes) {
  std::string out = MarkdownHeader(
      {"mesh", "vertices", "engine", "sources", "s/source wall", "s/source CPU",
       "peak RSS increase", "CPU time / VTP's", "max rel. diff vs VTP (VTP: vs ours, wavefront)"},
      "lrlrrrrrr");
  for (const std::string& row : rows) out += row + "\n";
  out += "\n";
  for (const std::string& note : notes) out += "- " + note + "\n";
  out +=
      "- vertex sources (fixed seed), the same for every engine; ours and CGAL: propagation + "
      "reading all vertex distances, mean over sources, each engine in its own forked child, "
      "memory = increase of ru_maxrss from just before the solver is made to the end (the mesh "
      "is in the baseline)\n";
  return out;
}

int RunGeodesicBench(GeodesicBenchOptions options) {
  std::vector<std::string> notes;
  absl::StatusOr<std::vector<LabelledMesh>> meshes = LoadMeshes(options, &notes);
  if (!meshes.ok()) {
    std::fprintf(stderr, "geodesic_bench: %s\n", std::string(meshes.status().message()).c_str());
    return 1;
  }
  std::vector<std::string> rows;
  for (const auto& [label, path, m] : *meshes) {
    absl::StatusOr<MeshReport> report = BenchMesh(label, path, m, options);
    if (!report.ok()) {
      std::fprintf(stderr, "geodesic_bench: %s: %s\n", label.c_str(),
                   std::string(report.status().message()).c_str());
      return 1;
    }
    for (std::string& row : ComparisonRows(label, m.num_vertices(), report->measured)) {
      rows.push_back(std::move(row));
    }
    notes.insert(notes.end(), report->notes.begin(), report->notes.end());
  }
  std::printf("%s", ResultsReport(rows, notes).c_str());
  return 0;
}

}  // namespace geodex::bench
