// soak_driver: many concurrent clients of one geodex-server, for
// tests/soak/soak.sh, until the time is up. What each thread sends and how
// every answer is checked (to the bit, against the offline engine of the
// version that answered it, --version V=INDEX) is in soak_client.h.
//
//   soak_driver --server ADDR --model M --version 1=v1.gdx --version 2=v2.gdx
//               [--threads 8] [--seconds 30] [--max-pairs 1000]
//
// Prints one line of counts; exits 1 on any violation (the first few are
// printed), 2 on bad usage.
//
// The clients are in soak_client.h, the rest in soak_driver_lib.h.

#include "tests/bench/bench_flags.h"
#include "tests/soak/soak_driver_lib.h"

int main(int argc, char** argv) {
  geodex::soak::SoakOptions options;
  const auto app = geodex::soak::SoakFlags(&options);
  if (const auto exit_code = geodex::bench::ParseFlags(*app, argc, argv)) return *exit_code;
  return geodex::soak::RunSoak(options);
}
