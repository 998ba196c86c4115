#!/usr/bin/env bash
# Measures the figures deploy/README.md sizes the cluster with, for one mesh
# and sample count per MESH:SAMPLES argument:
#   - build: plan, rows (one shard holding every sample, one thread: seconds
#     per exact propagation from a source), merge (with calibration) wall times;
#   - index file size;
#   - geodex-server memory with that one index loaded: VmRSS, RssAnon, RssFile
#     from /proc/PID/status, read after the model is SERVING and after a burst
#     of queries has touched the mapping.
# Prints one markdown table row per argument.
#
#   deploy/measure-sizing.sh [--bin-dir DIR] MESH:SAMPLES...
#   e.g. deploy/measure-sizing.sh --bin-dir build builtin:torus:150 ../shared/meshes/spot_11k.obj:500
#
# MESH is builtin:NAME or a mesh file (read in place, never copied).
set -euo pipefail

SCRIPT_DIR="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
BIN_DIR="$SCRIPT_DIR/../build"
ARGS=()
while [ $# -gt 0 ]; do
  case "$1" in
    --bin-dir) BIN_DIR="${2:?--bin-dir needs a value}"; shift 2 ;;
    -h|--help) sed -n '2,16p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) ARGS+=("$1"); shift ;;
  esac
done
[ "${#ARGS[@]}" -gt 0 ] || { echo "measure-sizing: give at least one MESH:SAMPLES" >&2; exit 2; }
BUILD_BIN="$BIN_DIR/core/geodex-build"
SERVER_BIN="$BIN_DIR/server/geodex-server"
CLIENT_BIN="$BIN_DIR/client/geodex"
for b in "$BUILD_BIN" "$SERVER_BIN" "$CLIENT_BIN"; do
  [ -x "$b" ] || { echo "measure-sizing: no executable $b" >&2; exit 2; }
done

WORK="$(mktemp -d "${TMPDIR:-/tmp}/geodex-sizing.XXXXXX")"
SERVER_PID=""
cleanup() {
  if [ -n "$SERVER_PID" ]; then kill -KILL "$SERVER_PID" 2>/dev/null || true; wait "$SERVER_PID" 2>/dev/null || true; fi
  rm -rf "$WORK"
}
trap cleanup EXIT

# seconds CMD...: runs CMD, prints its wall time in seconds.
seconds() {
  local start end
  start="$(date +%s.%N)"
  "$@" > "$WORK/cmd.log" 2>&1 || { cat "$WORK/cmd.log" >&2; echo "measure-sizing: failed: $*" >&2; exit 1; }
  end="$(date +%s.%N)"
  awk -v a="$start" -v b="$end" 'BEGIN { printf "%.2f", b - a }'
}
kib() { awk -v k="$2" '$1 == k ":" { print $2 }' "/proc/$1/status"; }

echo "| mesh | vertices | m | plan s | rows s (1 thread) | s/source | merge s | index MiB | VmRSS MiB | RssAnon MiB | RssFile MiB |"
echo "|---|---|---|---|---|---|---|---|---|---|---|"
for arg in "${ARGS[@]}"; do
  mesh="${arg%:*}" samples="${arg##*:}"
  name="$(basename "${mesh#builtin:}")"; name="${name%.*}"; name="${name//[^A-Za-z0-9_-]/_}"
  wd="$WORK/$name-work" repo="$WORK/repo-$name"
  t_plan="$(seconds "$BUILD_BIN" plan "$mesh" --samples "$samples" --threads 1 -o "$wd")"
  t_rows="$(seconds "$BUILD_BIN" rows "$wd" --shard 0/1 --threads 1)"
  mkdir -p "$repo/$name/1"
  t_merge="$(seconds "$BUILD_BIN" merge "$wd" -o "$repo/$name/1/index.gdx")"
  m="$(sed -n 's/^geodex-build rows: shard 0\/1, \([0-9]*\) samples$/\1/p' "$WORK/cmd.log" || true)"
  [ -n "$m" ] || m="$samples"
  vertices="$(sed -n 's/^element vertex \([0-9]*\)$/\1/p' "$wd/mesh.ply")"
  bytes="$(stat -c %s "$repo/$name/1/index.gdx")"

  "$SERVER_BIN" --models "$repo" --listen 127.0.0.1:0 --workers 2 --poll-seconds 0 \
    > "$WORK/server.out" 2> "$WORK/server.log" &
  SERVER_PID=$!
  port=""
  for _ in $(seq 1 300); do
    port="$(sed -n 's/^listening on port \([0-9]*\)$/\1/p' "$WORK/server.out")"
    if [ -n "$port" ] && "$CLIENT_BIN" models --server "127.0.0.1:$port" --attempts 1 --timeout 2 2>/dev/null |
        grep -qE "^$name .* SERVING "; then
      break
    fi
    sleep 0.2
  done
  # Queries fault in the pages they read, as in service.
  "$CLIENT_BIN" bench --server "127.0.0.1:$port" --model "$name" --duration 3 --warmup 0 \
    --concurrency 2 > /dev/null
  rss="$(kib "$SERVER_PID" VmRSS)" anon="$(kib "$SERVER_PID" RssAnon)" file="$(kib "$SERVER_PID" RssFile)"
  kill -TERM "$SERVER_PID"; wait "$SERVER_PID" || true; SERVER_PID=""

  awk -v mesh="$mesh" -v v="$vertices" -v m="$m" -v tp="$t_plan" -v tr="$t_rows" -v tm="$t_merge" \
      -v b="$bytes" -v rss="$rss" -v anon="$anon" -v file="$file" 'BEGIN {
    printf "| %s | %d | %d | %.2f | %.2f | %.4f | %.2f | %.1f | %.1f | %.1f | %.1f |\n",
      mesh, v, m, tp, tr, tr / m, tm, b / 1048576, rss / 1024, anon / 1024, file / 1024 }'
  rm -rf "$wd" "$repo"
done
