#!/usr/bin/env bash
# End-to-end test of the `geodex` CLI against a real server process on
# loopback (a random free port): queries cross-checked against geodex-query on
# the same index, bad input, unknown models, no server, bearer tokens, TLS.
#
#   e2e_test.sh --geodex BIN --server-bin BIN --build-bin BIN --query-bin BIN
#   e2e_test.sh --fake --geodex BIN --server-bin geodex-fake-server
#
# --fake runs the CLI checks against the fake server
# (client/fake_geodex_service_testing.h: closed-form answers, model "fake") and skips everything that needs the real geometry.
# Exit codes: 0 all passed, 1 a check failed, 77 the server binary is missing
# (ctest reports the test as skipped).
set -uo pipefail

GEODEX="" SERVER_BIN="" BUILD_BIN="" QUERY_BIN="" FAKE=0
while [ $# -gt 0 ]; do
  case "$1" in
    --geodex) GEODEX="$2"; shift 2 ;;
    --server-bin) SERVER_BIN="$2"; shift 2 ;;
    --build-bin) BUILD_BIN="$2"; shift 2 ;;
    --query-bin) QUERY_BIN="$2"; shift 2 ;;
    --fake) FAKE=1; shift ;;
    *) echo "e2e: unknown argument $1" >&2; exit 2 ;;
  esac
done
abspath() { [ -z "$1" ] || (cd "$(dirname "$1")" 2>/dev/null && echo "$(pwd)/$(basename "$1")") || echo "$1"; }
GEODEX="$(abspath "$GEODEX")" SERVER_BIN="$(abspath "$SERVER_BIN")"
BUILD_BIN="$(abspath "$BUILD_BIN")" QUERY_BIN="$(abspath "$QUERY_BIN")"
if [ ! -x "$SERVER_BIN" ]; then
  echo "e2e: SKIPPED: no server binary at $SERVER_BIN (server/ not built yet)"
  exit 77
fi
[ -x "$GEODEX" ] || { echo "e2e: no geodex CLI at $GEODEX" >&2; exit 1; }

WORK="$(mktemp -d "${TMPDIR:-/tmp}/geodex-e2e.XXXXXX")"
SERVER_PID=""
cleanup() {
  if [ -n "$SERVER_PID" ] && kill -0 "$SERVER_PID" 2>/dev/null; then
    kill -TERM "$SERVER_PID" 2>/dev/null
    wait "$SERVER_PID" 2>/dev/null
  fi
  rm -rf "$WORK"
}
trap cleanup EXIT

FAILURES=0
CHECKS=0
pass() { CHECKS=$((CHECKS + 1)); echo "ok    $1"; }
fail() {
  CHECKS=$((CHECKS + 1)); FAILURES=$((FAILURES + 1))
  echo "FAIL  $1" >&2
  shift
  for f in "$@"; do [ -f "$f" ] && sed 's/^/      | /' "$f" | head -20 >&2; done
}

# A port nothing listens on right now (bash's /dev/tcp connect fails).
free_port() {
  local port
  for _ in $(seq 1 100); do
    port=$((20000 + RANDOM % 40000))
    if ! (exec 3<>"/dev/tcp/127.0.0.1/$port") 2>/dev/null; then
      echo "$port"
      return 0
    fi
  done
  return 1
}

# start_server LOG ARGS...: starts the server on a free port (retrying if the
# port is taken in the meantime) and waits until MODEL is SERVING.
MODEL="cube"
[ $FAKE -eq 1 ] && MODEL="fake"
ADDR=""
start_server() {
  local log="$1"; shift
  for _ in 1 2 3; do
    local port
    port="$(free_port)" || { echo "e2e: no free port" >&2; return 1; }
    ADDR="127.0.0.1:$port"
    "$SERVER_BIN" --models "$WORK/models" --listen "$ADDR" "$@" > "$log" 2>&1 &
    SERVER_PID=$!
    for _ in $(seq 1 300); do
      if ! kill -0 "$SERVER_PID" 2>/dev/null; then break; fi
      if "$GEODEX" models --server "$ADDR" --timeout 2 --attempts 1 "${CLIENT_AUTH[@]}" \
          2>/dev/null | grep -E "^$MODEL .* SERVING " >/dev/null; then
        return 0
      fi
      sleep 0.2
    done
    if kill -0 "$SERVER_PID" 2>/dev/null; then
      echo "e2e: server did not serve $MODEL within 60 s" >&2
      cat "$log" >&2
      return 1
    fi
    wait "$SERVER_PID" 2>/dev/null
    SERVER_PID=""
  done
  echo "e2e: server would not start" >&2
  cat "$log" >&2
  return 1
}

