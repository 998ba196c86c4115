#!/usr/bin/env bash
# The unit, client and server tests under sanitizers, each in a build tree of
# its own beside the sources (reused between runs):
#   --asan  AddressSanitizer + UndefinedBehaviorSanitizer, no recovery: every
#           unit test program, client_tests and server_tests (build-asan/);
#   --tsan  ThreadSanitizer: server_tests' concurrency tests (streams, hot
#           swap, shutdown, limits) (build-tsan/).
# The system libraries (gRPC, protobuf, Abseil) are not instrumented: ASan
# still checks every access our code makes; TSan cannot see the
# synchronisation inside gRPC: races reported from within those libraries are
# suppressed by library (tests/sanitizers/tsan.supp), which does not yet
# silence all of them (see the README, "Sanitizers"); LeakSanitizer ignores
# what they never free (lsan.supp). Nothing of geodex's is suppressed.
#
#   tests/sanitizers/run.sh [--asan] [--tsan] [--jobs N]   (default: both)
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
asan=0 tsan=0 jobs=2
while [[ $# -gt 0 ]]; do
  case "$1" in
    --asan) asan=1; shift ;;
    --tsan) tsan=1; shift ;;
    --jobs) jobs="$2"; shift 2 ;;
    *) echo "sanitizers: unknown argument $1" >&2; exit 2 ;;
  esac
done
if [[ $asan -eq 0 && $tsan -eq 0 ]]; then asan=1 tsan=1; fi

# configure DIR SANITIZERS
configure() {
  if [[ ! -f "$1/build.ninja" ]]; then
    cmake -S "$repo" -B "$1" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
      -DGEODEX_SANITIZE="$2" -DGEODEX_BUILD_BENCHMARKS=OFF -DGEODEX_WITH_CGAL=OFF > /dev/null
  fi
}

failed=0
if [[ $asan -eq 1 ]]; then
  dir="$repo/build-asan"
  configure "$dir" "address,undefined"
  unit=(common_tests mesh_tests index_tests builder_tests query_tests validation_tests
        geometry_tests geodesic_tests radix_heap_tests)
  nice -n 10 cmake --build "$dir" -j"$jobs" --target "${unit[@]}" client_tests server_tests
  export ASAN_OPTIONS="detect_leaks=1:abort_on_error=0:halt_on_error=1"
  export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
  export LSAN_OPTIONS="suppressions=$repo/tests/sanitizers/lsan.supp:print_suppressions=0"
  for t in "${unit[@]}"; do
    start=$(date +%s)
    if "$dir/core/$t" --gtest_brief=1 > "$dir/$t.log" 2>&1; then
      echo "asan: $t passed ($(($(date +%s) - start)) s)"
    else
      echo "asan: $t FAILED (log $dir/$t.log)"; tail -n 30 "$dir/$t.log"; failed=1
    fi
  done
  for t in client/client_tests server/server_tests; do
    start=$(date +%s)
    if "$dir/$t" --gtest_brief=1 > "$dir/$(basename "$t").log" 2>&1; then
      echo "asan: $(basename "$t") passed ($(($(date +%s) - start)) s)"
    else
      echo "asan: $(basename "$t") FAILED (log $dir/$(basename "$t").log)"
      tail -n 30 "$dir/$(basename "$t").log"; failed=1
    fi
  done
fi

if [[ $tsan -eq 1 ]]; then
  dir="$repo/build-tsan"
  configure "$dir" "thread"
  nice -n 10 cmake --build "$dir" -j"$jobs" --target server_tests
  export TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:suppressions=$repo/tests/sanitizers/tsan.supp"
  filter='*Stream*:*Reload*:*Swap*:*Shutdown*:*Drain*:*Concurrent*:*Cancel*:*Limit*'
  start=$(date +%s)
  if "$dir/server/server_tests" --gtest_brief=1 --gtest_filter="$filter" > "$dir/server_tests.log" 2>&1; then
    echo "tsan: server_tests ($filter) passed ($(($(date +%s) - start)) s)"
  else
    echo "tsan: server_tests FAILED (log $dir/server_tests.log)"; tail -n 60 "$dir/server_tests.log"
    failed=1
  fi
fi
exit $failed
