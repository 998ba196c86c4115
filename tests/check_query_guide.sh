#!/usr/bin/env bash
# Fails when the "Adding a query" guide in core/query/README.md and the tree
# disagree on the files of the worked example, the exponential map.
#
# The tree's list: every tracked file but Markdown that names the map
# (ExpMap, expmap, exp_map in any case), but this script. The guide's list: every path in
# backquotes between the markers "<!-- query-files begin -->" and
# "<!-- query-files end -->" of core/query/README.md, Markdown files left out.
# Each path is written out in full there (no {h,cc}), so that both lists
# are plain sets of paths.
#
#   tests/check_query_guide.sh [ROOT]          compare; print the difference
#   tests/check_query_guide.sh --list [ROOT]   print the tree's list, by folder
#
# Exit 0 when the two lists are the same, 1 when not (the paths to add to
# or take out of the guide are printed) or when a new query touches more
# files than max_files (the tree's list but the files of the guide's row
# "not touched by a new query"), 77 (skipped) outside a git tree.
set -uo pipefail

list_only=0
if [[ "${1:-}" == "--list" ]]; then
  list_only=1
  shift
fi
root="${1:-$(dirname "$0")/..}"
cd "$root" || exit 1
if ! git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  echo "check_query_guide: not a git tree; skipped" >&2
  exit 77
fi
guide=core/query/README.md
# A ratchet on how many files a new query touches: lower it when a change
# leaves fewer, never raise it to make room for one.
max_files=25

tree_list() {
  # This script names the map too, to search for it.
  git grep -il -E 'exp_?map' -- ':!*.md' ':!tests/check_query_guide.sh' | LC_ALL=C sort -u
}

guide_rows() {
  sed -n '/<!-- query-files begin -->/,/<!-- query-files end -->/p' "$guide"
}

paths_of() {
  grep -o '`[^`]*`' | tr -d '`' |
  grep -E '^[A-Za-z0-9_.-]+(/[A-Za-z0-9_.-]+)+$|^[A-Za-z0-9_.-]+\.[A-Za-z]+$' |
  grep -v '\.md$' | LC_ALL=C sort -u
}

guide_list() { guide_rows | paths_of; }
# The files that use the map without being part of adding a query.
untouched_list() { guide_rows | grep '^| not touched by a new query' | paths_of; }

if ((list_only)); then
  # One line per top folder, ready to compare with the guide's table.
  tree_list | awk -F/ '{
      top = $1; if (NF > 2 && (top == "core" || top == "client")) top = $1 "/" $2
      rows[top] = rows[top] " `" $0 "`"; n[top]++; total++ }
    END { for (t in rows) printf "%s (%d):%s\n", t, n[t], rows[t]; printf "total: %d\n", total }' |
    LC_ALL=C sort
  exit 0
fi

if ! grep -q '<!-- query-files begin -->' "$guide"; then
  echo "check_query_guide: $guide has no <!-- query-files begin --> marker" >&2
  exit 1
fi

tree="$(tree_list)"
listed="$(guide_list)"
missing="$(LC_ALL=C comm -23 <(echo "$tree") <(echo "$listed"))"
stale="$(LC_ALL=C comm -13 <(echo "$tree") <(echo "$listed"))"
count=$(echo "$tree" | grep -c .)
touched_list="$(LC_ALL=C comm -23 <(echo "$tree") <(untouched_list))"
touched=$(echo "$touched_list" | grep -c .)
# Tests and benchmarks: files named *_test.*, and those under tests/.
tests=$(echo "$touched_list" | grep -c -E '(^|/)tests/|_test\.')
echo "check_query_guide: $count files name the exponential map, $touched of them touched by a new query ($((touched - tests)) sources, $tests tests and benchmarks); the guide lists $(echo "$listed" | grep -c .)"
if ((touched > max_files)); then
  echo "a new query touches $touched files, more than max_files=$max_files; adding a query must not touch more"
  exit 1
fi
if [[ -z "$missing" && -z "$stale" ]]; then
  exit 0
fi
if [[ -n "$missing" ]]; then
  echo "name the exponential map but are not in the guide ($guide, \"Adding a query\"):"
  echo "$missing" | sed 's/^/  + /'
fi
if [[ -n "$stale" ]]; then
  echo "in the guide but do not name the exponential map (or are not tracked):"
  echo "$stale" | sed 's/^/  - /'
fi
echo "(tests/check_query_guide.sh --list prints the tree's list by folder)"
exit 1
