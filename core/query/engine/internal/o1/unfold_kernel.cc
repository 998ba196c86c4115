#include "core/query/engine/internal/o1/unfold_kernel.h"

namespace geodex::query::kernel {

bool HasAvx2Lanes() {
#if defined(GEODEX_HAVE_AVX2_KERNEL)
  static const bool has = __builtin_cpu_supports("avx2");
  return has;
#else
  return false;
#endif
}

void FarDistancesOneByOne(const FarPair* pairs, double* out) {
  for (int k = 0; k < kLanes; ++k) out[k] = FarDistance(pairs[k]);
}

void FarDistances(const FarPair* pairs, double* out) {
#if defined(GEODEX_HAVE_AVX2_KERNEL)
  if (HasAvx2Lanes()) return FarDistancesAvx2(pairs, out);
#endif
  FarDistancesOneByOne(pairs, out);
}

}  // namespace geodex::query::kernel
