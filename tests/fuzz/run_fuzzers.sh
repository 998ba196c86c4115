#!/usr/bin/env bash
# Builds the libFuzzer targets (clang, ASan + UBSan) in BUILD_DIR (default
# <repo>/build-fuzz, reused when it exists) and runs each for N seconds on a
# copy of its seed corpus (tests/fuzz/corpus/<target>). Exits non-zero on any
# crash, sanitizer report, leak or slow input (> --timeout seconds, default
# 5, six times that for the whole build; at 1 s, long runs on a loaded
# 2-core machine stopped on inputs that run in 14-20 ms, caught inside
# ASan's allocator housekeeping, quarantine recycling and madvise); prints
# the executions of every target. Runs --jobs targets at once (default: the
# core count).
#
#   tests/fuzz/run_fuzzers.sh [--seconds N] [--timeout S] [--jobs J] [--build-dir DIR] [--keep DIR] [TARGET...]
#
# TARGET: obj ply off stl gltf repair build index pairs request (default: all). With --keep, the
# grown corpora and any crashing inputs are left in DIR (a temporary
# directory, removed at exit, otherwise).
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
seconds=20
timeout=5
jobs="$(nproc)"
build_dir="$repo/build-fuzz"
keep=""
targets=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --seconds) seconds="$2"; shift 2 ;;
    --timeout) timeout="$2"; shift 2 ;;
    --build-dir) build_dir="$2"; shift 2 ;;
    --jobs) jobs="$2"; shift 2 ;;
    --keep) keep="$2"; shift 2 ;;
    -h|--help) sed -n '2,16p' "$0"; exit 0 ;;
    -*) echo "unknown option $1" >&2; exit 2 ;;
    *) targets+=("$1"); shift ;;
  esac
done
[[ ${#targets[@]} -gt 0 ]] || targets=(obj ply off stl gltf repair build index pairs request)

# Longest input worth mutating, per target: meshes and requests of a few
# hundred elements exercise every path; longer inputs only slow the search.
# A repair soup of 512 bytes has up to 170 triangles on at most 18 vertices.
# A build input reads at most 64 extra triangles (196 bytes).
declare -A max_len=([obj]=4096 [ply]=4096 [off]=4096 [stl]=4096 [gltf]=4096 [repair]=512 [build]=196
  [index]=16384 [pairs]=2048 [request]=2048)
# A build input runs the whole pipeline, the triangulation's repair rounds
# too: a torus with a tiny tunnel and zero-area faces takes 0.34 s in
# release and 7 s under ASan and coverage, a legitimate build and no hang,
# so its slow-input limit is six times the others'.
declare -A timeout_factor=([build]=6)

# GEODEX_WERROR=ON (tests/run_tests.sh sets it): warnings fail the build; a
# tree made without it is configured again with it.
if [[ ! -f "$build_dir/build.ninja" || -n "${GEODEX_WERROR:-}" ]]; then
  CC=clang CXX=clang++ cmake -S "$repo" -B "$build_dir" -G Ninja \
    -DGEODEX_BUILD_FUZZERS=ON -DGEODEX_WITH_CGAL=OFF -DGEODEX_WERROR="${GEODEX_WERROR:-OFF}" >/dev/null
fi
build_log="$build_dir/run_fuzzers_build.log"
# shellcheck disable=SC2046  # one --target argument per word, as meant
if ! nice -n 10 cmake --build "$build_dir" -j2 --target $(printf 'fuzz_%s ' "${targets[@]}") \
    >"$build_log" 2>&1; then
  tail -n 40 "$build_log"
  echo "FAILED: building the fuzz targets (log $build_log)"
  exit 1
fi

if [[ -n "$keep" ]]; then
  work="$keep"
  mkdir -p "$work"
else
  work="$(mktemp -d "${TMPDIR:-/tmp}/geodex_fuzz.XXXXXX")"
  trap 'rm -rf "$work"' EXIT
fi

# A leak is a finding too; UBSan already aborts (-fno-sanitize-recover).
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=0:${ASAN_OPTIONS:-}"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:${UBSAN_OPTIONS:-}"

# One target's run; its status in $work/status_$t. Run `jobs` at a time:
# each fuzzer is one thread, so one at a time leaves every other core idle.
run_target() {
  local t="$1" status=0
  local bin="$build_dir/tests/fuzz/fuzz_$t" corpus="$work/corpus_$t"
  local artifacts="$work/artifacts_$t/" log="$work/fuzz_$t.log"
  mkdir -p "$corpus" "$artifacts"
  cp -r "$repo/tests/fuzz/corpus/$t/." "$corpus/"
  nice -n 10 "$bin" "$corpus" -max_total_time="$seconds" -max_len="${max_len[$t]}" \
    -timeout="$((timeout * ${timeout_factor[$t]:-1}))" -rss_limit_mb=2048 -print_final_stats=1 -artifact_prefix="$artifacts" \
    >"$log" 2>&1 || status=$?
  echo "$status" >"$work/status_$t"
}

running=0
for t in "${targets[@]}"; do
  if [[ $running -ge $jobs ]]; then
    wait -n || true
    running=$((running - 1))
  fi
  run_target "$t" &
  running=$((running + 1))
done
wait

failed=()
for t in "${targets[@]}"; do
  log="$work/fuzz_$t.log"
  artifacts="$work/artifacts_$t/"
  status="$(cat "$work/status_$t" 2>/dev/null || echo '?')"
  execs="$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || true)"
  if [[ $status != 0 ]] || grep -qE 'ERROR: (AddressSanitizer|LeakSanitizer|libFuzzer)|runtime error:' "$log"; then
    echo "fuzz_$t: FAILED (exit $status), ${execs:-?} executions; log $log"
    grep -E 'ERROR:|runtime error:|SUMMARY:|Test unit written' "$log" | head -20 || true
    failed+=("$t")
    if [[ -z "$keep" ]]; then
      # Keep the evidence when the work directory is about to be removed.
      saved="$(mktemp -d "${TMPDIR:-/tmp}/geodex_fuzz_failed.XXXXXX")"
      cp -r "$log" "$artifacts" "$saved/"
      echo "  log and crashing inputs copied to $saved"
    fi
  else
    echo "fuzz_$t: ok, ${execs:-?} executions in ${seconds} s"
  fi
done

if [[ ${#failed[@]} -gt 0 ]]; then
  echo "FAILED: ${failed[*]}"
  exit 1
fi