stop_server() {
  kill -TERM "$SERVER_PID"
  local status
  wait "$SERVER_PID"
  status=$?
  SERVER_PID=""
  return $status
}

# Numeric comparison of two files of whitespace-separated numbers ("inf"
# allowed): same shape, |a - b| <= 1e-9 * max(1, |a|).
same_numbers() {
  awk 'NR == FNR { line[FNR] = $0; n = FNR; next }
       { if (!(FNR in line)) { bad = 1; exit }
         k = split(line[FNR], a); m = split($0, b)
         if (k != m) { bad = 1; exit }
         for (i = 1; i <= k; i++) {
           if (a[i] == b[i]) continue
           d = a[i] - b[i]; if (d < 0) d = -d
           s = a[i] < 0 ? -a[i] : a[i]; if (s < 1) s = 1
           if (d > 1e-9 * s) { bad = 1; exit }
         }
         seen = FNR }
       END { exit (bad || seen != n) }' "$1" "$2"
}

CLIENT_AUTH=()
cd "$WORK" || exit 1
mkdir -p models

# --- the model ------------------------------------------------------------------
if [ $FAKE -eq 0 ]; then
  mkdir -p models/cube/1
  if ! "$BUILD_BIN" builtin:cube -o models/cube/1/index.gdx --samples 64 > build.log 2>&1; then
    echo "e2e: geodex-build failed" >&2; cat build.log >&2; exit 1
  fi
fi

start_server server.log || exit 1
S=(--server "$ADDR")
echo "e2e: server pid $SERVER_PID on $ADDR, model $MODEL"

# --- happy paths ----------------------------------------------------------------
"$GEODEX" models "${S[@]}" > models.txt 2> err.txt && grep -q "^$MODEL " models.txt &&
  pass "models lists $MODEL" || fail "models" models.txt err.txt

"$GEODEX" info "${S[@]}" --model "$MODEL" --format json > info.json 2> err.txt &&
  grep -q "\"name\": \"$MODEL\"" info.json && pass "info" || fail "info" info.json err.txt
# The real server sends the build report; the fake sends none, and the
# client then lays out the counts and the stored lines.
if [ $FAKE -eq 0 ]; then
  "$GEODEX" info "${S[@]}" --model "$MODEL" > info.txt 2> err.txt &&
    grep -q "^model $MODEL, version 1 (SERVING): geodex index" info.txt &&
    grep -q "^  error target  " info.txt && pass "info: the build report for a person" ||
    fail "info: the build report for a person" info.txt err.txt
else
  "$GEODEX" info "${S[@]}" --model "$MODEL" > info.txt 2> err.txt &&
    grep -q "^model $MODEL, version 1 (SERVING)" info.txt &&
    grep -q "^  mesh  " info.txt && pass "info: the counts for a person without a report" ||
    fail "info: the counts for a person without a report" info.txt err.txt
fi
NUM_FACES="$(awk -F': ' '/"num_faces"/ { gsub(",", "", $2); print $2 }' info.json)"
NUM_VERTICES="$(awk -F': ' '/"num_vertices"/ { gsub(",", "", $2); print $2 }' info.json)"
[ "${NUM_FACES:-0}" -gt 0 ] && pass "info: $NUM_FACES faces, $NUM_VERTICES vertices" ||
  fail "info has no face count" info.json

# Pairs over the first faces (at most 100), one at a vertex, one on an edge.
awk -v n="$NUM_FACES" 'BEGIN {
  srand(7); if (n > 100) n = 100
  print "# fa a0 a1 a2 fb b0 b1 b2"
  print "0 1 0 0 " n - 1 " 0 1 0"
  print "1 0.5 0.5 0 2 0 0.5 0.5"
  for (i = 0; i < 40; i++) {
    u = rand(); v = rand(); if (u + v > 1) { u = 1 - u; v = 1 - v }
    s = rand(); t = rand(); if (s + t > 1) { s = 1 - s; t = 1 - t }
    printf "%d %.17g %.17g %.17g %d %.17g %.17g %.17g\n", int(rand() * n), 1 - u - v, u, v,
           int(rand() * n), 1 - s - t, s, t
  }
}' > pairs.txt

