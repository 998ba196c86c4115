#!/usr/bin/env bash
# The Python package as its users get it: a wheel (python3 -m build, PEP 517,
# client/python), installed into fresh virtual environments in a temporary
# folder away from the source tree, and the package's tests run against the
# installed copy, not the build tree:
#   1. with the extra geodex[client] (grpcio, protobuf): the whole suite, and
#      the typed example checked by mypy --strict and run;
#   2. without it (grpc and protobuf made unimportable in that environment):
#      the in-process tests; those needing a server skip.
# The compiled module comes from BUILD_DIR (setup.py's GEODEX_CMAKE_BUILD_DIR),
# so the extension is not compiled a second time.
#
#   python_wheel_test.sh BUILD_DIR [PYTHON]     (PYTHON: the build's python3)
set -euo pipefail
build=$(cd "$1" && pwd)
python="${2:-/usr/bin/python3}"
source_dir=$(cd "$(dirname "$0")/../.." && pwd)
package="$source_dir/client/python"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
say() { echo "python_wheel_test: $*"; }

for module in build venv; do
  "$python" -c "import $module" 2> /dev/null ||
    { say "$python lacks the module $module (deploy/install-deps.sh installs it)"; exit 1; }
done

say "building the wheel"
GEODEX_CMAKE_BUILD_DIR="$build" GEODEX_SETUP_BUILD_BASE="$work/setup" \
  "$python" -m build --wheel --no-isolation --outdir "$work/dist" "$package" > "$work/build.log" 2>&1 ||
  { cat "$work/build.log"; say "the wheel did not build"; exit 1; }
wheels=("$work"/dist/geodex-*.whl)
if [ "${#wheels[@]}" -ne 1 ] || [ ! -f "${wheels[0]}" ]; then
  say "expected one wheel: ${wheels[*]}"; exit 1
fi
wheel="${wheels[0]}"
say "built $(basename "$wheel")"
# What a wheel must hold: the compiled module, the stubs, the types.
"$python" - "$wheel" << 'EOF'
import sys, zipfile
names = zipfile.ZipFile(sys.argv[1]).namelist()
for want in ("geodex/__init__.py", "geodex/py.typed", "geodex/_core.pyi", "geodex/v1/geodex_pb2.py"):
    assert want in names, f"{want} missing from the wheel: {names}"
assert any(n.startswith("geodex/_core.") and n.endswith(".so") for n in names), names
assert not any("tests/" in n or n.startswith("build/") for n in names), names
EOF

# The tests and the example are copied too: run from the temporary folder,
# nothing of the source tree is on sys.path.
cp -r "$package/tests" "$work/tests"
cp "$package/examples/quickstart.py" "$work/quickstart.py"
export GEODEX_BIN_DIR="$build" GEODEX_REQUIRE_IN_PROCESS=1 PYTHONDONTWRITEBYTECODE=1
export GEODEX_SHARED_MESHES_DEFAULT="${GEODEX_SHARED_MESHES_DEFAULT:-$source_dir/../shared/meshes}"
unset PYTHONPATH

# installed ENV: the package the environment imports is the installed one.
installed() {
  (cd "$work" && "$1/bin/python" -c "
import geodex, sys
assert geodex.__file__.startswith(sys.prefix), geodex.__file__
assert geodex.has_in_process()
print(geodex.__file__)")
}

# --- 1. with the client's dependencies ------------------------------------------
say "environment with geodex[client]"
"$python" -m venv --system-site-packages "$work/with-client"
# --no-index: the dependencies (numpy, grpcio, protobuf) are Debian's, offline.
"$work/with-client/bin/pip" install --quiet --no-index "${wheel}[client]"
installed "$work/with-client"
(cd "$work" && "$work/with-client/bin/python" -m pytest -q -p no:cacheprovider tests)
(cd "$work" && "$work/with-client/bin/python" -m mypy --strict --no-incremental quickstart.py)
(cd "$work" && "$work/with-client/bin/python" quickstart.py "$work")

# --- 2. without them -----------------------------------------------------------
say "environment without geodex[client]"
"$python" -m venv --system-site-packages "$work/no-client"
"$work/no-client/bin/pip" install --quiet --no-index "$wheel"
# Debian's grpcio and protobuf lie in the system site the environment sees;
# a .pth file hides them in it, as if they were not installed.
site=$("$work/no-client/bin/python" -c "import sysconfig; print(sysconfig.get_path('purelib'))")
cp "$package/tests/hide_client_deps.py" "$site/"
echo "import hide_client_deps" > "$site/zz_hide_client_deps.pth"
if "$work/no-client/bin/python" -c "import grpc" 2> /dev/null; then
  say "grpc is still importable in the environment without the client"; exit 1
fi
installed "$work/no-client"
(cd "$work" && GEODEX_WITHOUT_CLIENT=1 "$work/no-client/bin/python" -m pytest -q -p no:cacheprovider \
  -rs tests/test_arrays.py tests/test_index.py tests/test_without_client.py)
say "ok"
