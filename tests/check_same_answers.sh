#!/usr/bin/env bash
# Checks that two builds of geodex give the same answers to the bit: index
# files byte for byte, and every kind of query geodex-query answers
# (distances in each near-pair mode, bounds, tolerance, paths, fields,
# location, exponential maps, --info). Used to show that a restructuring of
# the code changed no answer.
#
#   tests/check_same_answers.sh BEFORE_BIN_DIR AFTER_BIN_DIR [--samples M]
#
# Each BIN_DIR holds geodex-build and geodex-query (e.g. build/core of two
# checkouts, or a copy of one). Meshes: the generated torus, sphere and
# double torus, and, when ../shared/meshes is present, cow_nonmanifold_3k
# (repaired: exercises the input ids) and max_planck_5k. Exit 0 when every
# output is identical, 1 otherwise (naming the first difference). Where two
# outputs differ, the largest difference between numbers in the same place
# is printed (absolute and relative to the larger of the two), and the
# largest over all outputs at the end: what a change of rounding moved.
set -euo pipefail

if [ "$#" -lt 2 ]; then sed -n '2,13p' "$0" | sed 's/^# \{0,1\}//'; exit 2; fi
before=$(cd "$1" && pwd)
after=$(cd "$2" && pwd)
shift 2
samples=150
while [ "$#" -gt 0 ]; do
  case "$1" in
    --samples) samples="$2"; shift 2 ;;
    *) echo "check_same_answers: unknown argument $1" >&2; exit 2 ;;
  esac
done
for b in "$before" "$after"; do
  for t in geodex-build geodex-query; do
    [ -x "$b/$t" ] || { echo "check_same_answers: no $b/$t" >&2; exit 2; }
  done
done

root=$(cd "$(dirname "$0")/.." && pwd)
shared="$root/../shared/meshes"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

meshes=(builtin:torus builtin:sphere builtin:double-torus)
if [ -d "$shared" ]; then
  meshes+=("$shared/cow_nonmanifold_3k.obj" "$shared/max_planck_5k.obj")
else
  echo "check_same_answers: $shared absent: generated meshes only"
fi

failures=0
largest_rel=0
largest_where="none"
# largest_difference A B -> "ABS REL LINE", the largest relative difference
# between numbers at the same place (line, word) of A and B; words that are
# not both numbers count when they differ, as an infinite difference.
largest_difference() {
  awk 'function num(s) { return s ~ /^[-+]?([0-9]+\.?[0-9]*|\.[0-9]+)([eE][-+]?[0-9]+)?[,\]})]*$/ }
    function strip(s) { sub(/[,\]})]+$/, "", s); return s }
    NR == FNR { before[FNR] = $0; next }
    {
      n = split(before[FNR], a, /[ \t:\[]+/); m = split($0, b, /[ \t:\[]+/)
      if (n != m) { if (worst_rel < 1e300) { worst_abs = "inf"; worst_rel = 1e300; at = FNR }; next }
      for (i = 1; i <= n; ++i) {
        if (a[i] == b[i]) continue
        if (num(a[i]) && num(b[i])) {
          x = strip(a[i]) + 0; y = strip(b[i]) + 0; d = x - y; if (d < 0) d = -d
          s = (x < 0 ? -x : x); t = (y < 0 ? -y : y); s = (s > t ? s : t)
          r = s > 0 ? d / s : 0
          if (r > worst_rel) { worst_rel = r; worst_abs = d; at = FNR }
        } else if (worst_rel < 1e300) { worst_abs = "inf"; worst_rel = 1e300; at = FNR }
      }
    }
    END { if (FNR != length(before) && worst_rel < 1e300) { worst_abs = "inf"; worst_rel = 1e300 }
          printf "%s %g %d\n", worst_abs == "" ? 0 : worst_abs, worst_rel, at }' "$1" "$2"
}
# path_lengths FILE -> the length of each path of a geodex-query --paths
# output, one a line: JSON (a path a line, its points' "xyz") or text
# (points "x y z", paths apart by blank lines). Two paths of equal length
# may cross an edge at another point where a crossing is degenerate; their
# lengths are what a rounding change must leave alone.
path_lengths() {
  awk 'function point(x, y, z) {
         if (have) len += sqrt((x - px) ^ 2 + (y - py) ^ 2 + (z - pz) ^ 2)
         px = x; py = y; pz = z; have = 1
       }
       function flush() { if (have) printf "%.17g\n", len; len = 0; have = 0 }
       /"xyz"/ {
         rest = $0
         while (match(rest, /"xyz": \[[^]]*\]/)) {
           split(substr(rest, RSTART + 8, RLENGTH - 9), c, /, */)
           point(c[1], c[2], c[3])
           rest = substr(rest, RSTART + RLENGTH)
         }
         flush(); next
       }
       NF == 3 && $1 ~ /^[-+.0-9]/ { point($1, $2, $3); next }
       { flush() }
       END { flush() }' "$1"
}
compare() {  # compare NAME: $work/before.NAME vs $work/after.NAME
  if cmp -s "$work/before.$1" "$work/after.$1"; then
    echo "  same   $1 ($(wc -c <"$work/after.$1") bytes)"
  else
    case "$1" in
      *.paths | *.corridor)
        path_lengths "$work/before.$1" >"$work/before.$1.lengths"
        path_lengths "$work/after.$1" >"$work/after.$1.lengths"
        read -r abs rel line < <(largest_difference "$work/before.$1.lengths" "$work/after.$1.lengths")
        line="path $line" ;;
      *) read -r abs rel line < <(largest_difference "$work/before.$1" "$work/after.$1") ;;
    esac
    echo "  DIFFER $1: largest difference $abs (relative $rel, line $line)"
    diff <(head -c 2000 "$work/before.$1") <(head -c 2000 "$work/after.$1") | head -5 || true
    if awk -v r="$rel" -v w="$largest_rel" 'BEGIN { exit !(r > w) }'; then
      largest_rel=$rel
      largest_where="$1 (absolute $abs, line $line)"
    fi
    failures=$((failures + 1))
  fi
}