"$GEODEX" distance "${S[@]}" --model "$MODEL" --pairs pairs.txt > d_cli.txt 2> err.txt &&
  [ "$(wc -l < d_cli.txt)" -eq 42 ] && pass "distance: 42 pairs" || fail "distance" d_cli.txt err.txt

"$GEODEX" distance "${S[@]}" --model "$MODEL" --pairs - < pairs.txt > d_stdin.txt 2> err.txt &&
  cmp -s d_cli.txt d_stdin.txt && pass "distance from standard input" ||
  fail "distance --pairs -" d_stdin.txt err.txt

# Many pairs: batched and pipelined over one stream; order must hold.
for _ in $(seq 1 120); do grep -v '^#' pairs.txt; done > many.txt
"$GEODEX" distance "${S[@]}" --model "$MODEL" --pairs many.txt --batch 500 > d_many.txt 2> err.txt &&
  for _ in $(seq 1 120); do cat d_cli.txt; done | cmp -s - d_many.txt &&
  pass "distance: 5040 pairs streamed in batches of 500, in order" ||
  fail "distance (many pairs)" err.txt

if [ $FAKE -eq 0 ]; then
  "$QUERY_BIN" models/cube/1/index.gdx --pairs pairs.txt > d_offline.txt 2> err.txt
  same_numbers d_offline.txt d_cli.txt && pass "distance equals geodex-query on the same index" ||
    fail "distance differs from geodex-query" d_offline.txt d_cli.txt err.txt
  for mode in unfold exact; do
    "$QUERY_BIN" models/cube/1/index.gdx --pairs pairs.txt --near-pairs $mode > d_offline.txt 2> err.txt
    "$GEODEX" distance "${S[@]}" --model "$MODEL" --pairs pairs.txt --near-pairs $mode \
      > d_mode.txt 2>> err.txt
    same_numbers d_offline.txt d_mode.txt &&
      pass "distance --near-pairs $mode equals geodex-query --near-pairs $mode" ||
      fail "distance --near-pairs $mode differs from geodex-query" d_offline.txt d_mode.txt err.txt
  done
  # Error bounds and a tolerance: "distance bound" lines, as geodex-query gives.
  "$QUERY_BIN" models/cube/1/index.gdx --pairs pairs.txt --error-bounds --tolerance 0.005 \
    > d_offline.txt 2> err.txt
  "$GEODEX" distance "${S[@]}" --model "$MODEL" --pairs pairs.txt --error-bounds \
    --tolerance 0.005 > d_bounds.txt 2>> err.txt
  same_numbers d_offline.txt d_bounds.txt &&
    [ "$(awk 'NF == 2 && $2 >= 0 && $2 <= 0.005 * $1 + 1e-12' d_bounds.txt | wc -l)" -eq 42 ] &&
    pass "distance --error-bounds --tolerance 0.005 equals geodex-query; every bound meets it" ||
    fail "distance with bounds differs from geodex-query" d_offline.txt d_bounds.txt err.txt
  # The every-distance mode: the threshold travels in L1000, and a server
  # answers as the offline tool does; it refines more than the default.
  "$QUERY_BIN" models/cube/1/index.gdx --pairs pairs.txt --refine-below 1000 > d_offline.txt 2> err.txt
  "$GEODEX" distance "${S[@]}" --model "$MODEL" --pairs pairs.txt --refine-below 1000 \
    > d_every.txt 2>> err.txt
  "$QUERY_BIN" models/cube/1/index.gdx --pairs pairs.txt --near-pairs exact --refine-below 1000 \
    > d_exact.txt 2>> err.txt
  same_numbers d_offline.txt d_every.txt &&
    [ "$(paste d_every.txt d_exact.txt | awk '$1 < $2 * (1 - 1e-9) || $1 > $2 * 1.0201' | wc -l)" -eq 0 ] &&
    pass "distance --refine-below 1000 equals geodex-query's; every answer within 2% of exact" ||
    fail "distance --refine-below differs from geodex-query or from exact" d_offline.txt d_every.txt d_exact.txt err.txt
fi

