#!/usr/bin/env bash
# End-to-end checks of the offline tools: geodex-build (one process and the
# plan/rows/merge pipeline, byte-identical), geodex-query and geodex-geodesic
# (answers, exit codes and line-numbered errors).
#   core_tools_test.sh BUILD_DIR
set -uo pipefail
build="$1"
tools="$build/core"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
failures=0
passes=0
check() {  # check NAME CONDITION...
  local name="$1"; shift
  if "$@"; then
    echo "ok   $name"; passes=$((passes + 1))
  else
    echo "FAIL $name"; failures=$((failures + 1))
  fi
}
# exits WANT NAME: the command just run exited with status WANT. Every
# command of this script is followed by one, so that a tool that fails (or
# succeeds where it must not) is caught even when its output looks right.
exits() {
  local got=$? want="$1"; shift
  check "$* exits $want$([ "$got" -eq "$want" ] || echo ", not $got")" test "$got" -eq "$want"
}
# within TOL EXACT APPROX N: both files hold N lines, every first field is a
# number, and each approximate value is within TOL (relative) of the exact
# one. Empty or short output fails.
within() {
  awk -v tol="$1" -v n="$4" '
    NR == FNR { e[FNR] = $1; ne = FNR; next }
    { na = FNR
      if ($1 !~ /^[-+]?[0-9.]+([eE][-+]?[0-9]+)?$/ || e[FNR] !~ /^[-+]?[0-9.]+([eE][-+]?[0-9]+)?$/) bad = 1
      d = $1 - e[FNR]; if (d < 0) d = -d
      if (e[FNR] > 0 && d / e[FNR] > tol) bad = 1 }
    END { exit !(ne == n && na == n && !bad) }' "$2" "$3"
}

# geodex-build: one process, and the sharded pipeline.
"$tools/geodex-build" builtin:sphere -o "$work/one.gdx" --samples 100 --threads 2 >"$work/build.out" 2>&1
exits 0 "geodex-build"
check "build prints its report" sh -c "grep -q '^  samples       m = [0-9]*: 100 requested' '$work/build.out' && grep -q '^  time  ' '$work/build.out'"
"$tools/geodex-build" plan builtin:sphere --samples 100 -o "$work/wd" >/dev/null 2>&1
exits 0 "geodex-build plan"
for i in 0 1 2; do
  "$tools/geodex-build" rows "$work/wd" --shard "$i/3" --threads 1 >/dev/null 2>&1
  exits 0 "geodex-build rows --shard $i/3"
done
"$tools/geodex-build" merge "$work/wd" -o "$work/sharded.gdx" >/dev/null 2>&1
exits 0 "geodex-build merge"
check "sharded build is byte-identical" cmp -s "$work/one.gdx" "$work/sharded.gdx"
"$tools/geodex-build" "$work/missing.obj" -o "$work/x.gdx" --samples 10 >/dev/null 2>"$work/err"
exits 2 "a missing mesh"
check "missing mesh names the file" grep -q "missing.obj" "$work/err"
"$tools/geodex-build" rows "$work/wd" --shard 3/3 >/dev/null 2>"$work/err"
exits 2 "a bad shard"

# A mesh file for geodex-geodesic: write the same sphere through the plan's copy.
mesh="$work/wd/mesh.ply"
printf '0 1 0 0 5 0 1 0\n# comment\n3 0.2 0.3 0.5 100 0.3 0.3 0.4\n0 1 0 0 0 1 0 0\n' >"$work/pairs.txt"
"$tools/geodex-geodesic" "$mesh" --pairs "$work/pairs.txt" >"$work/exact.txt" 2>&1
exits 0 "geodex-geodesic --pairs"
check "geodex-geodesic prints one line per pair" test "$(wc -l <"$work/exact.txt")" -eq 3
check "distance to itself is 0" test "$(sed -n 3p "$work/exact.txt")" = "0"
"$tools/geodex-query" "$work/one.gdx" --pairs "$work/pairs.txt" >"$work/approx.txt" 2>&1
exits 0 "geodex-query --pairs"
check "geodex-query agrees within 5%" within 0.05 "$work/exact.txt" "$work/approx.txt" 3

