#!/usr/bin/env bash
# The README's first command. On a fresh Debian 12 machine: installs the
# dependencies, builds geodex, builds an index of the built-in torus, starts
# geodex-server on loopback, asks it for a distance, a path and a distance
# field (as text and as the torus colored by distance, field.ply, for MeshLab)
# with the `geodex` CLI, prints the answers, and stops the server.
#
#   bash deploy/demo.sh
#
# Environment: GEODEX_BUILD_DIR (default build), GEODEX_DEMO_DIR (default
# $GEODEX_BUILD_DIR/demo; the index and the outputs stay there),
# GEODEX_DEMO_SAMPLES (default 200).
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT="$(pwd)"

BUILD_DIR="${GEODEX_BUILD_DIR:-build}"
DEMO_DIR="${GEODEX_DEMO_DIR:-$BUILD_DIR/demo}"
SAMPLES="${GEODEX_DEMO_SAMPLES:-200}"
JOBS="$(nproc)"

if [ -t 1 ]; then
  step() { printf '\n\033[1m== %s\033[0m\n' "$*"; }
else
  step() { printf '\n== %s\n' "$*"; }
fi
die() { echo "demo: $*" >&2; exit 1; }

if [ ! -f server/CMakeLists.txt ]; then
  die "this checkout has no server/ yet, so there is no geodex-server to start;" \
      "the demo needs it and will not fake its answers"
fi

step "1/6 dependencies (deploy/install-deps.sh)"
bash deploy/install-deps.sh

step "2/6 build: geodex-build, geodex-server, geodex (in $BUILD_DIR)"
cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo > /dev/null
cmake --build "$BUILD_DIR" --target geodex-build geodex-server geodex -j"$JOBS"
BUILD_BIN="$ROOT/$BUILD_DIR/core/geodex-build"
SERVER_BIN="$ROOT/$BUILD_DIR/server/geodex-server"
GEODEX="$ROOT/$BUILD_DIR/client/geodex"
for b in "$BUILD_BIN" "$SERVER_BIN" "$GEODEX"; do [ -x "$b" ] || die "missing $b after the build"; done

mkdir -p "$DEMO_DIR"
DEMO_DIR="$(cd "$DEMO_DIR" && pwd)"
INDEX="$DEMO_DIR/models/torus/1/index.gdx"
step "3/6 index of the built-in torus (R = 2, r = 0.7), $SAMPLES samples -> $INDEX"
mkdir -p "$(dirname "$INDEX")"
if [ -s "$INDEX" ] && [ "$(cat "$DEMO_DIR/.samples" 2>/dev/null)" = "$SAMPLES" ]; then
  echo "(already built; delete $INDEX to rebuild)"
else
  "$BUILD_BIN" builtin:torus -o "$INDEX" --samples "$SAMPLES"
  echo "$SAMPLES" > "$DEMO_DIR/.samples"
fi

# A free port on loopback, from 50051 up.
PORT=50051
while (exec 3<>"/dev/tcp/127.0.0.1/$PORT") 2>/dev/null; do PORT=$((PORT + 1)); done
ADDR="127.0.0.1:$PORT"
export GEODEX_SERVER="$ADDR"

step "4/6 start geodex-server --models $DEMO_DIR/models --listen $ADDR"
"$SERVER_BIN" --models "$DEMO_DIR/models" --listen "$ADDR" > "$DEMO_DIR/server.log" 2>&1 &
SERVER_PID=$!
stop_server() {
  if kill -0 "$SERVER_PID" 2>/dev/null; then
    kill -TERM "$SERVER_PID"
    wait "$SERVER_PID" || true
  fi
}
trap stop_server EXIT
for _ in $(seq 1 300); do
  kill -0 "$SERVER_PID" 2>/dev/null || { cat "$DEMO_DIR/server.log" >&2; die "geodex-server exited"; }
  if "$GEODEX" models --attempts 1 --timeout 2 2>/dev/null | grep -qE '^torus .* SERVING '; then
    break
  fi
  sleep 0.2
done
"$GEODEX" models

cd "$DEMO_DIR"
step "5/6 queries with the geodex CLI"

echo "-- distances (geodex distance --xyz: 3D points, located on the surface first)"
cat > pairs_xyz.txt <<'EOF'
# xa ya za   xb yb zb
2.7 0 0   2 0 0.7
2.7 0 0   1.3 0 0
2.7 0 0   -2.7 0 0
EOF
"$GEODEX" distance --model torus --pairs pairs_xyz.txt --xyz > distances.txt
paste <(grep -v '^#' pairs_xyz.txt) distances.txt | awk '
  BEGIN { pi = atan2(0, -1)
          note[1] = sprintf("a quarter of the tube circle, pi*0.7/2 = %.4f on the smooth torus", pi * 0.35)
          note[2] = sprintf("half the tube circle, pi*0.7 = %.4f on the smooth torus", pi * 0.7)
          note[3] = sprintf("opposite sides of the outer equator (its half is pi*2.7 = %.4f)", pi * 2.7) }
  { printf "  (%s, %s, %s) -> (%s, %s, %s): %.6f   [%s]\n", $1, $2, $3, $4, $5, $6, $7, note[NR] }'

echo
echo "-- a geodesic path (geodex path --format obj), outer equator to the opposite side"
sed -n 4p pairs_xyz.txt > path_xyz.txt
"$GEODEX" path --model torus --pairs path_xyz.txt --xyz --format obj --out path.obj
"$GEODEX" path --model torus --pairs path_xyz.txt --xyz --format json --out path.json
awk '/^v / { n++; if (n <= 3) printf "  point %d: %s %s %s\n", n, $2, $3, $4 }
     /^# path/ { len = $5 }
     END { printf "  ... %d points, length %s; polyline in %s/path.obj\n", n, len, ENVIRON["PWD"] }' path.obj

echo
echo "-- a distance field (geodex field) from the point nearest (2.7, 0, 0)"
echo "2.7 0 0" > source_xyz.txt
"$GEODEX" locate --model torus --points source_xyz.txt | awk '{ print $1, $2, $3, $4 }' > sources.txt
echo "  source on the surface (face w0 w1 w2): $(cat sources.txt)"
"$GEODEX" field --model torus --sources sources.txt --out field.txt
awk '$1 != "inf" { n++; s += $1; if (n == 1 || $1 > max) { max = $1; far = NR - 1 } }
     END { printf "  %d vertex distances: mean %.4f, farthest vertex %d at %.4f\n", n, s / n, far, max }
  ' field.txt
echo "  per-vertex distances in $DEMO_DIR/field.txt"

echo
echo "-- the same field on the mesh (geodex field --out field.ply: GetMesh + the field)"
"$GEODEX" field --model torus --sources sources.txt --out field.ply
echo "  $DEMO_DIR/field.ply (open it in MeshLab: color = distance, vertex quality = distance):"
awk '{ print "    " $0 }
     /^end_header$/ { body = NR }
     body && NR >= body + 3 { print "    ..."; exit }' field.ply

step "6/6 stop the server"
stop_server
trap - EXIT
echo "done. Server log: $DEMO_DIR/server.log"
