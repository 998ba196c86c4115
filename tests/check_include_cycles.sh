#!/usr/bin/env bash
# Fails if the project's files include each other in a loop, or if a folder
# includes one on a floor above it (ctest: include_loops).
#
# Loops between files. A header and
# its source (x.h, x.cc) count as one unit, since x.cc is where x.h's
# promises are kept: x.h -> y.h together with y.cc -> x.h is a loop between
# the units x and y, even though no header includes itself. Tests, mains and
# other sources are units of their own (x_test.cc is the unit x_test).
# Only quoted includes of files in the tree count; a path is taken from the
# root (#include "core/...") or else from the including file's folder.
#
# Floors. The folders of core/, server/ and client/ are floors, listed below
# from the bottom up; a file may include files of its own floor and of floors
# below it, never of one above, so no two folders include each other. A
# folder's subfolders are on its floor unless listed themselves. Tests sit on
# top of everything and are not checked here: *_test.cc, the test helpers
# (*_testing.h, *_testing.cc, *_testing_main.cc) and tests/. An internal/
# folder is included only from within the folder that holds it (the engine's
# parts from the engine), and production code never includes a test helper.
#
#   tests/check_include_cycles.sh [root]
set -uo pipefail
root="$(cd "${1:-$(dirname "$0")/..}" && pwd)"

cd "$root" || exit 1
files="$(find core server client tests proto -type f \( -name '*.h' -o -name '*.cc' \) \
           -not -path '*/CMakeFiles/*' 2>/dev/null | sort)"
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

# --- floors ----------------------------------------------------------------------
# Bottom first; several folders on one line share a floor.
floors='
core/common
core/geometry
core/mesh
core/geodesic
core/index
core/sampling
core/triangulation
core/builder
core/query/engine
core/query
core/validation
core/build
core/tools
core/python
server/config
server/registry
server/convert
server/service
server/streams
server
client client/include
client/cli
client/cli/web
client/cli/commands
'
production="$(grep -vE '_test\.cc$|_testing(_main)?\.(h|cc)$' <<<"$files" | grep -E '^(core|server|client)/')"
if ! awk -v floors="$floors" '
    function floor_of(path,    dir, best, len, prefix) {
      dir = path; sub(/\/[^\/]*$/, "", dir)
      best = -1; len = 0
      for (prefix in rank) {
        if ((dir == prefix || index(dir, prefix "/") == 1) && length(prefix) > len) {
          best = rank[prefix]; len = length(prefix)
        }
      }
      return best
    }
    BEGIN {
      n = split(floors, line, "\n")
      for (i = 1; i <= n; i++) {
        if (line[i] == "") continue
        ++floor
        m = split(line[i], folder, " ")
        for (j = 1; j <= m; j++) { rank[folder[j]] = floor; name[floor] = line[i] }
      }
    }
    NR == FNR || !listed {
      if ($0 == "--") { listed = 1; next }
      exists[$0] = 1
      next
    }
    FNR == 1 {
      dir = FILENAME; sub(/\/[^\/]*$/, "", dir)
      own = floor_of(FILENAME)
      if (own < 0) { printf "floors: %s is in no floor (list its folder in %s)\n", FILENAME, script; bad = 1 }
    }
    /^[ \t]*#[ \t]*include[ \t]*"/ {
      inc = $0; sub(/^[^"]*"/, "", inc); sub(/".*$/, "", inc)
      if (inc in exists) target = inc
      else if ((dir "/" inc) in exists) target = dir "/" inc
      else if (("client/include/" inc) in exists) target = "client/include/" inc
      else next  # a generated or third-party header
      if (target ~ /_testing(_main)?\.(h|cc)$/) {
        printf "floors: %s:%d includes the test helper %s\n", FILENAME, FNR, target; bad = 1
      }
      if (match(target, /\/internal\//)) {
        holder = substr(target, 1, RSTART - 1)
        if (index(FILENAME, holder "/") != 1) {
          printf "floors: %s:%d includes %s, internal to %s/\n", FILENAME, FNR, target, holder; bad = 1
        }
      }
      up = floor_of(target)
      if (own >= 0 && up > own) {
        printf "floors: %s:%d includes %s, a floor above it (%s above %s)\n", FILENAME, FNR, target, name[up], name[own]
        bad = 1
      }
    }
    END { exit bad }' script="tests/check_include_cycles.sh" - $production <<<"$files"$'\n--' >&2; then
  echo "floors: a folder includes one above it; see the list of floors in tests/check_include_cycles.sh" >&2
  exit 1
fi
echo "floors: every include points down"