# Error bounds and tolerance (the index carries its calibration by default).
"$tools/geodex-query" "$work/one.gdx" --pairs "$work/pairs.txt" --error-bounds --tolerance 0.005 \
  >"$work/bounded.txt" 2>&1
exits 0 "geodex-query --error-bounds --tolerance"
check "geodex-query --error-bounds prints distance and bound" \
  awk 'NF != 2 || $2 < 0 || $2 > 0.005 * $1 + 1e-12 { bad = 1 } END { exit bad || NR != 3 }' "$work/bounded.txt"
check "geodex-query --tolerance 0.005 is within 0.5% of exact" within 0.005 "$work/exact.txt" "$work/bounded.txt" 3
"$tools/geodex-query" "$work/one.gdx" --info >"$work/info.txt" 2>&1
exits 0 "geodex-query --info"
check "geodex-query --info shows the accuracy table" grep -q "^                  8-16  *[0-9.<]*%  *[0-9.<]*%  judged" "$work/info.txt"
"$tools/geodex-query" "$work/one.gdx" --info --format json >"$work/info.json" 2>&1
exits 0 "geodex-query --info --format json"
# The text and the JSON show the same figures: each L1000 band's p99s,
# formatted as the text formats them, are in the text's row of that band,
# and each judged check's measured figure, 95% upper limit and limit in its
# line; the bins by the index's own L have no row of their own.
check "geodex-query --info text and JSON agree" python3 -c '
import json, sys
r = json.load(open(sys.argv[1])); text = open(sys.argv[2]).read()
def pct(x):
    if x is None: return "n/a"
    v = 100 * x
    if v == 0: return "0%"
    if v < 0.001: return "<0.001%"
    d = 0 if v >= 100 else 1 if v >= 10 else 2 if v >= 1 else 3 if v >= 0.1 else 4 if v >= 0.01 else 5
    return "%.*f%%" % (d, v)
for b in r["accuracy"]["bands"]:
    row = [l for l in text.splitlines() if l.startswith(" " * 18 + b["label"] + " ")]
    assert len(row) == 1, b["label"]
    cells = row[0][18 + len(b["label"]):].split()
    judged = "-" if b["p99_limit"] is None else "judged"
    assert cells[:3] == [pct(b["p99_vertex"]), pct(b["p99_interior"]), judged], (b, cells)
for c in r["target"]["checks"]:
    line = "%s (%s / %s)" % (pct(c["measured"]), pct(c["upper95"]), pct(c["limit"]))
    if c["pairs"] == 0: line = "no pairs (not judged)"
    assert any(l.startswith(" " * 18 + c["label"]) and line in l for l in text.splitlines()), c
assert not any(l.startswith(" " * 18 + "3L-10L") for l in text.splitlines())
assert "m = %d:" % r["samples"]["final"] in text
' "$work/info.json" "$work/info.txt"
"$tools/geodex-build" builtin:sphere -o "$work/charted.gdx" --samples 100 --threads 2 \
  --report-png "$work/chart.png" >/dev/null 2>&1
exits 0 "geodex-build --report-png"
check "--report-png writes a PNG" sh -c "head -c 8 '$work/chart.png' | od -An -c | grep -q 'P   N   G'"
"$tools/geodex-build" builtin:sphere -o "$work/plain.gdx" --samples 100 --threads 2 --no-calibration >/dev/null 2>&1
exits 0 "geodex-build --no-calibration"
"$tools/geodex-query" "$work/plain.gdx" --pairs "$work/pairs.txt" --error-bounds >/dev/null 2>"$work/err"
exits 1 "bounds without calibration"
check "bounds without calibration name the remedy" grep -q "geodex-build calibrate" "$work/err"
"$tools/geodex-build" calibrate builtin:sphere "$work/plain.gdx" -o "$work/calibrated.gdx" >/dev/null 2>&1
exits 0 "geodex-build calibrate"
check "geodex-build calibrate gives the index a one-process build gives" cmp -s "$work/one.gdx" "$work/calibrated.gdx"

