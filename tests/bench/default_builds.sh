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
#   GEODEX_BENCH_KEEP     a folder to keep the indexes in (<mesh>.gdx, with
#                         the build's log beside it), for the accuracy
#                         harness (geodex-accuracy MESH --index FILE)
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
keep="${GEODEX_BENCH_KEEP:-}"
[[ -n "$keep" ]] && mkdir -p "$keep"

printf 'mesh\tvertices\tm\trounds (m)\tmet\tMiB\tMiB by section\twall s\tCPU s\tpeak RSS MiB\tuniform RMS\tp99 >=8 L1000 (vertex / interior)\n'
for name in "${meshes[@]}"; do
  out="$work/$name.gdx"
  log="$work/$name.log"
  if ! /usr/bin/time -f '%e %U %S %M' -o "$work/time" \
      "$build/core/geodex-build" "$meshes_dir/$name.obj" -o "$out" --threads "$threads" \
      > "$log" 2>&1; then
    printf '%s\tfailed: %s\n' "$name" "$(tail -1 "$log")"
    continue
  fi
  if ! "$build/core/geodex-query" "$out" --info --format json > "$work/$name.json" 2>> "$log"; then
    printf '%s\tno report: %s\n' "$name" "$(tail -1 "$log")"
    continue
  fi
  read -r wall user sys rss < "$work/time"
  [[ -n "$keep" ]] && cp "$out" "$log" "$keep/"
  python3 - "$name" "$work/$name.json" "$wall" "$user" "$sys" "$rss" <<'PY'
import json, sys
name, path, wall, user, sys_s, rss = sys.argv[1:]
r = json.load(open(path))
mib = lambda b: b / 1048576
sections = ", ".join("%s %.2f" % (x["key"], mib(x["bytes"]))
                     for x in r["size"]["sections"] if x["bytes"] >= 0.005 * 1048576)
t, a = r["target"], r["accuracy"] or {}
far = [b for b in a.get("bands", []) if b["from"] >= 8]
worst = lambda key: max((b[key] for b in far), default=float("nan"))
print("\t".join([
    name, str(r["mesh"]["vertices"]), str(r["samples"]["final"]),
    "%d (%s)" % (len(t["rounds"]), " > ".join(map(str, t["rounds"]))),
    {True: "met", False: "NOT met", None: "-"}[t["met"]] + ("" if t["met"] else " (%s)" % t["stop"]),
    "%.2f" % mib(r["size"]["bytes"]), sections, "%.0f" % float(wall), "%.0f" % (float(user) + float(sys_s)),
    "%.0f" % (int(rss) / 1024), "%.3f%%" % (100 * a.get("uniform_rms", float("nan"))),
    "%.2f%% / %.2f%%" % (100 * worst("p99_vertex"), 100 * worst("p99_interior"))]))
PY
done