# Paths. Path tracing belongs to core (a pair it cannot trace is INTERNAL, and
# core's own tests own that); here: the CLI gives what geodex-query gives on the
# same index, and formats correctly the paths that can be traced.
grep -v '^#' pairs.txt > path_pairs.txt
if [ $FAKE -eq 0 ]; then
  : > path_pairs.txt
  untraceable=""
  i=0
  while read -r line; do
    i=$((i + 1))
    if printf '%s\n' "$line" | "$QUERY_BIN" models/cube/1/index.gdx --paths - > /dev/null 2>&1; then
      printf '%s\n' "$line" >> path_pairs.txt
    else
      untraceable="$untraceable $i"
    fi
  done < <(grep -v '^#' pairs.txt)
  [ -n "$untraceable" ] && echo "note  geodex-query cannot trace the paths of pairs$untraceable (core)"
  "$QUERY_BIN" models/cube/1/index.gdx --paths pairs.txt > /dev/null 2> err_offline.txt
  offline=$?
  "$GEODEX" path "${S[@]}" --model "$MODEL" --pairs pairs.txt --out all_paths.json > /dev/null 2> err.txt
  online=$?
  if [ $offline -eq 0 ] && [ $online -eq 0 ]; then
    pass "path: all pairs traced, as by geodex-query"
  elif [ $offline -ne 0 ] && [ $online -eq 1 ] &&
       [ "$(sed 's/.*: //' err.txt)" = "$(sed 's/.*: //' err_offline.txt)" ]; then
    pass "path: fails like geodex-query on a pair core cannot trace (exit 1, same reason)"
  else
    fail "path: CLI (exit $online) and geodex-query (exit $offline) disagree" err.txt err_offline.txt
  fi
fi
NPATHS="$(wc -l < path_pairs.txt)"
"$GEODEX" path "${S[@]}" --model "$MODEL" --pairs path_pairs.txt --format obj --out paths.obj 2> err.txt &&
  [ "$(grep -c '^l ' paths.obj)" -eq "$NPATHS" ] && pass "path: $NPATHS polylines as OBJ" ||
  fail "path --format obj" paths.obj err.txt
"$GEODEX" path "${S[@]}" --model "$MODEL" --pairs path_pairs.txt --out paths.json 2> err.txt &&
  [ "$(grep -c '"length"' paths.json)" -eq "$NPATHS" ] && pass "path: JSON by extension" ||
  fail "path json" paths.json err.txt
"$GEODEX" path "${S[@]}" --model "$MODEL" --pairs path_pairs.txt --format ply --out paths.ply 2> err.txt &&
  head -1 paths.ply | grep -q '^ply' && pass "path: PLY" || fail "path ply" paths.ply err.txt
xyz_of() { grep -o '"xyz": \[[^]]*\]' "$1" | tr -d '"xyz:[],' ; }
if [ $FAKE -eq 0 ]; then
  # The same polylines as geodex-query traces on the same index.
  "$QUERY_BIN" models/cube/1/index.gdx --paths path_pairs.txt --format json > paths_offline.json 2> err.txt
  xyz_of paths.json > xyz_cli.txt
  xyz_of paths_offline.json > xyz_offline.txt
  [ -s xyz_cli.txt ] && same_numbers xyz_offline.txt xyz_cli.txt &&
    pass "path points equal geodex-query's ($(wc -l < xyz_cli.txt) points)" ||
    fail "path points differ from geodex-query" err.txt
else
  # The fake's path length is its distance.
  "$GEODEX" distance "${S[@]}" --model "$MODEL" --pairs path_pairs.txt > d_paths.txt 2> err.txt
  awk -F'"length": ' 'NF > 1 { split($2, a, ","); print a[1] }' paths.json > lengths.txt
  same_numbers d_paths.txt lengths.txt && pass "path lengths are the fake's distances" ||
    fail "path lengths" lengths.txt d_paths.txt
fi

printf '0 1 0 0\n%d 0.2 0.3 0.5\n' 1 > sources.txt
"$GEODEX" field "${S[@]}" --model "$MODEL" --sources sources.txt --out field.txt 2> err.txt &&
  [ "$(wc -l < field.txt)" -eq "$NUM_VERTICES" ] && pass "field: $NUM_VERTICES vertex distances" ||
  fail "field" err.txt
if [ $FAKE -eq 0 ]; then
  "$QUERY_BIN" models/cube/1/index.gdx --field sources.txt > field_offline.txt 2> err.txt
  same_numbers field_offline.txt field.txt && pass "field equals geodex-query" ||
    fail "field differs from geodex-query" err.txt
fi
# The field as a colored mesh (GetMesh): a complete ASCII PLY with the model's
# vertex and face counts, faces naming existing vertices, and as vertex quality
# the same distances as the text field (the model is connected: all finite,
# the smallest 0, at the source vertex).
if "$GEODEX" field "${S[@]}" --model "$MODEL" --sources sources.txt --out field.ply \
    > /dev/null 2> err.txt; then
  pass "field --out field.ply"
