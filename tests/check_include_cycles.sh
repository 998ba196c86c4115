#!/usr/bin/env bash
# Fails if the project's files include each other in a loop. A header and
# its source (x.h, x.cc) count as one unit, since x.cc is where x.h's
# promises are kept: x.h -> y.h together with y.cc -> x.h is a loop between
# the units x and y, even though no header includes itself. Tests, mains and
# other sources are units of their own (x_test.cc is the unit x_test).
# Only quoted includes of files in the tree count; a path is taken from the
# root (#include "core/...") or else from the including file's folder.
#
#   tests/check_include_cycles.sh [root]
set -uo pipefail
root="$(cd "${1:-$(dirname "$0")/..}" && pwd)"

edges="$(
  cd "$root" &&
  find core server client tests proto -type f \( -name '*.h' -o -name '*.cc' \) \
       -not -path '*/build*' 2>/dev/null | sort |
  while IFS= read -r file; do
    unit="${file%.*}"
    # Every unit is a node, with or without includes.
    echo "$unit $unit"
    sed -nE 's/^[[:space:]]*#[[:space:]]*include[[:space:]]*"([^"]+)".*/\1/p' "$file" |
    while IFS= read -r inc; do
      if [ -f "$inc" ]; then
        target="$inc"
      elif [ -f "$(dirname "$file")/$inc" ]; then
        target="$(realpath --relative-to=. "$(dirname "$file")/$inc")"
      else
        continue  # a generated or third-party header
      fi
      [ "${target%.*}" = "$unit" ] || echo "$unit ${target%.*}"
    done
  done
)"

if ! loops="$(tsort <<<"$edges" 2>&1 >/dev/null)" || [ -n "$loops" ]; then
  echo "include loops: these units include each other (x.h and x.cc are one unit):" >&2
  sed -E 's/^tsort: //' <<<"$loops" | grep -v 'input contains a loop' >&2
  exit 1
fi
echo "include loops: none"
