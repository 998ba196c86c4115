#!/usr/bin/env bash
# The unit, client and server tests under sanitizers, each in a build tree of
# its own beside the sources (reused between runs):
#   --asan  AddressSanitizer + UndefinedBehaviorSanitizer, no recovery: every
#           unit test program, client_tests and server_tests (build-asan/);
#   --tsan  ThreadSanitizer (build-tsan/): the registry's hot-swap and reload
#           tests and the worker pool's, which must be clean; then the gRPC
#           concurrency tests (streams, shutdown, limits), whose reports are
#           counted but not judged (below);
#   --ci    the subset the test suite runs (ctest "sanitizers"): the common,
#           mesh and index tests (the readers of untrusted files) under
#           ASan+UBSan, built with clang in the fuzz targets' tree
#           (build-fuzz/), whose instrumented objects they share, so that CI
#           pays for one sanitized build, not two. server_tests under ASan
#           is --asan's: its sanitized build and run (about 30 min on two
#           cores) would take most of CI's time. Exits 77 (skipped) without
#           clang.
# The system libraries (gRPC, protobuf, Abseil) are not instrumented: ASan
# still checks every access our code makes; TSan cannot see the
# synchronisation inside gRPC: races reported from within those libraries are
# suppressed by library (tests/sanitizers/tsan.supp), which does not yet
# silence all of them (see tests/README.md, "Sanitizers"); LeakSanitizer ignores
# what they never free (lsan.supp). Nothing of geodex's is suppressed.
#
#   tests/sanitizers/run.sh [--asan] [--tsan] [--ci] [--jobs N]   (default: --asan --tsan)
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
asan=0 tsan=0 ci=0 jobs=2
while [[ $# -gt 0 ]]; do
  case "$1" in
    --asan) asan=1; shift ;;
    --tsan) tsan=1; shift ;;
    --ci) ci=1; shift ;;
    --jobs) jobs="$2"; shift 2 ;;
    *) echo "sanitizers: unknown argument $1" >&2; exit 2 ;;
  esac
done
if [[ $asan -eq 0 && $tsan -eq 0 && $ci -eq 0 ]]; then asan=1 tsan=1; fi

# configure DIR SANITIZERS
configure() {
  if [[ ! -f "$1/build.ninja" || -n "${GEODEX_WERROR:-}" ]]; then
    cmake -S "$repo" -B "$1" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
      -DGEODEX_SANITIZE="$2" -DGEODEX_BUILD_BENCHMARKS=OFF -DGEODEX_WITH_CGAL=OFF \
      -DGEODEX_WERROR="${GEODEX_WERROR:-OFF}" > /dev/null
  fi
}

export ASAN_OPTIONS="detect_leaks=1:abort_on_error=0:halt_on_error=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
export LSAN_OPTIONS="suppressions=$repo/tests/sanitizers/lsan.supp:print_suppressions=0"

# run_tests DIR LABEL BINARY... : runs each test program, logs beside it.
run_tests() {
  local dir="$1" label="$2"; shift 2
  local t start
  for t in "$@"; do
    start=$(date +%s)
    if "$dir/$t" --gtest_brief=1 > "$dir/$(basename "$t").log" 2>&1; then
      echo "$label: $(basename "$t") passed ($(($(date +%s) - start)) s)"
    else
      echo "$label: $(basename "$t") FAILED (log $dir/$(basename "$t").log)"
      tail -n 30 "$dir/$(basename "$t").log"; failed=1
    fi
  done
}

failed=0
if [[ $ci -eq 1 ]]; then
  if ! command -v clang++ > /dev/null; then
    echo "sanitizers: SKIPPED: no clang++ (deploy/install-deps.sh installs it)"; exit 77
  fi
  dir="$repo/build-fuzz"
  if [[ ! -f "$dir/build.ninja" || -n "${GEODEX_WERROR:-}" ]]; then
    CC=clang CXX=clang++ cmake -S "$repo" -B "$dir" -G Ninja \
      -DGEODEX_BUILD_FUZZERS=ON -DGEODEX_WITH_CGAL=OFF -DGEODEX_WERROR="${GEODEX_WERROR:-OFF}" > /dev/null
  fi
  targets=(core/common_tests core/mesh_tests core/index_tests)
  if ! nice -n 10 cmake --build "$dir" -j"$jobs" --target "${targets[@]##*/}" > "$dir/sanitizers_build.log" 2>&1; then
    tail -n 40 "$dir/sanitizers_build.log"; echo "FAILED: building the sanitized tests"; exit 1
  fi
  run_tests "$dir" "asan (ci)" "${targets[@]}"
fi

if [[ $asan -eq 1 ]]; then
  dir="$repo/build-asan"
  configure "$dir" "address,undefined"
  unit=(common_tests mesh_tests index_tests builder_tests query_tests validation_tests
        geometry_tests geodesic_tests radix_heap_tests)
  nice -n 10 cmake --build "$dir" -j"$jobs" --target "${unit[@]}" client_tests server_tests
  run_tests "$dir" asan "${unit[@]/#/core/}" client/client_tests server/server_tests
fi

if [[ $tsan -eq 1 ]]; then
  dir="$repo/build-tsan"
  configure "$dir" "thread"
  nice -n 10 cmake --build "$dir" -j"$jobs" --target server_tests
  # Our own concurrency without gRPC's threads (the registry's hot swap and
  # reload, the worker pool): must be clean.
  export TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:suppressions=$repo/tests/sanitizers/tsan.supp"
  start=$(date +%s)
  if "$dir/server/server_tests" --gtest_brief=1 --gtest_filter='ModelRegistry*:WorkerPool*' \
      > "$dir/server_tests_own.log" 2>&1; then
    echo "tsan: registry and worker-pool tests passed ($(($(date +%s) - start)) s)"
  else
    echo "tsan: registry and worker-pool tests FAILED (log $dir/server_tests_own.log)"
    tail -n 60 "$dir/server_tests_own.log"; failed=1
  fi
  # The gRPC tests (streams, reload, shutdown, limits): TSan cannot see the
  # synchronisation inside Debian's uninstrumented gRPC, so its reports are
  # counted, not judged (tests/README.md, "Sanitizers"); a test failure still fails.
  export TSAN_OPTIONS="halt_on_error=0:report_signal_unsafe=0:suppressions=$repo/tests/sanitizers/tsan.supp"
  filter='*Stream*:*Reload*:*Swap*:*Shutdown*:*Drain*:*Concurrent*:*Cancel*:*Limit*'
  start=$(date +%s)
  status=0
  "$dir/server/server_tests" --gtest_brief=1 --gtest_filter="$filter" > "$dir/server_tests.log" 2>&1 || status=$?
  reports=$(grep -c "WARNING: ThreadSanitizer" "$dir/server_tests.log" || true)
  if grep -q "^\[  FAILED  \]" "$dir/server_tests.log"; then
    echo "tsan: server_tests ($filter) FAILED (log $dir/server_tests.log)"
    grep "^\[  FAILED  \]" "$dir/server_tests.log"; failed=1
  else
    echo "tsan: server_tests ($filter) passed ($(($(date +%s) - start)) s, exit $status);" \
      "$reports TSan reports through gRPC's uninstrumented threads, not judged"
  fi
fi
exit $failed