# --source-vertex: every vertex's distance from one vertex. On a flat 9x9
# grid (an OBJ written here, with an unreferenced vertex last) the exact
# distance is the Euclidean one.
awk 'BEGIN { n = 9
  for (j = 0; j < n; j++) for (i = 0; i < n; i++) printf "v %d %d 0\n", i, j
  printf "v 50 50 50\n"
  for (j = 0; j < n - 1; j++) for (i = 0; i < n - 1; i++) {
    a = j * n + i + 1; b = a + 1; c = a + n; d = c + 1
    printf "f %d %d %d\nf %d %d %d\n", a, b, d, a, d, c } }' >"$work/grid.obj"
"$tools/geodex-geodesic" "$work/grid.obj" --source-vertex 40 --out "$work/from40.txt" 2>"$work/err"
exits 0 "geodex-geodesic --source-vertex"
check "one line per vertex, in file order" test "$(wc -l <"$work/from40.txt")" -eq 82
check "flat grid: Euclidean to 1e-12, unreferenced vertex inf" awk '
  NR <= 81 { i = (NR - 1) % 9; j = int((NR - 1) / 9); e = sqrt((i - 4)^2 + (j - 4)^2)
             d = $1 - e; if (d < 0) d = -d; if ($1 == "" || d > 1e-12) bad = 1 }
  NR == 82 && $1 != "inf" { bad = 1 }
  END { exit bad || NR != 82 }' "$work/from40.txt"
# The long-edge split: 60 samples on the 9x9 grid (edges 1 and 1.41, longer
# than half the sample spacing) split its edges flat; the index answers in
# the grid's own faces and vertices, the sharded pipeline and `calibrate`
# give the same bytes, and the answers are the flat (Euclidean) distances.
"$tools/geodex-build" "$work/grid.obj" -o "$work/grid.gdx" --samples 60 --threads 2 \
  >"$work/grid_build.out" 2>&1
exits 0 "geodex-build of the grid (refined)"
check "refined build reports the midpoints" grep -q "split         [0-9]* midpoints" "$work/grid_build.out"
"$tools/geodex-build" plan "$work/grid.obj" --samples 60 -o "$work/gwd" >/dev/null 2>&1
exits 0 "geodex-build plan of the grid"
for i in 0 1; do
  "$tools/geodex-build" rows "$work/gwd" --shard "$i/2" --threads 1 >/dev/null 2>&1
  exits 0 "geodex-build rows of the grid --shard $i/2"
done
"$tools/geodex-build" merge "$work/gwd" -o "$work/grid_sharded.gdx" >/dev/null 2>&1
exits 0 "geodex-build merge of the grid"
check "refined sharded build is byte-identical" cmp -s "$work/grid.gdx" "$work/grid_sharded.gdx"
"$tools/geodex-build" "$work/grid.obj" -o "$work/grid_plain.gdx" --samples 60 --threads 2 \
  --no-calibration >/dev/null 2>&1
exits 0 "geodex-build of the grid --no-calibration"
"$tools/geodex-build" calibrate "$work/grid.obj" "$work/grid_plain.gdx" -o "$work/grid_cal.gdx" \
  >/dev/null 2>&1
exits 0 "geodex-build calibrate of the grid"
check "refined: calibrate gives the one-process index" cmp -s "$work/grid.gdx" "$work/grid_cal.gdx"
"$tools/geodex-build" "$work/grid.obj" -o "$work/grid_noref.gdx" --samples 60 --no-split \
  >"$work/grid_noref.out" 2>&1
exits 0 "geodex-build --no-split"
check "--no-split adds no midpoint" grep -q "split         none" "$work/grid_noref.out"
"$tools/geodex-query" "$work/grid.gdx" --info >"$work/grid_info.txt" 2>&1
exits 0 "geodex-query --info of the grid"
check "--info counts the grid's faces and shows the split" \
  sh -c "grep -q '^  mesh          [0-9]* vertices, 128 faces (answered on' '$work/grid_info.txt' && grep -q '^  split         [1-9][0-9]* midpoints' '$work/grid_info.txt'"
