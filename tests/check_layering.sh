#!/usr/bin/env bash
# Fails if a layer includes a layer it must not depend on:
#   core/   nothing from gRPC, protobuf or generated code;
#   client/ nothing from core/.
set -uo pipefail
root="${1:-$(dirname "$0")/..}"
status=0
if grep -rnE '#include\s*[<"](grpc|grpcpp|google/protobuf)/|#include\s*[<"][^">]*\.pb\.h[">]|#include\s*[<"](server|client|proto)/' \
    "$root/core" 2>/dev/null; then
  echo "layering: core/ must not include gRPC, protobuf, generated, server or client code" >&2
  status=1
fi
if [ -d "$root/client" ] && grep -rnE '#include\s*[<"](core|server)/' "$root/client" 2>/dev/null; then
  echo "layering: client/ must depend on proto/ only" >&2
  status=1
fi
[ $status -eq 0 ] && echo "layering: ok"
exit $status
