#!/usr/bin/env bash
# The cluster protocol of deploy/k8s, played with local processes on loopback,
# as a test that fails loudly on any violation:
#
#   1. distributed build of a built-in mesh: geodex-build plan, N
#      `geodex-build rows --shard i/N` in parallel, geodex-build merge, the
#      rows and merge again while merge plans another round (v1 is built to
#      an error target, in rounds, and must be the index a one-process build
#      to that target makes; v2 has a fixed sample count);
#   2. atomic publication: the version directory is assembled outside the
#      repository (same filesystem) and renamed to <repo>/<model>/<version>,
#      so a polling server never sees a version without its complete index;
#   3. two geodex-server replicas over the same repository, and the `geodex`
#      client spreading load over both (--server A,B: round-robin) while one
#      replica is SIGKILLed mid-run: not one call may fail, and every answer
#      must be the right one;
#   4. a new version (another sample count) published and picked up by the
#      surviving replica (repository polling) and by the restarted replica;
#   5. both replicas' answers of the new version equal geodex-query's offline
#      answers on the same index file, as text.
#
#   deploy/local-cluster.sh [--bin-dir DIR] [--build-bin B] [--server-bin S]
#                           [--client-bin C] [--query-bin Q] [--shards N]
#                           [--mesh builtin:NAME] [--keep]
#
# --bin-dir is a CMake build directory (default: ../build next to this script);
# the --*-bin flags override single binaries. --keep leaves the work directory
# (logs, repository, indexes) in place and prints where it is.
# Exit codes: 0 every check passed; 1 a check failed (the message says which);
# 2 bad usage; 77 a binary is missing (ctest reports the test as skipped).
set -euo pipefail

SCRIPT_DIR="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
BIN_DIR="$SCRIPT_DIR/../build"
BUILD_BIN="" SERVER_BIN="" CLIENT_BIN="" QUERY_BIN=""
SHARDS=3
MESH="builtin:torus"
MODEL="torus"
KEEP=0
# Two builds that answer differently, so that a replica still answering
# from version 1 cannot pass the version 2 checks: v1 to an error target
# (from a small m with a low cap, so that it takes two small rounds), v2
# with a fixed m.
FLAGS_V1="--target-error 0.01 --samples 120 --max-samples 360"
FLAGS_V2="--samples 180"

usage() { sed -n '/^#   deploy/,/^# 2 bad usage/p' "$0" | sed 's/^# \{0,1\}//' >&2; exit 2; }
die() { echo "local-cluster: FAILED: $*" >&2; exit 1; }
log() { echo "local-cluster: $*"; }

while [ $# -gt 0 ]; do
  case "$1" in
    --bin-dir) BIN_DIR="${2:?--bin-dir needs a value}"; shift 2 ;;
    --build-bin) BUILD_BIN="${2:?}"; shift 2 ;;
    --server-bin) SERVER_BIN="${2:?}"; shift 2 ;;
    --client-bin) CLIENT_BIN="${2:?}"; shift 2 ;;
    --query-bin) QUERY_BIN="${2:?}"; shift 2 ;;
    --shards) SHARDS="${2:?}"; shift 2 ;;
    --mesh) MESH="${2:?}"; shift 2 ;;
    --keep) KEEP=1; shift ;;
    -h|--help) usage ;;
    *) echo "local-cluster: unknown argument $1" >&2; usage ;;
  esac
done
[[ "$SHARDS" =~ ^[1-9][0-9]*$ ]] || { echo "local-cluster: --shards must be a positive integer" >&2; exit 2; }
# Repository files are read from the built-in meshes only: nothing outside
# the build tree is needed, and nothing of the developers' meshes is copied.
[[ "$MESH" == builtin:* ]] || { echo "local-cluster: --mesh must be builtin:NAME" >&2; exit 2; }
MODEL="${MESH#builtin:}"
MODEL="${MODEL//[^A-Za-z0-9_.-]/_}"

