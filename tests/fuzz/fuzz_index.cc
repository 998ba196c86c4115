// libFuzzer target: index::Index::FromBytes (core/index/index.h). When an
// image is accepted, every span is read end to end, so that ASan reports a
// span that Validate let point past the image.
//
// Almost every mutation of an image breaks one of its XXH64 checksums, which
// would stop the reader at the first check. So each input is tried twice: as
// it is, and with its file size and checksums rewritten (where the header and
// section table fit) so that the structural checks behind them get fuzzed.

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>

#include "core/index/index.h"
#include "core/index/index_format.h"
#include "xxhash.h"

namespace {

template <typename Span, typename Value>
double SumBytes(Span span, Value value) {
  double sum = 0;
  for (const auto& element : span) sum += value(element);
  return sum;
}

// Reads every byte of each element: element types are plain structs, and a
// byte-wise read needs no knowledge of their fields.
template <typename T>
double SumRaw(std::span<const T> span) {
  return SumBytes(span, [](const T& element) {
    const unsigned char* bytes = reinterpret_cast<const unsigned char*>(&element);
    double sum = 0;
    for (size_t i = 0; i < sizeof(T); ++i) sum += bytes[i];
    return sum;
  });
}

using geodex::index::FileHeader;
using geodex::index::SectionEntry;

// Rewrites file_size, the checksum of every section that fits, the table
// checksum and the header checksum (the reader's algorithm: XXH64 of the
// header with its checksum field zero), as a writer would have.
void RepairChecksums(std::string& image) {
  const size_t n = image.size();
  if (n < sizeof(FileHeader)) return;
  char* p = image.data();
  FileHeader h;
  std::memcpy(&h, p, sizeof(h));
  if (h.header_size < sizeof(FileHeader) || h.header_size > n) return;
  h.file_size = n;
  const uint64_t table_bytes = uint64_t{h.num_sections} * sizeof(SectionEntry);
  if (h.section_table_offset <= n && table_bytes <= n - h.section_table_offset) {
    for (uint32_t i = 0; i < h.num_sections; ++i) {
      char* at = p + h.section_table_offset + i * sizeof(SectionEntry);
      SectionEntry e;
      std::memcpy(&e, at, sizeof(e));
      if (e.offset > n || e.size > n - e.offset) continue;
      e.checksum = XXH64(p + e.offset, e.size, 0);
      std::memcpy(at, &e, sizeof(e));
    }
    h.table_checksum = XXH64(p + h.section_table_offset, table_bytes, 0);
  }
  h.header_checksum = 0;
  std::memcpy(p, &h, sizeof(h));
  h.header_checksum = XXH64(p, h.header_size, 0);
  std::memcpy(p, &h, sizeof(h));
}

void ReadIndex(std::string bytes) {
  auto index = geodex::index::Index::FromBytes(std::move(bytes));
  if (!index.ok()) return;
  const geodex::index::Index& ix = **index;
  double sum = SumRaw(ix.positions()) + SumRaw(ix.faces()) + SumRaw(ix.twins()) +
               SumRaw(ix.samples()) + SumRaw(ix.sample_distances()) + SumRaw(ix.vertices()) +
               SumRaw(ix.triangles()) + SumRaw(ix.bvh_nodes()) + SumRaw(ix.bvh_faces());
  if (const auto* accuracy = ix.accuracy()) {
    sum += SumRaw(std::span<const geodex::index::AccuracyRecord>(accuracy, 1));
  }
  sum += ix.report().size() + ix.builder_version().size();
  volatile double sink = sum;
  (void)sink;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string image(reinterpret_cast<const char*>(data), size);
  ReadIndex(image);
  RepairChecksums(image);
  ReadIndex(std::move(image));
  return 0;
}
