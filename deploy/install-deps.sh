#!/usr/bin/env bash
# Installs every Debian 12 package that geodex needs to build, test and benchmark.
# Idempotent: packages already present are left alone. Needs root (or sudo).
#
#   deploy/install-deps.sh               everything: build, tests, benchmarks,
#                                        fuzzers, linters, the k8s validator (npm)
#   deploy/install-deps.sh --build-only  only what building the binaries needs
#                                        (cmake -DGEODEX_BUILD_TESTS=OFF
#                                        -DGEODEX_BUILD_BENCHMARKS=OFF
#                                        -DGEODEX_WITH_CGAL=OFF): no CGAL, clang,
#                                        test frameworks, shellcheck, node/npm
#                                        (the image's build stage uses it)
set -euo pipefail

BUILD_ONLY=0
case "${1:-}" in
  "") ;;
  --build-only) BUILD_ONLY=1 ;;
  -h|--help) sed -n '2,12p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
  *) echo "install-deps: unknown argument $1 (--build-only or nothing)" >&2; exit 2 ;;
esac
if [ "$#" -gt 1 ]; then echo "install-deps: one argument at most" >&2; exit 2; fi

# Building the binaries (server, builder, query tool, CLI, client library).
BUILD_PACKAGES=(
  build-essential cmake ninja-build pkg-config
  libabsl-dev libeigen3-dev libspdlog-dev libfmt-dev
  libtinyobjloader-dev libcli11-dev libxxhash-dev
  libtinygltf-dev     # the glTF reader (core/mesh/mesh_io_gltf.cc)
  libprotobuf-dev protobuf-compiler libgrpc++-dev protobuf-compiler-grpc
  prometheus-cpp-dev
  libcpp-httplib-dev  # the HTTP server of `geodex web`
  zlib1g-dev          # the CLI's PNG pictures (client/cli/image.h)
  libcairo2-dev fonts-dejavu-core  # the build report's chart: geodex-build --report-png
  libjs-three         # three.js for the web viewer, copied into the build and install trees
  # The Python package geodex: its stubs (grpc_tools), the in-process module
  # (pybind11, python3-dev) and what it imports at run time.
  python3-dev pybind11-dev python3-numpy python3-grpcio python3-grpc-tools python3-protobuf
)
# Tests, benchmarks, reference cross-checks and tooling.
DEV_PACKAGES=(
  git libtbb-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libcgal-dev libgmp-dev libmpfr-dev libboost-dev
  clang-format
  clang libclang-rt-14-dev  # the libFuzzer targets (tests/fuzz)
  openssl  # server tests generate TLS certificates with it
  python3-pytest  # the Python package's tests (client/python/tests)
  # The package as users install it: the wheel (python3-build), installed
  # into fresh virtual environments (python3-venv), and its types (mypy).
  python3-build python3-venv mypy
  shellcheck  # deploy/k8s/check.sh lints every script in deploy/ and tests/
  chromium chromium-driver python3-selenium  # the web viewer's browser test
)

PACKAGES=("${BUILD_PACKAGES[@]}")
if [ "$BUILD_ONLY" -eq 0 ]; then PACKAGES+=("${DEV_PACKAGES[@]}"); fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if [ "${#missing[@]}" -gt 0 ]; then
  echo "install-deps: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
else
  echo "install-deps: all packages present"
fi

if [ "$BUILD_ONLY" -eq 1 ]; then exit 0; fi

# The offline Kubernetes schema validator of deploy/k8s/check.sh (npm packages
# pinned in deploy/k8s/validate/package-lock.json), installed now because the
# check runs without network. Debian's nodejs/npm only if no node is present.
command -v npm > /dev/null || { $SUDO apt-get update -qq && $SUDO apt-get install -y -qq --no-install-recommends nodejs npm; }
npm ci --silent --no-audit --no-fund --prefix "$(dirname "$0")/k8s/validate"
