// The four-lane far-pair kernel: the one file built with -mavx2 (see
// unfold_kernel.h). Nothing here runs unless HasAvx2Lanes().

#include "core/query/engine/internal/o1/unfold_kernel.h"

#if !defined(__AVX2__)
#error "unfold_kernel_avx2.cc must be compiled with -mavx2"
#endif

namespace geodex::query::kernel {

void FarDistancesAvx2(const FarPair* pairs, double* out) {
  static_assert(kLanes == 4);
  Frame<Lanes> p_frames[3], q_frames[3];
  Lanes p_distance[3], q_distance[3], e[3][3], shared[3];
  for (int i = 0; i < 3; ++i) {
    auto frame = [&](const Frame<double>* FarPair::*frames) {
      return Frame<Lanes>{MakeLanes([&](int k) { return (pairs[k].*frames)[i].l; }),
                          MakeLanes([&](int k) { return (pairs[k].*frames)[i].cx; }),
                          MakeLanes([&](int k) { return (pairs[k].*frames)[i].cy; }),
                          MakeLanes([&](int k) { return (pairs[k].*frames)[i].inv_2l; })};
    };
    p_frames[i] = frame(&FarPair::p_frames);
    q_frames[i] = frame(&FarPair::q_frames);
    p_distance[i] = MakeLanes([&](int k) { return pairs[k].p_distance[i]; });
    q_distance[i] = MakeLanes([&](int k) { return pairs[k].q_distance[i]; });
    shared[i] = MakeLanes([&](int k) { return pairs[k].shared[i]; });
    for (int j = 0; j < 3; ++j) e[j][i] = MakeLanes([&](int k) { return pairs[k].e[j][i]; });
  }
  const Lanes d = FarDistance(p_frames, p_distance, q_frames, q_distance, e, shared);
  for (int k = 0; k < kLanes; ++k) out[k] = d[k];
}

void PlaceInTriangleAvx2(const Frame<double>* const* frames, const double* const* d,
                         Placed<double>* out) {
  Frame<Lanes> lane_frames[3];
  Lanes lane_d[3];
  for (int i = 0; i < 3; ++i) {
    lane_frames[i] = Frame<Lanes>{MakeLanes([&](int k) { return frames[k][i].l; }),
                                  MakeLanes([&](int k) { return frames[k][i].cx; }),
                                  MakeLanes([&](int k) { return frames[k][i].cy; }),
                                  MakeLanes([&](int k) { return frames[k][i].inv_2l; })};
    lane_d[i] = MakeLanes([&](int k) { return d[k][i]; });
  }
  const Placed<Lanes> placed = PlaceInTriangle(lane_frames, lane_d);
  for (int k = 0; k < kLanes; ++k) {
    for (int i = 0; i < 3; ++i) {
      out[k].x[i] = placed.x[i][k];
      out[k].y[i] = placed.y[i][k];
    }
  }
}

}  // namespace geodex::query::kernel