printf '0 1 0 0 127 0 0 1
5 0.2 0.3 0.5 100 0.3 0.3 0.4
17 0.5 0.5 0 90 0.1 0.1 0.8
' >"$work/grid_pairs.txt"
"$tools/geodex-geodesic" "$work/grid.obj" --pairs "$work/grid_pairs.txt" >"$work/grid_exact.txt" 2>&1
exits 0 "geodex-geodesic --pairs on the grid"
"$tools/geodex-query" "$work/grid.gdx" --pairs "$work/grid_pairs.txt" >"$work/grid_approx.txt" 2>&1
exits 0 "geodex-query --pairs on the refined grid"
check "refined index: input faces, flat distances within 1%" within 0.01 "$work/grid_exact.txt" "$work/grid_approx.txt" 3
printf '128 1 0 0 0 1 0 0
' >"$work/grid_range.txt"
"$tools/geodex-query" "$work/grid.gdx" --pairs "$work/grid_range.txt" >/dev/null 2>"$work/err"
exits 2 "refined index: face 128, past the grid's faces,"
printf '0 1 0 0
' >"$work/grid_source.txt"
"$tools/geodex-query" "$work/grid.gdx" --field "$work/grid_source.txt" >"$work/grid_field.txt" 2>&1
exits 0 "geodex-query --field on the refined grid"
check "refined index: a field line per grid vertex" test "$(wc -l <"$work/grid_field.txt")" -eq 82

"$tools/geodex-geodesic" "$mesh" --source-vertex 7 >"$work/from7.txt" 2>"$work/err"
exits 0 "geodex-geodesic --source-vertex to standard output"
check "--source-vertex to standard output" test "$(sed -n 8p "$work/from7.txt")" = "0"
"$tools/geodex-geodesic" "$mesh" --source-vertex 100000 >/dev/null 2>"$work/err"
exits 2 "a vertex past the end"
check "a vertex past the end is named" grep -q "not a vertex" "$work/err"

printf '0 1 0 0 5 0 1 0\n0 1 0 0 5 0 1\n' >"$work/bad.txt"
"$tools/geodex-geodesic" "$mesh" --pairs "$work/bad.txt" >"$work/out" 2>"$work/err"
exits 2 "a bad line"
check "bad line is named" grep -q "line 2" "$work/err"
check "nothing printed on a bad batch" test ! -s "$work/out"
printf '0 1 0 0 99999 0 1 0\n' >"$work/range.txt"
"$tools/geodex-query" "$work/one.gdx" --pairs "$work/range.txt" >"$work/out" 2>"$work/err"
exits 2 "a face out of range"
check "face out of range is named" grep -q "line 1.*out of range" "$work/err"
printf '0 0.5 0.5 0.5 1 1 0 0\n' >"$work/sum.txt"
"$tools/geodex-query" "$work/one.gdx" --pairs "$work/sum.txt" >/dev/null 2>"$work/err"
exits 2 "weights not summing to 1"
check "weights not summing to 1 rejected" grep -q "sum" "$work/err"
head -c 1000 "$work/one.gdx" >"$work/truncated.gdx"
"$tools/geodex-query" "$work/truncated.gdx" --pairs "$work/pairs.txt" >/dev/null 2>"$work/err"
exits 1 "a truncated index"
check "truncated index rejected" grep -qi "truncated" "$work/err"

# Paths, fields and locate.
printf '0 1 0 0 100 0.3 0.3 0.4\n' >"$work/one_pair.txt"
"$tools/geodex-query" "$work/one.gdx" --paths "$work/one_pair.txt" --format json >"$work/path.json" 2>&1
exits 0 "geodex-query --paths"
check "path as JSON" grep -q '"xyz"' "$work/path.json"
printf '0 1 0 0\n' >"$work/sources.txt"
"$tools/geodex-query" "$work/one.gdx" --field "$work/sources.txt" --nearest >"$work/field.txt" 2>&1
exits 0 "geodex-query --field"
check "field has a line per vertex" test "$(wc -l <"$work/field.txt")" -gt 1000
printf '2 0 0\n0 0 0.5\n' >"$work/points.txt"
"$tools/geodex-query" "$work/one.gdx" --locate "$work/points.txt" >"$work/located.txt" 2>&1
exits 0 "geodex-query --locate"
check "locate answers each point" test "$(wc -l <"$work/located.txt")" -eq 2

echo "$passes passed, $failures failed"
[ "$failures" -eq 0 ]
