"""The package without its client's dependencies (grpcio and protobuf, the
extra geodex[client]): the in-process index and the builder work, and
connect and Client name what is missing and the extra that brings it."""

from __future__ import annotations

import importlib
import os
import subprocess
import sys
from pathlib import Path

import pytest

import geodex
from support import require_in_process

_HERE = Path(__file__).resolve().parent

# Run in a child interpreter that cannot import grpc (hide_client_deps), so
# that this file also tests the package where grpcio is installed.
_SCRIPT = r"""
import sys
import hide_client_deps
try:
    import grpc
except ImportError:
    pass
else:
    raise SystemExit("grpc is importable: the test hides nothing")
import numpy as np
import geodex

index = geodex.build("builtin:cube", sys.argv[1], samples=24, calibrate=False)
d = index.distance((np.array([0, 3], np.int32), np.eye(3)[:2]),
                   (np.array([7, 11], np.int32), np.full((2, 3), 1 / 3)))
assert d.shape == (2,) and d.dtype == np.float64 and (d > 0).all() and np.isfinite(d).all(), d
assert np.array_equal(d, geodex.Index(sys.argv[1]).distance(
    (np.array([0, 3]), np.eye(3)[:2]), (np.array([7, 11]), np.full((2, 3), 1 / 3))))
assert geodex.Tls(ca_file="ca.pem").ca_file == "ca.pem"  # the client's values need no gRPC
for attempt in (lambda: geodex.connect("127.0.0.1:1"), lambda: geodex.Client):
    try:
        attempt()
    except ImportError as e:
        assert "grpcio" in str(e) and "geodex[client]" in str(e), str(e)
    else:
        raise SystemExit("no ImportError without grpc")
assert "grpc" not in sys.modules and "geodex.client" not in sys.modules
print("in process without grpc:", d.tolist())
"""


def test_index_and_build_work_and_connect_names_the_extra(tmp_path: Path) -> None:
    require_in_process()
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(_HERE), env.get("PYTHONPATH", "")])
    result = subprocess.run(
        [sys.executable, "-c", _SCRIPT, str(tmp_path / "cube.gdx")],
        capture_output=True, text=True, env=env, cwd=tmp_path,
    )
    assert result.returncode == 0, result.stdout + result.stderr
    assert "in process without grpc" in result.stdout


@pytest.mark.skipif(os.environ.get("GEODEX_WITHOUT_CLIENT") != "1",
                    reason="only where the client's dependencies are absent")
def test_this_environment_has_no_client_dependencies() -> None:
    with pytest.raises(ImportError):
        importlib.import_module("grpc")
    with pytest.raises(ImportError, match=r"geodex\[client\]"):
        geodex.connect("127.0.0.1:1")
