#include "core/index/index_sections.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "absl/strings/str_format.h"
#include "core/common/status_macros.h"
#include "core/index/input_id_checks.h"

#define XXH_STATIC_LINKING_ONLY  // XXH64_state_t on the stack
#include "xxhash.h"

namespace geodex::index::internal {
namespace {

bool InRange(int64_t x, int64_t lo, int64_t hi) { return x >= lo && x < hi; }
// Non-negative and not NaN; +inf allowed.
bool NonNegative(float x) { return x >= 0; }

}  // namespace

// Index of `id` in kSpecs, or -1 for an id this reader does not know.
int SpecIndex(uint32_t id) {
  for (size_t i = 0; i < kNumSpecs; ++i) {
    if (static_cast<uint32_t>(kSpecs[i].id) == id) return static_cast<int>(i);
  }
  return -1;
}

// Elements a known section must hold; nullopt when any number is fine. Every
// product fits in uint64_t (the counts are at most 2^31).
std::optional<uint64_t> ExpectedCount(SectionId id, const Counts& c) {
  switch (id) {
    case SectionId::kPositions:
      return 3 * c.num_vertices;
    case SectionId::kFaces:
    case SectionId::kTwins:
      return 3 * c.num_faces;
    case SectionId::kSamples:
      return c.num_samples;
    case SectionId::kSampleDistances:
      return c.num_samples * c.num_samples;
    case SectionId::kSampleDistancesLower:
    case SectionId::kSampleDistancesCoded:
      return c.num_samples * (c.num_samples - std::min<uint64_t>(c.num_samples, 1)) / 2;
    case SectionId::kVertexRecords:
    case SectionId::kCompactVertexRecords:
      return c.num_vertices;
    case SectionId::kTriangles:
      return c.num_triangles;
    case SectionId::kFaceBvh:
      return c.num_bvh_nodes;
    case SectionId::kBvhFaces:
      return c.num_bvh_nodes > 0 ? c.num_faces : 0;
    case SectionId::kReport:
    case SectionId::kAccuracy:
    case SectionId::kInputFaces:
    case SectionId::kVertexCopies:
    case SectionId::kCoarseFaces:
    case SectionId::kSplitFaces:
    case SectionId::kSplitCoarseFaces:
    case SectionId::kSplitPieces:
    case SectionId::kSplitFaceCodes:
    case SectionId::kSplitPieceCodes:
    case SectionId::kSpreadBounds:
    case SectionId::kDistanceCode:
      return std::nullopt;
  }
  return std::nullopt;
}

uint64_t AlignUp(uint64_t x) { return (x + kAlignment - 1) / kAlignment * kAlignment; }

uint64_t Checksum(const void* data, size_t size) { return XXH64(data, size, 0); }

// XXH64 of the first `header_size` bytes with the header_checksum field read
// as zero. `header_size` >= sizeof(FileHeader) (a later minor version may
// append fields; they are covered too).
uint64_t HeaderChecksum(const uint8_t* p, size_t header_size) {
  constexpr size_t kField = offsetof(FileHeader, header_checksum);
  constexpr uint64_t kZero = 0;
  XXH64_state_t state;
  XXH64_reset(&state, 0);
  XXH64_update(&state, p, kField);
  XXH64_update(&state, &kZero, sizeof(kZero));
  XXH64_update(&state, p + kField + sizeof(kZero), header_size - kField - sizeof(kZero));
  return XXH64_digest(&state);
}

// The accuracy section: absent or one record of finite, non-negative figures.
absl::Status CheckAccuracy(std::span<const AccuracyRecord> records, absl::StatusCode code) {
  if (records.empty()) return absl::OkStatus();
  if (records.size() > 1) {
    return absl::Status(code, absl::StrFormat("accuracy: %d records, expected 1", records.size()));
  }
  const AccuracyRecord& r = records[0];
  std::vector<float> values = {r.scale_length, r.uniform_rms, r.uniform_far_p99};
  for (int b = 0; b < kAccuracyBins; ++b) {
    values.insert(values.end(), {r.unfold_bound[0][b], r.unfold_bound[1][b]});
    for (int k = 0; k < 4; ++k) values.push_back(r.trace_bound[k][b]);
  }
  for (int b = 0; b < 4; ++b) values.insert(values.end(), {r.rms[b], r.p99[b]});
  for (float v : values) {
    if (!(v >= 0) || !std::isfinite(v)) {
      return absl::Status(code, "accuracy: a figure is negative, NaN or infinite");
    }
  }
  if (!(r.scale_length > 0) || r.bound_quantile_permille > 1000) {
    return absl::Status(code, "accuracy: bad scale length or quantile");
  }
  return absl::OkStatus();
}

// The spread-bound section: absent, or one record of finite, non-negative
// figures beside an accuracy record.
absl::Status CheckSpreadBounds(std::span<const SpreadBoundRecord> records, size_t num_accuracy,
                               absl::StatusCode code) {
  if (records.empty()) return absl::OkStatus();
  if (records.size() > 1 || num_accuracy != 1) {
    return absl::Status(code,
                        absl::StrFormat("spread bounds: %d records beside %d accuracy records",
                                        records.size(), num_accuracy));
  }
  for (int k = 0; k < 2; ++k) {
    for (int b = 0; b < kAccuracyBins; ++b) {
      for (float v : {records[0].epsilon[k][b], records[0].factor[k][b]}) {
        if (!(v >= 0) || !std::isfinite(v)) {
          return absl::Status(code, "spread bounds: a figure is negative, NaN or infinite");
        }
      }
    }
  }
  return absl::OkStatus();
}

namespace {

absl::Status Fail(absl::StatusCode code, std::string message) {
  return absl::Status(code, message);
}

// The mesh's coordinates finite, and the faces', twins' and samples' ids in
// range.
absl::Status CheckMeshIds(const Contents& c, absl::StatusCode code) {
  const int64_t nv = static_cast<int64_t>(c.counts.num_vertices);
  const int64_t nf = static_cast<int64_t>(c.counts.num_faces);
  for (size_t i = 0; i < c.positions.size(); ++i) {
    if (!std::isfinite(c.positions[i])) {
      return Fail(code, absl::StrFormat("vertex %d: coordinate %d is not finite (%g)", i / 3, i % 3,
                                        c.positions[i]));
    }
  }
  for (size_t i = 0; i < c.faces.size(); ++i) {
    if (!InRange(c.faces[i], 0, nv)) {
      return Fail(code, absl::StrFormat("face %d: vertex id %d out of range [0, %d)", i / 3,
                                        c.faces[i], nv));
    }
  }
  for (size_t i = 0; i < c.twins.size(); ++i) {
    if (!InRange(c.twins[i], -1, 3 * nf)) {
      return Fail(code, absl::StrFormat("half-edge %d: twin %d out of range [-1, %d)", i,
                                        c.twins[i], 3 * nf));
    }
  }
  for (size_t i = 0; i < c.samples.size(); ++i) {
    if (!InRange(c.samples[i], 0, nv)) {
      return Fail(code, absl::StrFormat("sample %d: vertex id %d out of range [0, %d)", i,
                                        c.samples[i], nv));
    }
  }
  return absl::OkStatus();
}

// The sample matrix in whichever layout it is given.
absl::Status CheckSampleMatrix(const Contents& c, absl::StatusCode code) {
  const int64_t m = static_cast<int64_t>(c.counts.num_samples);
  // +inf is a legitimate distance between samples on different components.
  for (size_t i = 0; i < c.sample_distances.size(); ++i) {
    if (!NonNegative(c.sample_distances[i])) {
      return Fail(code, absl::StrFormat("sample distance (%d, %d) is negative or NaN (%g)", i / m,
                                        i % m, c.sample_distances[i]));
    }
  }
  for (size_t i = 0; i < c.sample_distances_lower.size(); ++i) {
    if (!NonNegative(c.sample_distances_lower[i])) {
      return Fail(
          code, absl::StrFormat("sample distance %d of the lower triangle is negative or NaN (%g)",
                                i, c.sample_distances_lower[i]));
    }
  }
  // Every code is a distance; only the scale can be wrong.
  if (c.distance_code.size() > 1 ||
      (!c.distance_code.empty() &&
       !(c.distance_code[0].scale > 0 && std::isfinite(c.distance_code[0].scale)))) {
    return Fail(code,
                absl::StrFormat("distance code: %d records, or a scale that is not finite and > 0",
                                c.distance_code.size()));
  }
  return absl::OkStatus();
}

absl::Status CheckVertexRecords(const Contents& c, absl::StatusCode code) {
  const int64_t nt = static_cast<int64_t>(c.counts.num_triangles);
  for (size_t v = 0; v < c.vertices.size(); ++v) {
    const VertexRecord& r = c.vertices[v];
    if (!InRange(r.triangle, -1, nt)) {
      return Fail(code, absl::StrFormat("vertex record %d: geodesic triangle %d out of range "
                                        "[-1, %d)",
                                        v, r.triangle, nt));
    }
    for (int k = 0; k < 3; ++k) {
      // Vertices without a triangle may carry +inf; the others need real values.
      const bool ok = r.triangle == -1 ? NonNegative(r.distance[k])
                                       : std::isfinite(r.distance[k]) && r.distance[k] >= 0;
      if (!ok) {
        return Fail(code, absl::StrFormat("vertex record %d: distance %d is invalid (%g)", v, k,
                                          r.distance[k]));
      }
    }
  }
  return absl::OkStatus();
}

absl::Status CheckTriangles(const Contents& c, absl::StatusCode code) {
  const int64_t m = static_cast<int64_t>(c.counts.num_samples);
  const int64_t nt = static_cast<int64_t>(c.counts.num_triangles);
  for (size_t t = 0; t < c.triangles.size(); ++t) {
    const GeodesicTriangle& g = c.triangles[t];
    for (int k = 0; k < 3; ++k) {
      if (!InRange(g.corner[k], 0, m)) {
        return Fail(
            code, absl::StrFormat("geodesic triangle %d: corner %d is %d, out of range [0, %d)", t,
                                  k, g.corner[k], m));
      }
      if (!InRange(g.neighbor[k], -1, nt)) {
        return Fail(
            code, absl::StrFormat("geodesic triangle %d: neighbour %d is %d, out of range [-1, %d)",
                                  t, k, g.neighbor[k], nt));
      }
    }
  }
  return absl::OkStatus();
}

// The corners a 1.x-5.x vertex record copied in: its triangle's.
absl::Status CheckRecordCorners(const Contents& c, absl::StatusCode code) {
  for (size_t v = 0; v < c.vertices_with_corners.size(); ++v) {
    const VertexRecordWithCorners& r = c.vertices_with_corners[v];
    for (int k = 0; k < 3; ++k) {
      const int32_t expected = r.triangle == -1 ? -1 : c.triangles[r.triangle].corner[k];
      if (r.corner[k] != expected) {
        return Fail(code, absl::StrFormat("vertex record %d: corner %d is %d, expected %d (%s)", v,
                                          k, r.corner[k], expected,
                                          r.triangle == -1 ? "no triangle" : "its triangle's"));
      }
    }
  }
  return absl::OkStatus();
}

absl::Status CheckBvhNodes(const Contents& c, absl::StatusCode code) {
  const int64_t nf = static_cast<int64_t>(c.counts.num_faces);
  const int64_t nb = static_cast<int64_t>(c.bvh_nodes.size());
  // Children after their parent: every traversal terminates.
  for (int64_t i = 0; i < nb; ++i) {
    const BvhNode& b = c.bvh_nodes[i];
    for (int k = 0; k < 3; ++k) {
      if (!(b.lo[k] <= b.hi[k])) {
        return Fail(code, absl::StrFormat("BVH node %d: bad box on axis %d [%g, %g]", i, k, b.lo[k],
                                          b.hi[k]));
      }
    }
    const bool ok = b.count > 0 ? b.first >= 0 && int64_t{b.first} + b.count <= nf
                                : b.count == 0 && b.first > i && int64_t{b.first} + 1 < nb;
    if (!ok) {
      return Fail(code, absl::StrFormat("BVH node %d: first %d, count %d out of range (%d nodes, "
                                        "%d faces)",
                                        i, b.first, b.count, nb, nf));
    }
  }
  return absl::OkStatus();
}

// The BVH's faces: each face once, when there is a BVH.
absl::Status CheckBvhFaces(const Contents& c, absl::StatusCode code) {
  const int64_t nf = static_cast<int64_t>(c.counts.num_faces);
  if (c.bvh_faces.empty()) return absl::OkStatus();
  std::vector<bool> seen(nf, false);
  for (size_t i = 0; i < c.bvh_faces.size(); ++i) {
    const int32_t f = c.bvh_faces[i];
    if (!InRange(f, 0, nf) || seen[f]) {
      return Fail(
          code, absl::StrFormat("BVH face %d: face %d out of range [0, %d) or repeated", i, f, nf));
    }
    seen[f] = true;
  }
  return absl::OkStatus();
}

}  // namespace

absl::Status CheckContents(const Contents& c, absl::StatusCode code) {
  const int64_t nv = static_cast<int64_t>(c.counts.num_vertices);
  const int64_t nf = static_cast<int64_t>(c.counts.num_faces);
  GEODEX_RETURN_IF_ERROR(CheckMeshIds(c, code));
  GEODEX_RETURN_IF_ERROR(CheckSampleMatrix(c, code));
  GEODEX_RETURN_IF_ERROR(CheckVertexRecords(c, code));
  GEODEX_RETURN_IF_ERROR(CheckTriangles(c, code));
  GEODEX_RETURN_IF_ERROR(CheckRecordCorners(c, code));
  GEODEX_RETURN_IF_ERROR(CheckBvhNodes(c, code));
  GEODEX_RETURN_IF_ERROR(
      CheckInputIds({nv, nf, c.input_faces, c.vertex_copies, c.split, c.split_vertices}, code));
  return CheckBvhFaces(c, code);
}

}  // namespace geodex::index::internal
