#!/usr/bin/env bash
# Installs the geodex client package from a build tree into a temporary
# prefix, then configures, builds and runs the consumer project in this
# directory against it.
#
#   run_consumer_test.sh BUILD_DIR [GENERATOR [CXX_COMPILER]]
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
build_dir="$1"
generator="${2:-Ninja}"
cxx="${3:-c++}"

tmp="$(mktemp -d "${TMPDIR:-/tmp}/geodex-consumer.XXXXXX")"
trap 'rm -rf "$tmp"' EXIT

echo "== cmake --install $build_dir --prefix $tmp/prefix --component client"
cmake --install "$build_dir" --prefix "$tmp/prefix" --component client > "$tmp/install.log"

# The package holds the client and the generated API, nothing of core/ or server/.
for f in include/geodex/client/client.h include/geodex/client/mocks/mock_geodex_connection.h \
         include/geodex/v1/geodex.pb.h lib/cmake/geodex/geodexConfig.cmake \
         lib/cmake/geodex/geodexConfigVersion.cmake bin/geodex; do
  [ -e "$tmp/prefix/$f" ] || { echo "missing from the install: $f" >&2; cat "$tmp/install.log"; exit 1; }
done
if find "$tmp/prefix/include" -path '*/core/*' -o -path '*/server/*' | grep -q .; then
  echo "the install holds core/ or server/ headers" >&2
  exit 1
fi

echo "== configure and build the consumer"
cmake -S "$here" -B "$tmp/build" -G "$generator" -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_PREFIX_PATH="$tmp/prefix" > "$tmp/configure.log" ||
  { cat "$tmp/configure.log"; exit 1; }
cmake --build "$tmp/build" -j2

echo "== run"
"$tmp/build/geodex_consumer"