BUILD_BIN="${BUILD_BIN:-$BIN_DIR/core/geodex-build}"
SERVER_BIN="${SERVER_BIN:-$BIN_DIR/server/geodex-server}"
CLIENT_BIN="${CLIENT_BIN:-$BIN_DIR/client/geodex}"
QUERY_BIN="${QUERY_BIN:-$BIN_DIR/core/geodex-query}"
for b in "$BUILD_BIN" "$SERVER_BIN" "$CLIENT_BIN" "$QUERY_BIN"; do
  if [ ! -x "$b" ]; then
    echo "local-cluster: SKIPPED: no executable $b (build it, or pass --bin-dir / --*-bin)"
    exit 77
  fi
done

WORK="$(mktemp -d "${TMPDIR:-/tmp}/geodex-local-cluster.XXXXXX")"
REPO="$WORK/models"
STAGING="$WORK/staging"  # beside the repository: same filesystem, so mv is a rename
mkdir -p "$REPO" "$STAGING"

# Every background process is recorded here and killed (by its pid) on exit,
# whatever the exit path.
CHILDREN=()
cleanup() {
  local status=$?
  local pid
  for pid in "${CHILDREN[@]}"; do
    kill -KILL "$pid" 2>/dev/null || true
  done
  for pid in "${CHILDREN[@]}"; do
    wait "$pid" 2>/dev/null || true
  done
  if [ "$KEEP" -eq 1 ] || [ "$status" -ne 0 ]; then
    # A failed run keeps its logs: the message above points into them.
    echo "local-cluster: work directory kept: $WORK" >&2
  else
    rm -rf "$WORK"
  fi
  exit "$status"
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

cd "$WORK"
SECONDS=0

# --- 1 + 2: distributed build, atomic publication ------------------------------
# run_shards VERSION WORKDIR ROUND: SHARDS row jobs in parallel, one thread each.
run_shards() {
  local version="$1" workdir="$2" round="$3"
  log "v$version round $round: $SHARDS x geodex-build rows --shard i/$SHARDS, in parallel"
  local pids=() i
  for ((i = 0; i < SHARDS; i++)); do
    # One thread each: the shards, not the threads, are the parallelism here,
    # as with one pod per shard.
    "$BUILD_BIN" rows "$workdir" --shard "$i/$SHARDS" --threads 1 > "rows-v$version-$i.log" 2>&1 &
    pids+=("$!")
    CHILDREN+=("$!")
  done
  for ((i = 0; i < SHARDS; i++)); do
    if ! wait "${pids[$i]}"; then
      cat "rows-v$version-$i.log" >&2
      die "rows shard $i/$SHARDS of v$version, round $round"
    fi
  done
}

# build_version VERSION FLAGS: plan, then the rows shards and merge into the
# staging area, again while merge exits 3 (it planned another round of a
# target-error build), then one rename into the repository.
build_version() {
  local version="$1" flags="$2"
  local workdir="$WORK/build-v$version"
  log "v$version: geodex-build plan $MESH $flags"
  # shellcheck disable=SC2086  # flags is a list of flags
  "$BUILD_BIN" plan "$MESH" $flags --threads 1 -o "$workdir" \
    > "plan-v$version.log" 2>&1 || { cat "plan-v$version.log" >&2; die "plan of v$version"; }

  local stage
  stage="$(mktemp -d "$STAGING/$MODEL-v$version.XXXXXX")"
  local round=1 status
  while :; do
    run_shards "$version" "$workdir" "$round"
    log "v$version round $round: geodex-build merge"
    status=0
    "$BUILD_BIN" merge "$workdir" -o "$stage/index.gdx" > "merge-v$version-$round.log" 2>&1 ||
      status=$?
    [ "$status" -eq 0 ] && break
    [ "$status" -eq 3 ] || { cat "merge-v$version-$round.log" >&2; die "merge of v$version"; }
    [ ! -e "$stage/index.gdx" ] || die "merge of v$version wrote an index and planned a round"
    round=$((round + 1))
    [ "$round" -le 10 ] || die "v$version: no index after 10 rounds"
  done
  [ -s "$stage/index.gdx" ] || die "merge of v$version wrote no index"
  ROUNDS_V[$version]="$round"
  # mktemp -d makes 0700 directories; a server under another uid must read it.
  chmod 0755 "$stage"
  if [ "$(stat -c %d "$stage")" != "$(stat -c %d "$REPO")" ]; then
    die "staging and repository are on different filesystems: mv would copy, not rename"
  fi
  mkdir -p "$REPO/$MODEL"
  [ ! -e "$REPO/$MODEL/$version" ] || die "$REPO/$MODEL/$version exists: versions are immutable"
  # rename(2) of the whole directory: the server's scan sees either no
  # version directory or one holding the complete index.gdx.
  mv -T "$stage" "$REPO/$MODEL/$version"
}

# --- servers -----------------------------------------------------------------
# start_replica NAME PORT: starts geodex-server on 127.0.0.1:PORT (0: any free
# port, read back from its "listening on port N" line) and sets
# REPLICA_PID_<NAME>, REPLICA_ADDR_<NAME>, REPLICA_METRICS_<NAME>.
start_replica() {
  local name="$1" port="$2"
  local out="$WORK/server-$name.out" err="$WORK/server-$name.log"
  : > "$out"
  "$SERVER_BIN" --models "$REPO" --listen "127.0.0.1:$port" --metrics 127.0.0.1:0 \
    --poll-seconds 0.5 --workers 2 --drain-seconds 2 > "$out" 2>> "$err" &
  local pid=$!
  CHILDREN+=("$pid")
  local listening=""
  for _ in $(seq 1 100); do
    listening="$(sed -n 's/^listening on port \([0-9]*\)$/\1/p' "$out")"
    [ -n "$listening" ] && break
    kill -0 "$pid" 2>/dev/null || { cat "$err" >&2; die "replica $name exited at start"; }
    sleep 0.1
  done
  [ -n "$listening" ] || { cat "$err" >&2; die "replica $name did not listen within 10 s"; }
  local metrics
  metrics="$(grep -o 'metrics on port [0-9]*' "$err" | tail -1 | awk '{print $4}')"
  [ -n "$metrics" ] || die "replica $name logged no metrics port"
  printf -v "REPLICA_PID_$name" '%s' "$pid"
  printf -v "REPLICA_ADDR_$name" '%s' "127.0.0.1:$listening"
  printf -v "REPLICA_METRICS_$name" '%s' "$metrics"
}

# served_version ADDR: the model's newest served version as `geodex info`
# reports it, or nothing.
served_version() {
  "$CLIENT_BIN" info --server "$1" --model "$MODEL" --format json --attempts 1 --timeout 2 2>/dev/null |
    sed -n 's/^  "version": \([0-9]*\),$/\1/p'
}

# wait_version NAME ADDR VERSION SECONDS: until the replica serves VERSION.
wait_version() {
  local name="$1" addr="$2" want="$3" limit="$4" got=""
  local deadline=$((SECONDS + limit))
  while [ "$SECONDS" -le "$deadline" ]; do
    got="$(served_version "$addr" || true)"
    [ "$got" = "$want" ] && return 0
    sleep 0.2
  done
  "$CLIENT_BIN" models --server "$addr" --attempts 1 --timeout 2 >&2 || true
  die "replica $name ($addr) serves version '${got:-none}' of $MODEL after ${limit} s, expected $want"
}

# metric PORT NAME: the sum of every sample of metric NAME on the replica's
# Prometheus endpoint (bash's /dev/tcp: no curl needed).
metric() {
  local port="$1" name="$2"
  exec 3<>"/dev/tcp/127.0.0.1/$port" || die "metrics endpoint 127.0.0.1:$port unreachable"
  printf 'GET /metrics HTTP/1.0\r\nHost: 127.0.0.1\r\n\r\n' >&3
  awk -v n="$name" '$1 == n || index($1, n "{") == 1 { s += $NF } END { printf "%d\n", s }' <&3
  exec 3<&-
}

# --- pairs and offline answers ---------------------------------------------------
declare -A ROUNDS_V
build_version 1 "$FLAGS_V1"
[ "${ROUNDS_V[1]}" -ge 2 ] || die "v1 met its target in one round: the rounds were not exercised"
# The same target in one process: the same index, byte for byte.
# shellcheck disable=SC2086  # FLAGS_V1 is a list of flags
"$BUILD_BIN" "$MESH" $FLAGS_V1 --threads 2 -o "$WORK/one-process-v1.gdx" > one-process-v1.log 2>&1 ||
  { cat one-process-v1.log >&2; die "one-process build of v1"; }
cmp -s "$WORK/one-process-v1.gdx" "$REPO/$MODEL/1/index.gdx" ||
  die "the distributed target-error build differs from the one-process build"
log "v1: ${ROUNDS_V[1]} rounds, the same bytes as the one-process build"
FACES="$("$QUERY_BIN" "$REPO/$MODEL/1/index.gdx" --info --format json |
  sed -n 's/^    "faces": \([0-9]*\),$/\1/p')" ||
  die "geodex-query --info on v1"
