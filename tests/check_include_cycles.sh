#!/usr/bin/env bash
# Fails if the project's files include each other in a loop (ctest: include_loops). A header and
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

cd "$root" || exit 1
files="$(find core server client tests proto -type f \( -name '*.h' -o -name '*.cc' \) \
           -not -path '*/build*' 2>/dev/null | sort)"
# One awk over every file: the list of files first (to resolve paths), then
# their lines. Prints "unit included-unit" per include, and "unit unit" so
# that every unit is a node.
edges="$(
  { echo "$files"; echo "--"; } | awk '
    NR == FNR || !listed {
      if ($0 == "--") { listed = 1; next }
      exists[$0] = 1
      next
    }
    FNR == 1 {
      unit = FILENAME; sub(/\.[^.\/]*$/, "", unit)
      dir = FILENAME; sub(/\/[^\/]*$/, "", dir)
      print unit, unit
    }
    /^[ \t]*#[ \t]*include[ \t]*"/ {
      inc = $0; sub(/^[^"]*"/, "", inc); sub(/".*$/, "", inc)
      if (inc in exists) target = inc
      else if ((dir "/" inc) in exists) target = dir "/" inc
      else next  # a generated or third-party header
      sub(/\.[^.\/]*$/, "", target)
      if (target != unit) print unit, target
    }' - $files
)"

if ! loops="$(tsort <<<"$edges" 2>&1 >/dev/null)" || [ -n "$loops" ]; then
  echo "include loops: these units include each other (x.h and x.cc are one unit):" >&2
  sed -E 's/^tsort: //' <<<"$loops" | grep -v 'input contains a loop' >&2
  exit 1
fi
echo "include loops: none"