else
  fail "field --out field.ply" err.txt
fi
if [ "$(sed -n '1p;2p' field.ply | tr '\n' ' ')" = "ply format ascii 1.0 " ] &&
   grep -qx "element vertex $NUM_VERTICES" field.ply && grep -qx "element face $NUM_FACES" field.ply &&
   grep -qx "property float quality" field.ply &&
   awk -v nv="$NUM_VERTICES" -v nf="$NUM_FACES" '
     body == 0 { if ($0 == "end_header") body = 1; next }
     body && v < nv { v++; if (NF != 7) exit 1
                      for (i = 4; i <= 6; i++) if ($i !~ /^[0-9]+$/ || $i > 255) exit 1
                      next }
     body && f < nf { f++; if (NF != 4 || $1 != 3) exit 1
                      for (i = 2; i <= 4; i++) if ($i !~ /^[0-9]+$/ || $i >= nv) exit 1
                      next }
     { exit 1 }
     END { exit !(v == nv && f == nf) }' field.ply; then
  pass "field.ply: $NUM_VERTICES colored vertices and $NUM_FACES faces, as the model has"
else
  fail "field.ply is not a PLY of the model's mesh" field.ply
fi
awk '/^end_header$/ { body = 1; next } body && NF == 7 { print $7 }' field.ply > ply_quality.txt
if awk 'NR == FNR { d[FNR] = $1; n = FNR; next }
        { q = $1 + 0; e = d[FNR] - q; if (e < 0) e = -e; s = q < 1 ? 1 : q
          if (d[FNR] == "inf" || q < 0 || e > 1e-6 * s) exit 1
          if (FNR == 1 || q < min) min = q; m = FNR }
        END { exit !(m == n && min == 0) }' field.txt ply_quality.txt; then
  pass "field.ply quality: the text field's distances, all finite, the smallest 0"
else
  fail "field.ply quality differs from field.txt" ply_quality.txt field.txt
fi
if [ $FAKE -eq 0 ]; then
  [ "$(grep -cx 0 ply_quality.txt)" -eq 1 ] && pass "field.ply: one vertex at distance 0 (the source)" ||
    fail "field.ply: not exactly one vertex at distance 0" ply_quality.txt
fi

# The field within a radius: 'vertex distance' lines, vertices ascending, every
# distance within the radius; the fake's closed form exactly (sources on faces
# 0 and 1: |v - 0| and |v - 1|).
"$GEODEX" field "${S[@]}" --model "$MODEL" --sources sources.txt --radius 2.5 --out near.txt \
  2> err.txt || fail "field --radius" err.txt
if [ $FAKE -eq 1 ]; then
  [ "$(cat near.txt)" = "$(printf '0 0\n1 0\n2 1\n3 2')" ] &&
    pass "field --radius: the vertices within it, the fake's distances" ||
    fail "field --radius: not the fake's vertices within 2.5" near.txt
else
  awk -v r=2.5 -v nv="$NUM_VERTICES" 'NF != 2 || $1 !~ /^[0-9]+$/ || $1 >= nv || $2 > r ||
       (NR > 1 && $1 <= last) { exit 1 } { last = $1 } END { exit NR == 0 }' near.txt &&
    [ "$(wc -l < near.txt)" -lt "$NUM_VERTICES" ] &&
    pass "field --radius: $(wc -l < near.txt) vertices within it, ascending" ||
    fail "field --radius: lines not 'vertex distance' within 2.5, ascending" near.txt
fi
"$GEODEX" field "${S[@]}" --model "$MODEL" --sources sources.txt --radius -1 > /dev/null 2> err.txt
code=$?
[ $code -eq 2 ] && grep -q "radius must be finite and > 0, got -1" err.txt &&
  pass "field --radius -1: exit 2" || fail "field --radius -1: exit $code" err.txt