if ! [[ "$FACES" =~ ^[1-9][0-9]*$ ]]; then die "cannot tell the mesh's face count"; fi
# Pairs inside faces and at vertices, spread over the mesh (fixed seed).
awk -v f="$FACES" 'BEGIN { srand(20);
  for (i = 0; i < 64; i++)
    printf "%d 0.2 0.3 0.5 %d %s\n", int(rand() * f), int(rand() * f), (i % 4 ? "0.6 0.3 0.1" : "1 0 0") }' > pairs.txt
"$QUERY_BIN" "$REPO/$MODEL/1/index.gdx" --pairs pairs.txt > expected-v1.txt 2> query-v1.log ||
  { cat query-v1.log >&2; die "geodex-query on v1"; }
[ "$(wc -l < expected-v1.txt)" -eq 64 ] || die "geodex-query gave $(wc -l < expected-v1.txt) answers for 64 pairs"

# --- 3: two replicas, load over both, one killed -------------------------------
start_replica A 0
start_replica B 0
wait_version A "$REPLICA_ADDR_A" 1 30
wait_version B "$REPLICA_ADDR_B" 1 30
BOTH="$REPLICA_ADDR_A,$REPLICA_ADDR_B"
log "replicas A=$REPLICA_ADDR_A (pid $REPLICA_PID_A), B=$REPLICA_ADDR_B (pid $REPLICA_PID_B), serving v1"

