#!/usr/bin/env bash
# Soak and load: one geodex-server on loopback under many concurrent clients
# (soak_driver: valid and invalid requests, every valid answer checked against
# the offline engine of the version that gave it) while the model is
# hot-swapped: a new version, then a corrupt one (truncated: refused, the
# previous version keeps serving), then another good one. Checks that no valid
# call failed, every invalid one was refused with its code, the server's heap
# (RssAnon) grew less than 5% over the last 40% of the run, and no file descriptor or thread
# leaked. Prints its figures; exits 1 on any violation, 77 when a binary is
# missing.
#
#   soak.sh [--seconds N] [--threads T] [--bin-dir DIR]
#       (or --build-bin, --server-bin, --client-bin, --driver-bin)
set -euo pipefail

RUN_SECONDS=60 THREADS=8 BIN_DIR=""
BUILD_BIN="" SERVER_BIN="" CLIENT_BIN="" DRIVER_BIN=""
while [ $# -gt 0 ]; do
  case "$1" in
    --seconds) RUN_SECONDS="$2"; shift 2 ;;
    --threads) THREADS="$2"; shift 2 ;;
    --bin-dir) BIN_DIR="$2"; shift 2 ;;
    --build-bin) BUILD_BIN="$2"; shift 2 ;;
    --server-bin) SERVER_BIN="$2"; shift 2 ;;
    --client-bin) CLIENT_BIN="$2"; shift 2 ;;
    --driver-bin) DRIVER_BIN="$2"; shift 2 ;;
    *) echo "soak: unknown argument $1" >&2; exit 2 ;;
  esac
done
BIN_DIR="${BIN_DIR:-$(cd "$(dirname "$0")/../.." && pwd)/build}"
BUILD_BIN="${BUILD_BIN:-$BIN_DIR/core/geodex-build}"
SERVER_BIN="${SERVER_BIN:-$BIN_DIR/server/geodex-server}"
CLIENT_BIN="${CLIENT_BIN:-$BIN_DIR/client/geodex}"
DRIVER_BIN="${DRIVER_BIN:-$BIN_DIR/tests/soak_driver}"
for b in "$BUILD_BIN" "$SERVER_BIN" "$CLIENT_BIN" "$DRIVER_BIN"; do
  if [ ! -x "$b" ]; then echo "soak: SKIPPED: no binary $b"; exit 77; fi
done

WORK="$(mktemp -d "${TMPDIR:-/tmp}/geodex-soak.XXXXXX")"
SERVER_PID="" DRIVER_PID=""
cleanup() {
  if [ -n "$DRIVER_PID" ]; then kill "$DRIVER_PID" 2> /dev/null || true; fi
  if [ -n "$SERVER_PID" ]; then kill "$SERVER_PID" 2> /dev/null || true; fi
  wait 2> /dev/null || true
  rm -rf "$WORK"
}
trap cleanup EXIT
fail() { echo "soak: FAIL: $*" >&2; exit 1; }

# --- indexes: two good versions and a corrupt one -----------------------------
"$BUILD_BIN" builtin:torus -o "$WORK/v1.gdx" --samples 100 --no-calibration > /dev/null
"$BUILD_BIN" builtin:torus -o "$WORK/v2.gdx" --samples 160 --no-calibration > /dev/null
head -c "$(($(stat -c %s "$WORK/v2.gdx") / 2))" "$WORK/v2.gdx" > "$WORK/corrupt.gdx"
REPO="$WORK/models"
mkdir -p "$REPO/torus" "$WORK/staging"
# Publishes FILE as version V: staged on the same filesystem, then renamed,
# so the server never maps a half-written file.
publish() {
  mkdir -p "$WORK/staging/$2"
  cp "$1" "$WORK/staging/$2/index.gdx"
  mv -T "$WORK/staging/$2" "$REPO/torus/$2"
}
publish "$WORK/v1.gdx" 1

free_port() {
  local port
  for _ in $(seq 1 100); do
    port=$((20000 + RANDOM % 40000))
    if ! (exec 3<> "/dev/tcp/127.0.0.1/$port") 2> /dev/null; then
      echo "$port"
      return 0
    fi
  done
  return 1
}
PORT="$(free_port)"
ADDR="127.0.0.1:$PORT"
# One malloc arena: glibc opens another arena whenever a thread finds its own
# locked, up to 8 per core, and each new one shows as a step in RssAnon that
# then stays flat. Those steps reached +7% in 20 s of a server that leaked
# nothing, +1.3-3.6% with one arena. A leak grows with every call either way.
MALLOC_ARENA_MAX=1 "$SERVER_BIN" --models "$REPO" --listen "$ADDR" --poll-seconds 0.2 --max-pairs 1000 \
  --log-level warn > "$WORK/server.log" 2>&1 &
SERVER_PID=$!
for _ in $(seq 100); do
  "$CLIENT_BIN" models --server "$ADDR" 2> /dev/null | grep -q SERVING && break
  sleep 0.1
done
"$CLIENT_BIN" models --server "$ADDR" | grep -q SERVING || fail "the server did not start serving"

