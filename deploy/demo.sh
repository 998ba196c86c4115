#!/usr/bin/env bash
# The README's first command. On a fresh Debian 12 machine: installs the
# dependencies, builds geodex, builds an index of the built-in torus with the
# builder's default accuracy target, starts geodex-server on loopback, asks
# it for distances (within a tolerance of 0.5%, with their error bounds), a
# path and a distance field
# (as text and as the torus colored by distance, field.ply, for MeshLab) with
# the `geodex` CLI, and checks every distance against the exact one that
# geodex-geodesic computes on the same mesh: the demo fails if an answer is
# farther from the exact distance than its bound. Then it stops the server.
#
#   bash deploy/demo.sh
#
# Environment: GEODEX_BUILD_DIR (default build), GEODEX_DEMO_DIR (default
# $GEODEX_BUILD_DIR/demo; the index and the outputs stay there),
# GEODEX_DEMO_BUILD_FLAGS (extra geodex-build flags, default none: the
# default error target).
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT="$(pwd)"

BUILD_DIR="${GEODEX_BUILD_DIR:-build}"
DEMO_DIR="${GEODEX_DEMO_DIR:-$BUILD_DIR/demo}"
BUILD_FLAGS="${GEODEX_DEMO_BUILD_FLAGS:-}"
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

step "2/6 build: geodex-build, geodex-server, geodex, geodex-geodesic (in $BUILD_DIR)"
cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo > /dev/null
cmake --build "$BUILD_DIR" --target geodex-build geodex-server geodex geodex-geodesic -j"$JOBS"
BUILD_BIN="$ROOT/$BUILD_DIR/core/geodex-build"
SERVER_BIN="$ROOT/$BUILD_DIR/server/geodex-server"
GEODEX="$ROOT/$BUILD_DIR/client/geodex"
EXACT_BIN="$ROOT/$BUILD_DIR/core/geodex-geodesic"
for b in "$BUILD_BIN" "$SERVER_BIN" "$GEODEX" "$EXACT_BIN"; do
  [ -x "$b" ] || die "missing $b after the build"
done

mkdir -p "$DEMO_DIR"
DEMO_DIR="$(cd "$DEMO_DIR" && pwd)"
INDEX="$DEMO_DIR/models/torus/1/index.gdx"
step "3/6 index of the built-in torus (R = 2, r = 0.7) to the default error target -> $INDEX"
mkdir -p "$(dirname "$INDEX")"
# The flags and the builder the index was made with: other ones rebuild it.
STAMP="$BUILD_FLAGS $(cksum < "$BUILD_BIN")"
if [ -s "$INDEX" ] && [ "$(cat "$DEMO_DIR/.build-stamp" 2>/dev/null)" = "$STAMP" ]; then
  echo "(already built; delete $INDEX to rebuild)"
else
  # Rounds of samples until the held-out error meets the target (minutes on
  # two cores); each round's figures are logged.
  # shellcheck disable=SC2086  # BUILD_FLAGS is a list of flags
  "$BUILD_BIN" builtin:torus -o "$INDEX" $BUILD_FLAGS
  echo "$STAMP" > "$DEMO_DIR/.build-stamp"
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
step "5/6 queries with the geodex CLI, each distance beside the exact one"

# The torus as the server has it (GetMesh, through `geodex field --out
# X.ply`): the exact distances are computed on this very mesh.
echo "2.7 0 0" > source_xyz.txt
"$GEODEX" locate --model torus --points source_xyz.txt | awk '{ print $1, $2, $3, $4 }' > sources.txt
"$GEODEX" field --model torus --sources sources.txt --out field.ply
"$GEODEX" field --model torus --sources sources.txt --out field.txt

cat > pairs_xyz.txt <<'PAIRS'
# xa ya za   xb yb zb
2.7 0 0   2 0 0.7
2.7 0 0   1.3 0 0
2.7 0 0   -2.7 0 0
PAIRS
# Each point located on the surface ("face w0 w1 w2"), then paired.
grep -v '^#' pairs_xyz.txt | awk '{ print $1, $2, $3; print $4, $5, $6 }' > points_xyz.txt
"$GEODEX" locate --model torus --points points_xyz.txt |
  awk '{ printf "%s %s %s %s%s", $1, $2, $3, $4, (NR % 2 ? " " : "\n") }' > pairs.txt
