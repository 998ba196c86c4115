#pragma once

// The thread count an option asks for: the builder, the triangulation's edge
// tracing, the validation's exact propagations and the tools all take
// "0 = every hardware thread".

#include <algorithm>
#include <thread>

namespace geodex::common {

// `requested` when positive, else the hardware's thread count (at least 1).
inline int ThreadCount(int requested) {
  if (requested > 0) return requested;
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

}  // namespace geodex::common