# The exponential map: lines as geodex-query prints them offline, the decal
# as a textured OBJ + MTL + PNG, and a rendered picture.
if [ $FAKE -eq 0 ]; then
  "$GEODEX" expmap "${S[@]}" --model "$MODEL" --center "1 0.2 0.3 0.5" --radius 0.4 \
    --direction 0 1 0 --out map.txt 2> err.txt &&
    "$QUERY_BIN" models/cube/1/index.gdx --expmap "1 0.2 0.3 0.5" --radius 0.4 \
      --direction 0 1 0 > map_offline.txt 2>> err.txt &&
    [ "$(wc -l < map.txt)" -gt 10 ] && same_numbers map.txt map_offline.txt &&
    pass "expmap: $(wc -l < map.txt) vertices, as geodex-query --expmap" ||
    fail "expmap differs from geodex-query --expmap" err.txt map.txt map_offline.txt
  if "$GEODEX" expmap "${S[@]}" --model "$MODEL" --center "1 0.2 0.3 0.5" --radius 0.4 \
       --out decal.obj --png decal_view.png 2> err.txt &&
     grep -q '^mtllib decal.mtl$' decal.obj && grep -q '^usemtl ' decal.obj &&
     [ "$(grep -c '^v ' decal.obj)" -eq "$(grep -c '^vt ' decal.obj)" ] &&
     [ "$(grep -c '^f [0-9]*/[0-9]* [0-9]*/[0-9]* [0-9]*/[0-9]*$' decal.obj)" -gt 0 ] &&
     grep -q '^map_Kd decal_checker.png$' decal.mtl &&
     [ "$(head -c 8 decal_checker.png | od -An -tx1 | tr -d ' \n')" = "89504e470d0a1a0a" ] &&
     [ "$(head -c 8 decal_view.png | od -An -tx1 | tr -d ' \n')" = "89504e470d0a1a0a" ]; then
    pass "expmap --out decal.obj: OBJ with texture coordinates, MTL, checkerboard PNG; --png"
  else
    fail "expmap --out decal.obj" err.txt decal.obj decal.mtl
  fi
  mkdir -p decal_dir && printf 'not really a picture' > my_picture.jpg
  if "$GEODEX" expmap "${S[@]}" --model "$MODEL" --center "1 0.2 0.3 0.5" --radius 0.4 \
       --out decal_dir/d.obj --image my_picture.jpg 2> err.txt &&
     grep -q '^map_Kd my_picture.jpg$' decal_dir/d.mtl && cmp -s my_picture.jpg decal_dir/my_picture.jpg; then
    pass "expmap --image: the MTL applies the user's picture, copied beside the OBJ"
  else
    fail "expmap --image" err.txt
  fi
fi

"$GEODEX" matrix "${S[@]}" --model "$MODEL" --sources sources.txt --targets sources.txt > m.txt 2> err.txt &&
  [ "$(wc -l < m.txt)" -eq 2 ] && awk '{ if ($1 + 0 != $1 || NF != 2) exit 1 }' m.txt &&
  pass "matrix 2x2" || fail "matrix" m.txt err.txt

printf '0 0 0\n0.3 0.1 -0.2\n' > points.txt
"$GEODEX" locate "${S[@]}" --model "$MODEL" --points points.txt > located.txt 2> err.txt &&
  [ "$(awk 'NF == 5' located.txt | wc -l)" -eq 2 ] && pass "locate" || fail "locate" located.txt err.txt
printf '0 0 0 0.3 0.1 -0.2\n' > xyz.txt
"$GEODEX" distance "${S[@]}" --model "$MODEL" --pairs xyz.txt --xyz > d_xyz.txt 2> err.txt &&
  [ "$(wc -l < d_xyz.txt)" -eq 1 ] && pass "distance --xyz" || fail "distance --xyz" d_xyz.txt err.txt

GEODEX_SERVER="$ADDR" "$GEODEX" models > /dev/null 2> err.txt && pass "\$GEODEX_SERVER" ||
  fail "GEODEX_SERVER" err.txt

"$GEODEX" bench "${S[@]}" --model "$MODEL" --concurrency 2 --duration 1 --warmup 0.2 --batch 64 \
  > bench.txt 2> err.txt && grep -q "throughput" bench.txt && pass "bench (unary)" ||
  fail "bench" bench.txt err.txt
"$GEODEX" bench "${S[@]}" --model "$MODEL" --concurrency 2 --duration 1 --warmup 0.2 --batch 64 \
  --mode stream > bench_s.txt 2> err.txt && grep -q "throughput" bench_s.txt &&
  pass "bench (stream)" || fail "bench stream" bench_s.txt err.txt

