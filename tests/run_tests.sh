#!/usr/bin/env bash
# Builds geodex and runs the whole test suite (unit, integration, accuracy,
# golden and layering checks). This is the README's test command and what CI
# runs (.ci/run). Benchmarks are built but not run here.
set -euo pipefail
cd "$(dirname "$0")/.."

bash deploy/install-deps.sh
BUILD_DIR="${GEODEX_BUILD_DIR:-build}"
# Warnings fail the build here (and in the fuzz and sanitizer trees that
# ctest builds: they read GEODEX_WERROR from the environment).
export GEODEX_WERROR=ON
cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DGEODEX_WERROR=ON
cmake --build "$BUILD_DIR" -j"$(nproc)"
ctest --test-dir "$BUILD_DIR" --output-on-failure -j"$(nproc)" --timeout 900
