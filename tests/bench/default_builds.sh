#!/usr/bin/env bash
# The default build (no flags but the threads) of each shared mesh, as a new
# user runs it: m, rounds, whether the target was met, the index's MiB and
# its largest sections, wall and CPU seconds and peak RSS. One line a mesh,
# tab-separated, after a header. Skips (exit 77) without ../shared/meshes.
#
#   tests/bench/default_builds.sh [BUILD_DIR] [MESH...]
#     BUILD_DIR  a build tree with core/geodex-build (default: build)
#     MESH       names under ../shared/meshes (default: every mesh but the cow)
#   GEODEX_BENCH_THREADS  builder threads (default 2)
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
build="${1:-$repo/build}"
shift || true
meshes_dir="$repo/../shared/meshes"
if [[ ! -d "$meshes_dir" ]]; then
  echo "default_builds: $meshes_dir is absent; skipped" >&2
  exit 77
fi
threads="${GEODEX_BENCH_THREADS:-2}"
if [[ $# -gt 0 ]]; then
  meshes=("$@")
else
  meshes=()
  for f in "$meshes_dir"/*.obj; do
    name="$(basename "$f" .obj)"
    [[ "$name" == cow_nonmanifold_3k ]] && continue
    meshes+=("$name")
  done
fi
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

printf 'mesh\tm\trounds\treached\tMiB\tmatrix MiB\twall s\tCPU s\tpeak RSS MiB\tfar p99 (vertex / interior)\tuniform RMS\n'
for name in "${meshes[@]}"; do
  out="$work/$name.gdx"
  log="$work/$name.log"
  if ! /usr/bin/time -f '%e %U %S %M' -o "$work/time" \
      "$build/core/geodex-build" "$meshes_dir/$name.obj" -o "$out" --threads "$threads" \
      > "$log" 2>&1; then
    printf '%s\tfailed: %s\n' "$name" "$(tail -1 "$log")"
    continue
  fi
  read -r wall user sys rss < "$work/time"
  report="$log"
  m=$(grep -m1 -oP '^\s*samples\s+\K[0-9]+' "$report" || grep -oP 'm = \K[0-9]+' "$report" | tail -1)
  rounds=$(grep -oP '^target_error_rounds = \K[0-9]+' "$report" || echo 1)
  reached=$(grep -oP '^target_error_reached = \K\S+' "$report" || echo '-')
  bytes=$(stat -c %s "$out")
  matrix=$(grep -m1 -oP 'distance matrix\s+\K[0-9.]+' "$report" || echo '-')
  far=$(grep -oP '^target_error_round_[0-9]+ = .*' "$report" | tail -1 |
        grep -oP 'vertex >=8 L1000 p99 \K[0-9.]+%|interior >=8 L1000 p99 \K[0-9.]+%' | paste -sd/ -)
  rms=$(grep -oP '^target_error_round_[0-9]+ = .*' "$report" | tail -1 |
        grep -oP 'uniform RMS \K[0-9.]+%' || echo '-')
  printf '%s\t%s\t%s\t%s\t%.2f\t%s\t%.0f\t%.0f\t%.0f\t%s\t%s\n' "$name" "$m" "$rounds" "$reached" \
    "$(echo "$bytes / 1048576" | bc -l)" "$matrix" "$wall" "$(echo "$user + $sys" | bc -l)" \
    "$(echo "$rss / 1024" | bc -l)" "$far" "$rms"
done