# The field's farthest vertex from the source, as a fourth pair (at a
# corner of a face that has it).
FAR="$(awk '$1 != "inf" && $1 > max { max = $1; far = NR - 1 } END { print far }' field.txt)"
[ -n "$FAR" ] || die "the distance field has no finite distance"
FAR_POINT="$(awk -v v="$FAR" '
  /^element vertex/ { vertices = $3 }
  /^end_header$/ { body = 1; next }
  body && seen < vertices { seen++; next }
  body { for (i = 2; i <= 4; i++) if ($i == v) {
           printf "%d %d %d %d", faces, (i == 2), (i == 3), (i == 4); exit }
         faces++ }' field.ply)"
[ -n "$FAR_POINT" ] || die "vertex $FAR is on no face of field.ply"
echo "$(cat sources.txt) $FAR_POINT" >> pairs.txt

# With a relative tolerance of 0.5%: the server refines every answer whose
# bound exceeds it. A bound is a calibrated statistic (99.5% of held-out
# pairs), and these pairs are special: (1.3,0,0) and (-2.7,0,0) are each
# joined to (2.7,0,0) by two geodesics (over and under the tube, or round
# either side of the hole), where the O(1) answer errs most, by 1-2.4%
# at this m, beyond its bound.
"$GEODEX" distance --model torus --pairs pairs.txt --error-bounds --tolerance 0.005 > distances.txt
"$EXACT_BIN" field.ply --pairs pairs.txt > exact.txt
{ [ "$(wc -l < distances.txt)" -eq 4 ] && [ "$(wc -l < exact.txt)" -eq 4 ]; } ||
  die "expected 4 answers from geodex and from geodex-geodesic"

echo "-- distances within a tolerance of 0.5%: geodex's answer and its error bound, the exact"
echo "   distance on the same mesh (geodex-geodesic), and the error; an answer farther from exact"
echo "   than its bound fails"
printf "   %-34s %10s %10s %10s %9s\n" pair geodex bound exact error
paste <(grep -v '^#' pairs_xyz.txt; echo "farthest vertex $FAR of the field") \
  distances.txt exact.txt | awk -F'\t' '
  { split($2, a, " "); d = a[1]; b = a[2]; x = $3 + 0
    if ($1 ~ /^farthest/) name = $1
    else { split($1, p, " ")
           name = sprintf("(%s,%s,%s) -> (%s,%s,%s)", p[1], p[2], p[3], p[4], p[5], p[6]) }
    err = d - x
    ok = (err <= b + 1e-12 && -err <= b + 1e-12)
    printf "   %-34s %10.6f %10.6f %10.6f %+8.3f%% %s\n", name, d, b, x, 100 * err / x,
           ok ? "within the bound" : "OUTSIDE THE BOUND"
    if (!ok) bad++ }
  END { exit bad > 0 }' || die "an answer lies farther from the exact distance than its error bound"
awk -v v="$FAR" 'NR == v + 1 { printf "   (the field says %.6f at vertex %d)\n", $1, v }' field.txt

echo
echo "-- a geodesic path (geodex path --format obj), outer equator to the opposite side"
sed -n 3p pairs.txt > path.txt
"$GEODEX" path --model torus --pairs path.txt --format obj --out path.obj
"$GEODEX" path --model torus --pairs path.txt --format json --out path.json
awk -v exact="$(sed -n 3p exact.txt)" '
     /^v / { n++; if (n <= 3) printf "  point %d: %s %s %s\n", n, $2, $3, $4 }
     /^# path/ { len = $5 }
     END { printf "  ... %d points, length %s (exact distance %.6f); polyline in %s/path.obj\n",
                  n, len, exact, ENVIRON["PWD"] }' path.obj

echo
echo "-- a distance field (geodex field) from the point nearest (2.7, 0, 0)"
echo "  source on the surface (face w0 w1 w2): $(cat sources.txt)"
awk '$1 != "inf" { n++; s += $1; if (n == 1 || $1 > max) { max = $1; far = NR - 1 } }
     END { printf "  %d vertex distances: mean %.4f, farthest vertex %d at %.4f\n", n, s / n, far, max }
  ' field.txt
echo "  per-vertex distances in $DEMO_DIR/field.txt"
echo "  the same field on the mesh: $DEMO_DIR/field.ply (open it in MeshLab: color = distance,"
echo "  vertex quality = distance):"
awk '{ print "    " $0 }
     /^end_header$/ { body = NR }
     body && NR >= body + 3 { print "    ..."; exit }' field.ply

step "6/6 stop the server"
stop_server
trap - EXIT
echo "done. Server log: $DEMO_DIR/server.log"
