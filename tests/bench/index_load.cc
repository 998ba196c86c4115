// index_load: what format 6.0 (index_format.h) saves and what it costs at
// load. For each index file: its bytes as it is and written as older
// builders wrote it (4.0 or 5.0: the vertex records with their corners, the
// twins and the face BVH stored), and the time to validate and load each
// image (Index::FromBytes, the copy of the image excluded; 6.0 derives the
// twins and the BVH there), the median of several loads; whether the two
// give the same spans. With --write-dir, each file is also written there as
// today's writer writes it (for the sections `geodex-query --info` lists).
//
//   index_load INDEX.gdx... [--repeats 5] [--write-dir DIR]

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "CLI/CLI.hpp"
#include "core/index/index.h"

namespace geodex {
namespace {

// Median seconds of `repeats` loads of `bytes` (-1 when it does not load);
// the last load in *out.
double LoadSeconds(const std::string& bytes, int repeats,
                   std::shared_ptr<const index::Index>* out) {
  std::vector<double> seconds;
  for (int r = 0; r < repeats; ++r) {
    std::string copy = bytes;
    const auto start = std::chrono::steady_clock::now();
    auto ix = index::Index::FromBytes(std::move(copy));
    seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    if (!ix.ok()) {
      std::fprintf(stderr, "%s\n", ix.status().ToString().c_str());
      return -1;
    }
    *out = *ix;
  }
  std::sort(seconds.begin(), seconds.end());
  return seconds[seconds.size() / 2];
}

template <typename T>
bool Same(std::span<const T> a, std::span<const T> b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size_bytes()) == 0;
}

int Run(const std::vector<std::string>& paths, int repeats, const std::string& write_dir) {
  std::printf("| index | format | MiB | load ms | older format | MiB | load ms | same spans |\n"
              "|---|---|---|---|---|---|---|---|\n");
  for (const std::string& path : paths) {
    auto opened = index::Index::Open(path);
    if (!opened.ok()) {
      std::fprintf(stderr, "%s\n", opened.status().ToString().c_str());
      return 1;
    }
    index::IndexData d = index::ToIndexData(**opened);
    d.coded_as_version_5 = false;
    auto now = index::SerializeIndex(d);
    d.coded_as_version_5 = true;
    auto older = index::SerializeIndex(d);
    if (!now.ok() || !older.ok()) {
      std::fprintf(stderr, "%s: cannot write it again\n", path.c_str());
      return 1;
    }
    if (!write_dir.empty()) {
      // The file as today's writer writes it, for geodex info's sections.
      const std::string to = write_dir + "/" + std::filesystem::path(path).filename().string();
      std::ofstream out(to, std::ios::binary);
      out.write(now->data(), static_cast<std::streamsize>(now->size()));
      if (!out.good()) {
        std::fprintf(stderr, "%s: cannot write\n", to.c_str());
        return 1;
      }
    }
    std::shared_ptr<const index::Index> a, b;
    const double ta = LoadSeconds(*now, repeats, &a), tb = LoadSeconds(*older, repeats, &b);
    if (ta < 0 || tb < 0) return 1;
    const bool same = Same(a->twins(), b->twins()) && Same(a->bvh_nodes(), b->bvh_nodes()) &&
                      Same(a->bvh_faces(), b->bvh_faces()) && Same(a->vertices(), b->vertices()) &&
                      Same(a->positions(), b->positions()) && Same(a->faces(), b->faces());
    auto mib = [](size_t bytes) { return bytes / 1048576.0; };
    std::printf("| %s | %u.%u | %.2f | %.1f | %u.%u | %.2f | %.1f | %s |\n", path.c_str(),
                a->header().format_major, a->header().format_minor, mib(now->size()), 1e3 * ta,
                b->header().format_major, b->header().format_minor, mib(older->size()), 1e3 * tb,
                same ? "yes" : "NO");
    if (!same) return 1;
  }
  return 0;
}

}  // namespace
}  // namespace geodex

int main(int argc, char** argv) {
  CLI::App app("index_load: format 6.0's bytes and load time against the older format");
  std::vector<std::string> paths;
  int repeats = 5;
  app.add_option("indexes", paths, "Index files")->required();
  std::string write_dir;
  app.add_option("--repeats", repeats, "Loads of each image")->check(CLI::PositiveNumber);
  app.add_option("--write-dir", write_dir, "Also write each index again, in today's format, here")
      ->check(CLI::ExistingDirectory);
  CLI11_PARSE(app, argc, argv);
  return geodex::Run(paths, repeats, write_dir);
}
