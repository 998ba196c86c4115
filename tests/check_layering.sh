#!/usr/bin/env bash
# Fails if a layer depends on a layer it must not, by what it includes and by
# what its CMake targets link (directly or through other targets):
#   core/         nothing from gRPC, protobuf, generated, server or client code;
#   core/builder  nothing built from core/query sources (the query engine, the
#                 point locator); the face BVH it stores is in core/index;
#   client/       nothing from core/ or server/;
#   server/       not the client library;
#   the engine's parts (core/query/engine/internal/) only from the engine and
#                 from tests and benchmarks: the server, the offline tools
#                 and the Python bindings use the public headers (the
#                 queries at the top of core/query/, and the engine's face
#                 at the top of core/query/engine/: query_engine.h,
#                 query_types.h, query_scratch.h). tests/check_include_cycles.sh
#                 checks the rest of core/ and the floors of every folder.
# The Python package keeps the same direction: client/python/geodex imports
# core only through the optional in-process module geodex._core, in
# _inprocess.py alone and inside a try (the client works without it), and
# never by loading a library itself; core/python (the bindings) imports
# nothing of gRPC, protobuf, the generated stubs or the client.
# The link graph is read from the target_link_libraries calls of every
# CMakeLists.txt under core/, proto/, client/ and server/; a target belongs
# to the layer whose directory adds it.
set -uo pipefail
root="${1:-$(dirname "$0")/..}"
status=0

# --- includes ------------------------------------------------------------------
if grep -rnE '#include\s*[<"](grpc|grpcpp|google/protobuf)/|#include\s*[<"][^">]*\.pb\.h[">]|#include\s*[<"](server|client|proto)/' \
    "$root/core" 2>/dev/null; then
  echo "layering: core/ must not include gRPC, protobuf, generated, server or client code" >&2
  status=1
fi
if [ -d "$root/client" ] && grep -rnE '#include\s*[<"](core|server)/' "$root/client" 2>/dev/null; then
  echo "layering: client/ must depend on proto/ only" >&2
  status=1
fi

# Production code outside core's libraries: server/ (but its tests), the tools'
# mains and the Python bindings.
if grep -rnE '#include\s*[<"]core/query/engine/internal/' "$root/server" "$root/core/tools" "$root/core/python" \
    2>/dev/null | grep -vE '_test\.cc:|/server_testing\.(h|cc):'; then
  echo "layering: only core/ and tests include core/query/engine/internal/ (use core/query/input_queries.h)" >&2
  status=1
fi

# --- the Python package ----------------------------------------------------------
pkg="$root/client/python/geodex"
if [ -d "$pkg" ]; then
  if grep -rnE '^\s*(from|import)\s.*\b_core\b' --include='*.py' "$pkg" | grep -v '/_inprocess\.py:'; then
    echo "layering: client/python imports geodex._core outside _inprocess.py" >&2
    status=1
  fi
  # The one import of the compiled module is optional: the line before it is "try:".
  if [ -f "$pkg/_inprocess.py" ] && ! awk '
      /^[[:space:]]*(from|import)[[:space:]].*[^[:alnum:]_]_core([^[:alnum:]_]|$)/ {
        if (prev !~ /^[[:space:]]*try:[[:space:]]*$/) bad = 1
        seen = 1
      }
      { prev = $0 }
      END { exit !(seen && !bad) }' "$pkg/_inprocess.py"; then
    echo "layering: client/python/geodex/_inprocess.py must import _core inside a try" >&2
    status=1
  fi
  if grep -rnE '\b(ctypes|cffi|ExtensionFileLoader)\b' --include='*.py' "$pkg"; then
    echo "layering: client/python must not load core's libraries itself (ctypes, cffi, loaders)" >&2
    status=1
  fi
fi
if [ -d "$root/core/python" ] && grep -rnE 'import\("(grpc|google\.protobuf|geodex\.v1|geodex\.client)|_pb2|\.pb\.h|#include\s*[<"](grpc|grpcpp|google/protobuf|server|client|proto)/' \
    "$root/core/python"; then
  echo "layering: core/python must not use gRPC, protobuf, the generated stubs or the client" >&2
  status=1
fi