# --- bad input and errors: exit codes and messages ---------------------------------
expect() {  # expect NAME CODE PATTERN CMD...: exit code CODE and PATTERN on stderr
  local name="$1" code="$2" pattern="$3"; shift 3
  "$@" > out.txt 2> err.txt
  local got=$?
  if [ $got -eq "$code" ] && grep -qE -- "$pattern" err.txt; then
    pass "$name (exit $got)"
  else
    echo "      expected exit $code and /$pattern/, got exit $got" >&2
    fail "$name" err.txt out.txt
  fi
}
printf '0 1 0 0 1 0 1 0\n\n0 1 0 0 1 0 1\n' > malformed.txt
expect "malformed pairs line: exit 2 with its line number" 2 "malformed.txt: line 3: expected 8 fields" \
  "$GEODEX" distance "${S[@]}" --model "$MODEL" --pairs malformed.txt
printf '0 1 0 0 1 0 1 0\n0 1 0 0 1 zero 1 0\n' > notnumber.txt
expect "non-number field: exit 2" 2 "line 2: field 6 \('zero'\) is not a finite number" \
  "$GEODEX" distance "${S[@]}" --model "$MODEL" --pairs notnumber.txt
printf '# ok\n0 1 0 0 1 0 1 0\n%d 1 0 0 1 0 1 0\n' "$NUM_FACES" > pastend.txt
expect "face past the end: exit 2 with its line number" 2 "line 3: face $NUM_FACES is past the end" \
  "$GEODEX" distance "${S[@]}" --model "$MODEL" --pairs pastend.txt
printf '0 0.7 0.7 0 1 0 1 0\n' > weights.txt
expect "weights not summing to 1: exit 2" 2 "line 1: .*sum to" \
  "$GEODEX" distance "${S[@]}" --model "$MODEL" --pairs weights.txt
expect "missing pairs file: exit 2" 2 "cannot open" \
  "$GEODEX" distance "${S[@]}" --model "$MODEL" --pairs does-not-exist.txt
expect "unknown model: exit 1 with NOT_FOUND" 1 "NOT_FOUND" \
  "$GEODEX" distance "${S[@]}" --model no-such-model --pairs pairs.txt
expect "unknown model (models info): exit 1" 1 "NOT_FOUND" \
  "$GEODEX" info "${S[@]}" --model no-such-model
expect "unknown model (field --out X.ply): exit 1" 1 "NOT_FOUND" \
  "$GEODEX" field "${S[@]}" --model no-such-model --sources sources.txt --out none.ply
if [ $FAKE -eq 0 ]; then
  expect "expmap with a zero radius: exit 2" 2 "radius" \
    "$GEODEX" expmap "${S[@]}" --model "$MODEL" --center "1 0.2 0.3 0.5" --radius 0
  expect "expmap with a malformed centre: exit 2" 2 "--center wants" \
    "$GEODEX" expmap "${S[@]}" --model "$MODEL" --center "1 0.2 0.3" --radius 0.4
  expect "expmap with a face past the end: exit 2" 2 "OUT_OF_RANGE|out of range|past" \
    "$GEODEX" expmap "${S[@]}" --model "$MODEL" --center "99999 1 0 0" --radius 0.4
  expect "expmap with a zero reference direction: exit 1 (the server's INVALID_ARGUMENT)" 1 \
    "INVALID_ARGUMENT.*zero or perpendicular" \
    "$GEODEX" expmap "${S[@]}" --model "$MODEL" --center "1 0.2 0.3 0.5" --radius 0.4 \
      --direction 0 0 0
fi
expect "field --nearest with a .ply: exit 2" 2 "--nearest is for text output" \
  "$GEODEX" field "${S[@]}" --model "$MODEL" --sources sources.txt --nearest --out nearest.ply
NO_SERVER="127.0.0.1:$(free_port)"
expect "no server: exit 1 with UNAVAILABLE" 1 "UNAVAILABLE" \
  "$GEODEX" models --server "$NO_SERVER" --attempts 2 --timeout 5
expect "unknown flag: exit 2" 2 "" "$GEODEX" distance --model "$MODEL" --pairs pairs.txt --bogus
expect "missing --model: exit 2" 2 "model" "$GEODEX" distance "${S[@]}" --pairs pairs.txt
expect "no subcommand: exit 2" 2 "" "$GEODEX"
"$GEODEX" --help > help.txt 2>&1 && grep -q distance help.txt && pass "--help (exit 0)" ||
  fail "--help" help.txt
"$GEODEX" bench --help > help.txt 2>&1 && grep -q -- "--concurrency" help.txt &&
  grep -q -- "--server" help.txt && pass "bench --help lists its and the connection flags" ||
  fail "bench --help" help.txt