# Generous retries: after the kill, calls that were in flight on A fail
# UNAVAILABLE and must be retried on B; backoff with jitter may need several.
CLIENT_FLAGS=(--server "$BOTH" --attempts 10 --timeout 20)
LOAD_SECONDS=8
log "load: geodex bench for ${LOAD_SECONDS} s plus a loop of geodex distance calls, over A and B"
"$CLIENT_BIN" bench "${CLIENT_FLAGS[@]}" --model "$MODEL" --concurrency 2 --batch 64 \
  --duration "$LOAD_SECONDS" --warmup 0 > bench.txt 2> bench.err &
BENCH_PID=$!
CHILDREN+=("$BENCH_PID")
# The loop checks the answers themselves, not only that calls succeed.
(
  n=0
  while [ ! -e stop-loop ]; do
    n=$((n + 1))
    if ! "$CLIENT_BIN" distance "${CLIENT_FLAGS[@]}" --model "$MODEL" --model-version 1 \
        --pairs pairs.txt > "loop-answer.txt" 2> "loop-$n.err"; then
      echo "call $n failed: $(cat "loop-$n.err")" >> loop-failures.txt
    elif ! cmp -s loop-answer.txt expected-v1.txt; then
      echo "call $n: answers differ from geodex-query" >> loop-failures.txt
    fi
    # Renamed into place: a reader never sees the file empty mid-write.
    echo "$n" > loop-count.tmp && mv loop-count.tmp loop-count.txt
  done
) &
LOOP_PID=$!
CHILDREN+=("$LOOP_PID")

sleep 3
# Round-robin is checked where it happens: both replicas have answered calls.
REQ_A="$(metric "$REPLICA_METRICS_A" geodex_requests_total)"
REQ_B="$(metric "$REPLICA_METRICS_B" geodex_requests_total)"
log "before the kill: A answered $REQ_A calls, B $REQ_B"
if ! [ "$REQ_A" -gt 0 ] || ! [ "$REQ_B" -gt 0 ]; then
  die "load is not spread over both replicas (A $REQ_A, B $REQ_B calls)"
fi
kill -0 "$BENCH_PID" 2>/dev/null || die "geodex bench ended before the kill: $(cat bench.err bench.txt)"
log "SIGKILL replica A (pid $REPLICA_PID_A) under load"
kill -KILL "$REPLICA_PID_A"
wait "$REPLICA_PID_A" 2>/dev/null || true
LOOP_BEFORE_KILL="$(cat loop-count.txt 2>/dev/null || echo 0)"

