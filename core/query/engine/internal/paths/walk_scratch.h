#pragma once

// The chord walks' working memory (chord_walk.h), kept per thread in a
// QueryScratch (core/query/engine/query_scratch.h). A header of its own so
// that the scratch can hold it without including the walks that use it.

#include <cstdint>
#include <vector>

#include "core/query/engine/internal/paths/strip_funnel.h"

namespace geodex::query {

// The working memory of the chord's walks, kept per thread in a
// QueryScratch so that a near pair allocates nothing once the vectors have
// grown to the longest corridor seen: the corridor being walked, its faces
// laid out in the plane (each once: a release lays out again only the
// faces after its bend) and its portals, and the faces of the corridors
// the walks returned.
struct WalkScratch {
  std::vector<int32_t> faces;
  std::vector<FlatFace> flat;  // flat[t]: faces[t] laid out
  std::vector<Portal> portals;
  std::vector<int32_t> found_faces, doubted_faces;
  std::vector<int32_t> join;  // the chord's walk that joins a shot to its target
  // The cut bound's region (cut_bound.h): the faces reached, and each
  // face's mark, equal to `region_mark` when the current region holds it
  // (a new region takes the next mark instead of clearing them).
  std::vector<int32_t> region;
  std::vector<uint32_t> region_marks;
  uint32_t region_mark = 0;
};

}  // namespace geodex::query