# Deterministic random points of a mesh with `faces` faces: a vertex point
# (weight 1 on one corner) every fifth point, interior points otherwise.
points() {  # points FACES COUNT SEED -> lines "f w0 w1 w2"
  awk -v faces="$1" -v n="$2" -v seed="$3" 'BEGIN {
    srand(seed)
    for (i = 0; i < n; ++i) {
      f = int(rand() * faces)
      if (i % 5 == 0) { k = int(rand() * 3); w[0] = w[1] = w[2] = 0; w[k] = 1 }
      else { a = rand(); b = rand(); if (a + b > 1) { a = 1 - a; b = 1 - b }
             w[0] = a; w[1] = b; w[2] = 1 - a - b }
      printf "%d %.17g %.17g %.17g\n", f, w[0], w[1], w[2]
    }
  }'
}

for mesh in "${meshes[@]}"; do
  name=$(basename "$mesh" .obj)
  name=${name#builtin:}
  echo "$name:"
  for side in before after; do
    bin=$before; [ "$side" = after ] && bin=$after
    "$bin/geodex-build" "$mesh" -o "$work/$side.$name.gdx" --samples "$samples" --threads 2 \
      >"$work/$side.$name.build.log" 2>&1
  done
  compare "$name.gdx"
  # Query the same index file (the one built before) with both query tools,
  # so that a difference in the answers is the query code's.
  index="$work/before.$name.gdx"
  # --format json: the build report's JSON; a geodex-query older than it
  # prints "faces = N" lines there instead.
  faces=$("$before/geodex-query" "$index" --info --format json |
    sed -n 's/^faces = \([0-9]*\)$/\1/p; s/^    "faces": \([0-9]*\),$/\1/p')
  [ -n "$faces" ] || { echo "check_same_answers: no face count for $name" >&2; exit 1; }
  paste -d' ' <(points "$faces" 600 11) <(points "$faces" 600 12) >"$work/pairs"
  # Near pairs too: the second point in the first point's face.
  paste -d' ' <(points "$faces" 200 13) <(points "$faces" 200 14 | awk '{ $1 = "" } 1') |
    awk '{ print $1, $2, $3, $4, $1, $5, $6, $7 }' >>"$work/pairs"
  head -40 "$work/pairs" >"$work/path_pairs"
  points "$faces" 3 15 >"$work/sources"
  awk -v seed=16 'BEGIN { srand(seed); for (i = 0; i < 50; ++i)
    printf "%.17g %.17g %.17g\n", 6 * rand() - 3, 6 * rand() - 3, 2 * rand() - 1 }' >"$work/xyz"
  centre=$(points "$faces" 1 17)
  # A radius of about a sixth of a typical distance on this mesh.
  radius=$("$before/geodex-query" "$index" --pairs "$work/pairs" --near-pairs unfold |
    sort -g | awk 'NR == 300 { print $1 / 6 }')
  for side in before after; do
    q="$before/geodex-query"; [ "$side" = after ] && q="$after/geodex-query"
    o="$work/$side.$name"
    "$q" "$index" --info >"$o.info"
    "$q" "$index" --pairs "$work/pairs" --error-bounds >"$o.default"
    "$q" "$index" --pairs "$work/pairs" --near-pairs unfold --error-bounds >"$o.unfold"
    "$q" "$index" --pairs "$work/pairs" --near-pairs exact >"$o.exact"
    "$q" "$index" --pairs "$work/pairs" --tolerance 0.005 --error-bounds >"$o.tolerance"
    "$q" "$index" --pairs "$work/pairs" --linear-baseline >"$o.linear"
    "$q" "$index" --paths "$work/path_pairs" --format json >"$o.paths"
    "$q" "$index" --paths "$work/path_pairs" --exact-path-corridor 2 >"$o.corridor"
    "$q" "$index" --field "$work/sources" --nearest >"$o.field"
    "$q" "$index" --locate "$work/xyz" >"$o.locate"
    "$q" "$index" --expmap "$centre" --radius "$radius" >"$o.expmap"
  done
  for kind in info default unfold exact tolerance linear paths corridor field locate expmap; do
    compare "$name.$kind"
  done
done

if [ "$failures" -gt 0 ]; then
  echo "check_same_answers: $failures outputs differ; the largest relative difference: $largest_rel in $largest_where"
  exit 1
fi
echo "check_same_answers: every output identical"
