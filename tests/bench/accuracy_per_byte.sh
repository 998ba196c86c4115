#!/usr/bin/env bash
# Accuracy per byte and per build-second: for each mesh, indexes of several
# sizes (geodex-build --samples M, and optionally the default build's index)
# measured by the accuracy harness on held-out pairs (its own sources and
# seed, not the build's), in the fixed L1000 bins of the default target.
# One Markdown row per index: m, index MiB, build wall and CPU seconds, the
# area-uniform relative RMS and the p99 of each fixed bin (vertex / interior),
# and the bytes of an exact float32 table of the mesh's vertex pairs (its
# lower triangle) for comparison. Skips (exit 77) without ../shared/meshes.
#
#   tests/bench/accuracy_per_byte.sh [BUILD_DIR] MESH... [-- M...]
#     BUILD_DIR  a build tree with core/geodex-build and tests/geodex-accuracy
#                (default: build)
#     MESH       names under ../shared/meshes
#     M          sample counts (default: 250 500 1000 2000 4000)
#   GEODEX_BENCH_THREADS   builder and harness threads (default 2)
#   GEODEX_BENCH_DEFAULTS  a folder of default builds (<mesh>.gdx, as
#                          tests/bench/default_builds.sh keeps them, with its
#                          table as table.tsv): adds a row for each, its wall
#                          and CPU seconds from the table
#   GEODEX_BENCH_SOURCES   the harness's exact propagations (default 40)
#   GEODEX_BENCH_VERTICES  1: also the index whose samples are the mesh's
#                          vertices, unsplit (--no-split --samples <vertex
#                          count>): the same unfolding over an exact table of
#                          the vertices
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
build="$repo/build"
if [[ $# -gt 0 && -d "$1/core" ]]; then build="$1"; shift; fi
meshes=() counts=()
while [[ $# -gt 0 && "$1" != "--" ]]; do meshes+=("$1"); shift; done
if [[ $# -gt 0 ]]; then shift; counts=("$@"); fi
[[ ${#counts[@]} -gt 0 ]] || counts=(250 500 1000 2000 4000)
meshes_dir="$repo/../shared/meshes"
if [[ ! -d "$meshes_dir" ]]; then
  echo "accuracy_per_byte: $meshes_dir is absent; skipped" >&2
  exit 77
fi
if [[ ${#meshes[@]} -eq 0 ]]; then
  echo "accuracy_per_byte: name at least one mesh" >&2
  exit 2
fi
threads="${GEODEX_BENCH_THREADS:-2}"
sources="${GEODEX_BENCH_SOURCES:-40}"
defaults="${GEODEX_BENCH_DEFAULTS:-}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

# The p99 columns are in %, vertex / interior, by bin of L1000.
printf '| mesh | index | m | MiB | wall / CPU s | uniform RMS |'
for bin in "0-0.5" "0.5-1" "1-2" "2-4" "4-8" "8-16" ">=16"; do printf ' p99 %s |' "$bin"; done
printf ' float32 vertex table MiB |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n'

# row NAME LABEL INDEX WALL CPU: measures INDEX and prints its row.
row() {
  local name="$1" label="$2" index="$3" wall="$4" cpu="$5"
  "$build/tests/geodex-accuracy" "$meshes_dir/$name.obj" --index "$index" --modes default \
    --target-error 0.005 --sources "$sources" --seed 7 --threads "$threads" \
    > "$work/acc.md" 2> "$work/acc.err" || { echo "| $name | $label | failed: $(tail -1 "$work/acc.err") |"; return; }
  "$build/core/geodex-query" "$index" --info --format json > "$work/info.json"
  python3 - "$name" "$label" "$work/acc.md" "$work/info.json" "$wall" "$cpu" <<'PY'
import json, re, sys
name, label, md, info, wall, cpu = sys.argv[1:]
r = json.load(open(info))
bins = ["0-0.5", "0.5-1", "1-2", "2-4", "4-8", "8-16", ">=16"]
p99 = {}
rms = "-"
for line in open(md):
    cells = [c.strip() for c in line.strip().strip("|").split("|")]
    if len(cells) < 6:
        continue
    if cells[1] == "uniform" and cells[2] == "all":
        rms = cells[4]
    m = re.fullmatch(r"(.*) L1000", cells[2])
    if m and cells[1] in ("vertex", "interior"):
        p99[(cells[1], m.group(1))] = cells[5].rstrip("%")
cols = ["%s / %s" % (p99.get(("vertex", b), "-"), p99.get(("interior", b), "-")) for b in bins]
n = r["mesh"]["vertices"]
table = n * (n - 1) / 2 * 4 / 1048576
print("| %s | %s | %d | %.2f | %s / %s | %s | %s | %.1f |" % (
    name, label, r["samples"]["final"], r["size"]["bytes"] / 1048576, wall, cpu, rms,
    " | ".join(cols), table))
PY
}

# built NAME LABEL ARGS...: builds with geodex-build ARGS, then its row.
built() {
  local name="$1" label="$2"; shift 2
  local out="$work/$name.gdx" wall cpu
  if ! /usr/bin/time -f '%e %U %S' -o "$work/time" "$build/core/geodex-build" \
      "$meshes_dir/$name.obj" -o "$out" --threads "$threads" "$@" > "$work/build.log" 2>&1; then
    echo "| $name | $label | failed: $(tail -1 "$work/build.log") |"
    return
  fi
  read -r wall cpu < <(awk '{printf "%.0f %.0f\n", $1, $2 + $3}' "$work/time")
  row "$name" "$label" "$out" "$wall" "$cpu"
  rm -f "$out"
}

for name in "${meshes[@]}"; do
  for m in "${counts[@]}"; do built "$name" "--samples $m" --samples "$m"; done
  if [[ "${GEODEX_BENCH_VERTICES:-0}" == 1 ]]; then
    n="$(awk '$1 == "v" {n++} END {print n}' "$meshes_dir/$name.obj")"
    built "$name" "every vertex, unsplit" --no-split --samples "$n"
  fi
  if [[ -n "$defaults" && -f "$defaults/$name.gdx" ]]; then
    wall=- cpu=-
    if [[ -f "$defaults/table.tsv" ]]; then
      read -r wall cpu < <(awk -F'\t' -v n="$name" '$1 == n {print $8, $9}' "$defaults/table.tsv")
    fi
    row "$name" "default" "$defaults/$name.gdx" "${wall:--}" "${cpu:--}"
  fi
done
