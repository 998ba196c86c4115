#!/usr/bin/env bash
# Shows that tests/check_include_cycles.sh fails on what it is for (ctest:
# include_loops_catches): on a copy of the tree's sources it plants, one at a
# time, a loop between two files, an include of a floor above, an include of
# an engine part from outside the engine, an include of a test helper from
# production code and a folder on no floor; each must fail with its message,
# and the untouched copy must pass.
#
#   tests/check_include_cycles_test.sh [root]
set -uo pipefail
root="$(cd "${1:-$(dirname "$0")/..}" && pwd)"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
failed=0

fresh() {
  rm -rf "$work/tree"
  mkdir -p "$work/tree/tests"
  (cd "$root" && find core server client -type f \( -name "*.h" -o -name "*.cc" \) -print0 |
     xargs -0 cp --parents -t "$work/tree")
}

# expect NAME PATTERN: the check on the planted copy fails and says PATTERN.
expect() {
  local out
  if out="$(bash "$root/tests/check_include_cycles.sh" "$work/tree" 2>&1)"; then
    echo "FAIL $1: the check passed"; failed=1
  elif ! grep -q -- "$2" <<<"$out"; then
    echo "FAIL $1: no '$2' in:"; echo "$out"; failed=1
  else
    echo "ok   $1"
  fi
}

fresh
if out="$(bash "$root/tests/check_include_cycles.sh" "$work/tree" 2>&1)"; then
  echo "ok   the tree as it is"
else
  echo "FAIL the tree as it is:"; echo "$out"; failed=1
fi

fresh
echo '#include "core/index/index.h"' >>"$work/tree/core/mesh/mesh.h"
echo '#include "core/mesh/mesh.h"' >>"$work/tree/core/index/index.h"
expect "a loop" "include loops"

fresh
echo '#include "core/query/input_queries.h"' >>"$work/tree/core/builder/plan.cc"
expect "a floor above" "a floor above it (core/query above core/builder)"

fresh
part="$(cd "$work/tree" && find core/query/engine/internal -name '*.h' | sort | head -1)"
echo "#include \"$part\"" >>"$work/tree/core/query/input_queries.cc"
expect "an engine part from outside the engine" "internal to core/query/engine/"

fresh
echo "#include \"core/index/index_testing.h\"" >>"$work/tree/server/convert/convert.cc"
expect "a test helper in production code" "includes the test helper"

fresh
mkdir -p "$work/tree/core/nowhere"
echo '#include "core/mesh/mesh.h"' >"$work/tree/core/nowhere/x.cc"
expect "a folder on no floor" "is in no floor"

exit $failed
