#!/usr/bin/env bash
# Installs every Debian 12 package that geodex needs to build, test and benchmark.
# Idempotent: packages already present are left alone. Needs root (or sudo).
set -euo pipefail

PACKAGES=(
  build-essential cmake ninja-build pkg-config git
  libabsl-dev libeigen3-dev libspdlog-dev libfmt-dev
  libtinyobjloader-dev libcli11-dev libtbb-dev libxxhash-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libprotobuf-dev protobuf-compiler libgrpc++-dev protobuf-compiler-grpc
  prometheus-cpp-dev
  libcgal-dev libgmp-dev libmpfr-dev libboost-dev
  clang-format
  clang libclang-rt-14-dev  # the libFuzzer targets (tests/fuzz)
  openssl  # server tests generate TLS certificates with it
  shellcheck  # deploy/k8s/check.sh lints every script in deploy/ and tests/
)

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

# The offline Kubernetes schema validator of deploy/k8s/check.sh (npm packages
# pinned in deploy/k8s/validate/package-lock.json), installed now because the
# check runs without network. Debian's nodejs/npm only if no node is present.
command -v npm > /dev/null || { $SUDO apt-get update -qq && $SUDO apt-get install -y -qq --no-install-recommends nodejs npm; }
npm ci --silent --no-audit --no-fund --prefix "$(dirname "$0")/k8s/validate"