status_field() { awk -v k="$1:" '$1 == k { print $2 }' "/proc/$SERVER_PID/status"; }
fds() { find "/proc/$SERVER_PID/fd" -mindepth 1 -maxdepth 1 | wc -l; }
FDS_BEFORE=$(fds) THREADS_BEFORE=$(status_field Threads)

"$DRIVER_BIN" --server "$ADDR" --model torus --threads "$THREADS" --seconds "$RUN_SECONDS" \
  --max-pairs 1000 --version "1=$WORK/v1.gdx" --version "2=$WORK/v2.gdx" \
  --version "4=$WORK/v1.gdx" > "$WORK/driver.out" 2> "$WORK/driver.err" &
DRIVER_PID=$!

# Samples the heap and the threads every 0.25 s; swaps versions at 5%, 10%
# and 15% of the run, so that its last 40% is steady state: each swap loads
# an engine, the first near-pair refinement of a version builds its exact
# mesh, and each worker's scratch grows to the largest request it has seen
# (a high-water mark that rises for about 15 s after a swap under this load,
# then stays flat: +0.1% from 50% to 100% of a 180 s run). That is growth by
# design; a leak grows with every call, in the last 40% as anywhere.
START_MS=$(date +%s%3N)
# The share of the run done, in percent.
percent_done() { echo $((($(date +%s%3N) - START_MS) / (10 * RUN_SECONDS))); }
declare -a RSS_AT=()
STEP=0
while kill -0 "$DRIVER_PID" 2> /dev/null; do
  DONE=$(percent_done)
  RSS_AT+=("$DONE $(status_field RssAnon) $(status_field Threads) $(fds)")
  if [ $STEP -eq 0 ] && [ "$DONE" -ge 5 ]; then publish "$WORK/v2.gdx" 2; STEP=1; fi
  if [ $STEP -eq 1 ] && [ "$DONE" -ge 10 ]; then publish "$WORK/corrupt.gdx" 3; STEP=2; fi
  if [ $STEP -eq 2 ] && [ "$DONE" -ge 15 ]; then publish "$WORK/v1.gdx" 4; STEP=3; fi
  sleep 0.25
done
DRIVER_RC=0
wait "$DRIVER_PID" || DRIVER_RC=$?
DRIVER_PID=""
cat "$WORK/driver.out"
if [ $DRIVER_RC -ne 0 ]; then
  cat "$WORK/driver.err" >&2
  fail "the driver failed (exit $DRIVER_RC): violations, or no call checked (above)"
fi
[ $STEP -eq 3 ] || fail "the run ended before all three swaps (step $STEP)"
kill -0 "$SERVER_PID" 2> /dev/null || fail "the server died"

# The corrupt version failed; the server serves the last good one.
sleep 1
MODELS="$("$CLIENT_BIN" models --server "$ADDR")"
echo "$MODELS" | grep -q "SERVING" || fail "no version serving after the run: $MODELS"
INFO="$("$CLIENT_BIN" info --server "$ADDR" --model torus --format json)"
echo "$INFO" | grep -q '"version": 4' || fail "version 4 is not the one serving: $INFO"

# After warm-up (the samples from 60% of the run on) the heap grows less
# than 5%, and the threads and descriptors do not grow.
read -r HEAP_WARM HEAP_END HEAP_MAX THREADS_WARM THREADS_END FDS_WARM FDS_END < <(
  printf '%s\n' "${RSS_AT[@]}" | awk '
    $1 >= 60 && $2 > 0 { n++; v[n] = $2; t[n] = $3; f[n] = $4; if ($2 > mx) mx = $2 }
    END { if (n < 4) { print 0, 0, 0, 0, 0, 0, 0; exit }
          print v[1], v[n], mx, t[1], t[n], f[1], f[n] }')
[ "$HEAP_WARM" -gt 0 ] || fail "too few heap samples after warm-up"
GROWTH=$(awk -v a="$HEAP_WARM" -v b="$HEAP_END" 'BEGIN { printf "%.2f", 100 * (b - a) / a }')
# File descriptors and threads back where they were once the clients are gone.
sleep 2
FDS_AFTER=$(fds) THREADS_AFTER=$(status_field Threads)
printf 'soak: heap (RssAnon) %s kB after warm-up, %s kB at the end (%+.1f%%), peak %s kB\n' \
  "$HEAP_WARM" "$HEAP_END" "$GROWTH" "$HEAP_MAX"
echo "soak: threads $THREADS_BEFORE before the load, $THREADS_WARM after warm-up, $THREADS_END at the end, $THREADS_AFTER after"
echo "soak: file descriptors $FDS_BEFORE before the load, $FDS_WARM after warm-up, $FDS_END at the end, $FDS_AFTER after"
awk -v g="$GROWTH" 'BEGIN { exit !(g < 5) }' || fail "the heap grew ${GROWTH}% after warm-up"
[ "$FDS_AFTER" -le "$((FDS_BEFORE + 2))" ] || fail "file descriptors leaked: $FDS_BEFORE -> $FDS_AFTER"
[ "$THREADS_END" -le "$((THREADS_WARM + 2))" ] || fail "threads grew under steady load: $THREADS_WARM -> $THREADS_END"
[ "$FDS_END" -le "$((FDS_WARM + 2))" ] || fail "file descriptors grew under steady load: $FDS_WARM -> $FDS_END"
echo "soak: OK"