wait "$BENCH_PID" || die "geodex bench failed: $(cat bench.err)"
sleep 1  # a few more loop calls with A gone
touch stop-loop
wait "$LOOP_PID" || die "the distance loop crashed"
LOOP_CALLS="$(cat loop-count.txt)"
cat bench.txt
# geodex bench prints one "calls" line per stream of pairs (uniform, then near
# pairs); every one must be all ok.
bench_calls=0
while read -r calls_line; do
  [[ "$calls_line" =~ ^calls\ +([0-9]+)\ ok$ ]] ||
    die "geodex bench saw failed calls across the kill: '$calls_line' ($(cat bench.err))"
  bench_calls=$((bench_calls + BASH_REMATCH[1]))
done < <(grep '^calls ' bench.txt)
[ "$bench_calls" -gt 0 ] || die "geodex bench made no call: $(cat bench.txt bench.err)"
if [ -s loop-failures.txt ]; then
  cat loop-failures.txt >&2
  die "geodex distance calls failed or answered wrongly across the kill"
fi
[ "$LOOP_CALLS" -gt "$LOOP_BEFORE_KILL" ] || die "no geodex distance call ran after the kill"
log "no failed call: bench $bench_calls calls, loop $LOOP_CALLS calls ($LOOP_BEFORE_KILL before the kill), all answers equal to geodex-query's"

# --- 4: a new version, picked up by the survivor and by a restarted replica -----
build_version 2 "$FLAGS_V2"
wait_version B "$REPLICA_ADDR_B" 2 30
log "replica B picked up v2 by polling"
# The restarted replica takes its old port, as a pod behind the same address.
start_replica A "${REPLICA_ADDR_A##*:}"
wait_version A "$REPLICA_ADDR_A" 2 30
log "replica A restarted on $REPLICA_ADDR_A, serving v2"

# --- 5: answers of v2 equal geodex-query on the same index ------------------------
"$QUERY_BIN" "$REPO/$MODEL/2/index.gdx" --pairs pairs.txt > expected-v2.txt 2> query-v2.log ||
  { cat query-v2.log >&2; die "geodex-query on v2"; }
! cmp -s expected-v1.txt expected-v2.txt || die "v1 and v2 answer alike: the version check would prove nothing"
for name in A B; do
  addr_var="REPLICA_ADDR_$name"
  "$CLIENT_BIN" distance --server "${!addr_var}" --attempts 3 --model "$MODEL" --pairs pairs.txt \
    > "answers-v2-$name.txt" 2> "answers-v2-$name.err" ||
    die "geodex distance on replica $name: $(cat "answers-v2-$name.err")"
  if ! cmp -s "answers-v2-$name.txt" expected-v2.txt; then
    diff "answers-v2-$name.txt" expected-v2.txt | head -10 >&2
    die "replica $name's v2 answers differ from geodex-query's on $MODEL/2/index.gdx"
  fi
done
# And through the round-robin pair, as clients see them.
"$CLIENT_BIN" distance "${CLIENT_FLAGS[@]}" --model "$MODEL" --pairs pairs.txt > answers-v2-both.txt ||
  die "geodex distance over both replicas"
cmp -s answers-v2-both.txt expected-v2.txt || die "answers over both replicas differ from geodex-query's"

# No replica ever failed to load a version (a half-published index would).
for name in A B; do
  metrics_var="REPLICA_METRICS_$name"
  exec 3<>"/dev/tcp/127.0.0.1/${!metrics_var}"
  printf 'GET /metrics HTTP/1.0\r\nHost: 127.0.0.1\r\n\r\n' >&3
  failed="$(awk '$1 ~ /^geodex_model_state\{.*state="FAILED"/ { s += $NF } END { print s + 0 }' <&3)"
  exec 3<&-
  [ "$failed" -eq 0 ] || die "replica $name reports a FAILED model"
done
if grep -i 'fail' "$WORK"/server-*.log >&2; then
  die "a replica logged a failure (above)"
fi

log "PASSED in ${SECONDS} s: $SHARDS-shard builds of v1 (${ROUNDS_V[1]} rounds to an error target, as one process builds it) and v2 (fixed m), atomic publication, no failed call across a SIGKILL, v2 picked up by the survivor and the restarted replica, answers equal to geodex-query's"