if [ $FAKE -eq 0 ]; then
  # The every-distance mode through both call paths: every batch answered.
  for mode in unary stream; do
    "$GEODEX" bench "${S[@]}" --model "$MODEL" --pairs uniform --mode "$mode" --refine-below 8 \
      --duration 0.5 --warmup 0 --concurrency 1 --batch 64 > bench.txt 2>&1 &&
      grep -q "refined below 8 L1000" bench.txt && grep -Eq "^calls +[1-9][0-9]* ok$" bench.txt &&
      pass "bench --refine-below 8 --mode $mode: every call answered" ||
      fail "bench --refine-below 8 --mode $mode" bench.txt
  done
  # The pairs a bench draws, saved: the service and geodex-query answer them alike.
  "$GEODEX" bench "${S[@]}" --model "$MODEL" --pairs near --save-pairs near_pairs.txt \
    --duration 0.3 --warmup 0 --concurrency 1 --batch 64 > bench.txt 2> err.txt &&
    "$GEODEX" distance "${S[@]}" --model "$MODEL" --pairs near_pairs.txt > d_near.txt 2>> err.txt &&
    "$QUERY_BIN" models/cube/1/index.gdx --pairs near_pairs.txt > d_near_offline.txt 2>> err.txt &&
    [ "$(wc -l < d_near.txt)" -ge 64 ] && same_numbers d_near_offline.txt d_near.txt &&
    pass "bench --save-pairs: $(wc -l < near_pairs.txt) near pairs, answered alike by the service and geodex-query" ||
    fail "bench --save-pairs" err.txt near_pairs.txt d_near.txt d_near_offline.txt
fi

if [ $FAKE -eq 0 ]; then
  stop_server && pass "server stops cleanly on SIGTERM" || fail "server exit status" server.log

  # --- bearer token ---------------------------------------------------------------
  echo "e2e-secret-token" > token.txt
  CLIENT_AUTH=(--token-file token.txt)
  start_server server_token.log --token-file token.txt || exit 1
  CLIENT_AUTH=()
  S=(--server "$ADDR")
  expect "no token: exit 1 with UNAUTHENTICATED" 1 "UNAUTHENTICATED" "$GEODEX" models "${S[@]}"
  "$GEODEX" models "${S[@]}" --token-file token.txt > /dev/null 2> err.txt &&
    pass "--token-file accepted" || fail "--token-file" err.txt server_token.log
  "$GEODEX" distance "${S[@]}" --token e2e-secret-token --model "$MODEL" --pairs many.txt \
    --batch 500 > d_tok.txt 2> err.txt && cmp -s d_many.txt d_tok.txt &&
    pass "--token on a streamed distance call" || fail "--token stream" err.txt
  stop_server

  # --- TLS (a throwaway CA and a server certificate for 127.0.0.1) ------------------
  if command -v openssl > /dev/null; then
    openssl req -x509 -newkey rsa:2048 -nodes -days 1 -subj "/CN=geodex-e2e-ca" \
      -keyout ca.key -out ca.pem > openssl.log 2>&1 &&
    openssl req -newkey rsa:2048 -nodes -subj "/CN=localhost" -keyout server.key \
      -out server.csr >> openssl.log 2>&1 &&
    printf 'subjectAltName=IP:127.0.0.1,DNS:localhost\n' > san.ext &&
    openssl x509 -req -in server.csr -CA ca.pem -CAkey ca.key -CAcreateserial -days 1 \
      -extfile san.ext -out server.pem >> openssl.log 2>&1
    if [ -s server.pem ]; then
      CLIENT_AUTH=(--tls-ca ca.pem)
      start_server server_tls.log --tls-cert server.pem --tls-key server.key || exit 1
      S=(--server "$ADDR")
      "$GEODEX" distance "${S[@]}" --tls-ca ca.pem --model "$MODEL" --pairs pairs.txt \
        > d_tls.txt 2> err.txt && cmp -s d_cli.txt d_tls.txt &&
        pass "TLS with --tls-ca" || fail "TLS" err.txt server_tls.log
      expect "TLS server, plaintext client: exit 1 with UNAVAILABLE" 1 "UNAVAILABLE" \
        "$GEODEX" models "${S[@]}" --attempts 1 --timeout 5
      stop_server
      CLIENT_AUTH=()
    else
      fail "could not make test certificates" openssl.log
    fi
  fi
fi

echo "e2e: $((CHECKS - FAILURES))/$CHECKS checks passed"
[ $FAILURES -eq 0 ]
