#!/usr/bin/env bash
# Checks proto/rpc_list.cmake, which lists the service's calls for the server
# and the C++ client: on a service written as people write them (comments
# that name "rpc" or hold parentheses, a declaration over two lines, every
# kind of call) it lists each call once with its kind, in order; on what it
# cannot list (a client-streaming call, a message of another package) it
# stops with the reason instead of leaving the call out.
#
#   tests/check_rpc_list.sh [ROOT]
set -euo pipefail
root="${1:-$(dirname "$0")/..}"
script="$root/proto/rpc_list.cmake"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
failed=0

list() { cmake -DPROTO="$1" -DOUT="$2" -P "$script"; }
# Whether the log says $1 (CMake wraps its messages: compare on one line).
says() { tr -s ' \n' '  ' <"$work/log" | grep -q "$1"; }

cat >"$work/good.proto" <<'PROTO'
syntax = "proto3";
package geodex.v1;
message A {}
message B {}
// rpc Commented(A) returns (B);
service Geodex {
  rpc One(A) returns (B);  // (not rpc Two)
  /* rpc Hidden(A) returns (B); */
  rpc Two(A)
      returns (stream B);
  rpc Three(stream A) returns (stream B);
}
PROTO
if list "$work/good.proto" "$work/good.h" >"$work/log" 2>&1; then
  got="$(grep -o '^  X([^)]*)' "$work/good.h" | tr -d ' ')"
  want="$(printf '%s\n' 'X(One,A,B,Unary,__VA_ARGS__)' 'X(Two,A,B,ServerStreaming,__VA_ARGS__)' \
    'X(Three,A,B,BidiStreaming,__VA_ARGS__)')"
  if [[ "$got" != "$want" ]]; then
    echo "rpc_list: listed"; echo "$got"; echo "instead of"; echo "$want"; failed=1
  fi
  # A second run on the same proto leaves the header untouched (its users
  # are not rebuilt).
  touch -d '2000-01-01' "$work/good.h"
  list "$work/good.proto" "$work/good.h"
  if [[ "$(stat -c %Y "$work/good.h")" != "$(date -d '2000-01-01' +%s)" ]]; then
    echo "rpc_list: rewrote an unchanged list"; failed=1
  fi
else
  echo "rpc_list: failed on a good service:"; cat "$work/log"; failed=1
fi

refuse() {  # NAME PATTERN SERVICE-BODY
  printf 'syntax = "proto3";\nservice Geodex {\n%s\n}\n' "$3" >"$work/$1.proto"
  if list "$work/$1.proto" "$work/$1.h" >"$work/log" 2>&1; then
    echo "rpc_list: listed $1 instead of refusing it"; failed=1
  elif ! says "$2"; then
    echo "rpc_list: refused $1 without saying \"$2\":"; cat "$work/log"; failed=1
  fi
}
refuse client_streaming "Up is client-streaming" '  rpc Up(stream A) returns (B);'
refuse other_package "cannot read" '  rpc Empty(A) returns (google.protobuf.Empty);'
refuse options "option blocks" '  rpc One(A) returns (B) { option deprecated = true; }'
printf 'syntax = "proto3";\nservice Other {\n  rpc One(A) returns (B);\n}\n' >"$work/other.proto"
if list "$work/other.proto" "$work/other.h" >"$work/log" 2>&1 || ! says "one service, Geodex"; then
  echo "rpc_list: did not refuse a proto without the Geodex service"; failed=1
fi

((failed)) && exit 1
echo "rpc_list: lists every kind of call in order, refuses what it cannot list"