# --- links ---------------------------------------------------------------------
# Prints "def TARGET LAYER" for add_library / add_executable, "src TARGET
# FILE" for every source of add_library / add_executable / target_sources that
# lies in query/, and "link TARGET DEPENDENCY" for every item of
# target_link_libraries (comments dropped; a call may span lines).
read -r -d '' links_awk <<'AWK'
FNR == 1 { call = ""; depth = 0 }
{
  line = $0
  sub(/#.*/, "", line)
  if (depth == 0) {
    if (!match(line, /(add_library|add_executable|pybind11_add_module|target_sources|target_link_libraries)[ \t]*\(/)) next
    call = substr(line, RSTART)
    depth = 1
  } else {
    call = call " " line
  }
  if (index(call, ")") == 0) next
  call = substr(call, 1, index(call, ")") - 1)
  gsub(/\(/, " ", call)
  n = split(call, w, /[ \t]+/)
  if (w[1] == "add_library" || w[1] == "add_executable" || w[1] == "pybind11_add_module" ||
      w[1] == "target_sources") {
    if (w[1] != "target_sources") print "def", w[2], layer
    for (i = 3; i <= n; i++) {
      if (layer == "core" && w[i] ~ /^query\//) print "src", w[2], w[i]
    }
  } else {
    for (i = 3; i <= n; i++) {
      if (w[i] == "" || w[i] ~ /^(PUBLIC|PRIVATE|INTERFACE|LINK_PUBLIC|LINK_PRIVATE)$/) continue
      print "link", w[2], w[i]
    }
  }
  depth = 0
  call = ""
}
AWK

# Walks every target's links depth-first; prints each forbidden dependency
# with the chain of links that makes it, and exits 1 if there is one.
read -r -d '' check_awk <<'AWK'
$1 == "def" { layer[$2] = $3; targets[++num_targets] = $2 }
$1 == "link" { adj[$2] = adj[$2] " " $3 }
$1 == "src" { query_source[$2] = $3 }
function forbidden(from, to) {
  if (from == "geodex_builder" && (to == "geodex_query" || to in query_source))
    return "core/builder must not link code built from core/query (" query_source[to] ")"
  if (layer[from] == "core" && (layer[to] ~ /^(proto|server|client)$/ || to ~ /^(gRPC|protobuf)::/))
    return "core/ must not link gRPC, protobuf, generated, server or client code"
  if (layer[from] == "client" && layer[to] ~ /^(core|server)$/)
    return "client/ must depend on proto/ only"
  if (layer[from] == "server" && layer[to] == "client")
    return "server/ must not link the client library"
  return ""
}
END {
  failed = 0
  for (i = 1; i <= num_targets; i++) {
    start = targets[i]
    why = forbidden(start, start)
    if (why != "") {
      printf "layering: %s compiles %s: %s\n", start, query_source[start], why
      failed = 1
    }
    split("", seen)
    split("", parent)
    top = 0
    stack[++top] = start
    seen[start] = 1
    while (top > 0) {
      node = stack[top--]
      n = split(adj[node], deps, " ")
      for (k = 1; k <= n; k++) {
        dep = deps[k]
        if (dep in seen) continue
        seen[dep] = 1
        parent[dep] = node
        stack[++top] = dep
        why = forbidden(start, dep)
        if (why == "") continue
        chain = dep
        for (p = node; p != start; p = parent[p]) chain = p " -> " chain
        printf "layering: %s links %s (%s -> %s): %s\n", start, dep, start, chain, why
        failed = 1
      }
    }
  }
  exit failed
}
AWK

graph=""
for layer in core proto client server; do
  [ -d "$root/$layer" ] || continue
  while IFS= read -r file; do
    graph+="$(awk -v layer="$layer" "$links_awk" "$file")"$'\n'
  done < <(find "$root/$layer" -name CMakeLists.txt | sort)
done
if ! grep -q '^def geodex_builder ' <<<"$graph"; then
  echo "layering: no geodex_builder target found; update tests/check_layering.sh" >&2
  status=1
fi
if ! awk "$check_awk" <<<"$graph" >&2; then
  status=1
fi

[ $status -eq 0 ] && echo "layering: ok"
exit $status
