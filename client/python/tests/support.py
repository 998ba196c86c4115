"""Helpers of the geodex package's tests: the build tree's binaries, indexes
built from generated meshes (geodex-build), a geodex-server on a free
loopback port, random surface points, and geodex-query as the reference.

The binaries come from the build tree: $GEODEX_BIN_DIR (ctest sets it; then a
missing binary fails the tests that need it), else ../../../build (then it
skips them). Tests that use the shared development meshes skip when those are
absent ($GEODEX_SHARED_MESHES, else $GEODEX_SHARED_MESHES_DEFAULT).
"""

from __future__ import annotations

import os
import signal
import subprocess
import time
from pathlib import Path
from typing import Dict, List, Optional, Sequence

import numpy as np
import pytest

import geodex

_REPO = Path(__file__).resolve().parents[3]
_BIN_DIR = Path(os.environ.get("GEODEX_BIN_DIR", _REPO / "build"))
_REQUIRED = "GEODEX_BIN_DIR" in os.environ


def binary(relative: str) -> Path:
    """A binary of the build tree (e.g. "server/geodex-server")."""
    path = _BIN_DIR / relative
    if not os.access(path, os.X_OK):
        message = f"{path} is not built"
        if _REQUIRED:
            pytest.fail(message)
        pytest.skip(message)
    return path


def shared_mesh(name: str) -> Path:
    """A mesh of the shared development set, or a skip."""
    root = os.environ.get("GEODEX_SHARED_MESHES") or os.environ.get(
        "GEODEX_SHARED_MESHES_DEFAULT", str(_REPO.parent / "shared" / "meshes")
    )
    path = Path(root) / name
    if not path.is_file():
        pytest.skip(f"shared mesh {path} absent (set GEODEX_SHARED_MESHES)")
    return path


def build_index(mesh: str, out: Path, *args: str) -> Path:
    """geodex-build MESH -o OUT ARGS..., once (kept for the session)."""
    if not out.exists():
        out.parent.mkdir(parents=True, exist_ok=True)
        result = subprocess.run(
            [str(binary("core/geodex-build")), mesh, "-o", str(out), *args],
            capture_output=True,
            text=True,
        )
        assert result.returncode == 0, f"geodex-build {mesh} failed:\n{result.stderr}"
    return out


class Server:
    """A server process on 127.0.0.1, on a port the kernel chose: by default
    geodex-server on `models` (the fake server,
    client/fake_geodex_service_testing.h, with
    binary="client/geodex-fake-server", which announces its port on stderr)."""

    def __init__(self, models: Path, log: Path, *args: str,
                 binary_path: str = "server/geodex-server") -> None:
        self._log = open(log, "w")
        fake = "fake" in binary_path
        self.process = subprocess.Popen(
            [str(binary(binary_path)), "--models", str(models), "--listen", "127.0.0.1:0",
             *([] if fake else ["--workers", "2"]), *args],
            stdout=self._log if fake else subprocess.PIPE,
            stderr=subprocess.PIPE if fake else self._log,
            text=True,
        )
        announce = self.process.stderr if fake else self.process.stdout
        line = announce.readline()  # "... listening on port N", or EOF if it died
        if "listening on port " not in line:
            self.stop()
            raise RuntimeError(f"{binary_path} did not start: {line!r}; see {log}")
        self.address = f"127.0.0.1:{int(line.split()[-1])}"

    def wait_serving(self, names: Sequence[str], token: Optional[str] = None) -> None:
        """Waits (60 s at most) until every model of `names` is SERVING."""
        client = geodex.connect(self.address, token=token)
        deadline = time.monotonic() + 60
        states: Dict[str, str] = {}
        while time.monotonic() < deadline:
            try:
                states = {m.name: m.state for m in client.models()}
            except geodex.Unavailable:
                states = {}
            if all(states.get(n) == "SERVING" for n in names):
                client.close()
                return
            time.sleep(0.1)
        client.close()
        raise RuntimeError(f"models not serving within 60 s: {states}")

    def alive(self) -> bool:
        return self.process.poll() is None

    def stop(self) -> int:
        """SIGTERM (a graceful shutdown), then SIGKILL after 30 s."""
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
            try:
                self.process.wait(30)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        self._log.close()
        return self.process.returncode


def random_points(num_faces: int, n: int, seed: int) -> geodex.SurfacePoints:
    """n points: uniform faces, weights uniform on the triangle; every
    seventh a vertex, every eleventh on an edge (zero weights are the cases
    the engine treats apart)."""
    rng = np.random.default_rng(seed)
    faces = rng.integers(0, num_faces, n).astype(np.int32)
    weights = rng.dirichlet((1.0, 1.0, 1.0), n)
    weights[::7] = np.eye(3)[rng.integers(0, 3, weights[::7].shape[0])]
    weights[3::11] = [0.5, 0.0, 0.5]
    return geodex.SurfacePoints(faces, weights)


def area_uniform_points(vertices: np.ndarray, faces: np.ndarray, n: int, seed: int):
    """n points uniform by area: faces drawn in proportion to their area,
    weights uniform on the triangle (the square-root construction)."""
    rng = np.random.default_rng(seed)
    p = vertices[faces]
    area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    f = rng.choice(faces.shape[0], size=n, p=area / area.sum()).astype(np.int32)
    r1 = np.sqrt(rng.random(n))
    r2 = rng.random(n)
    w = np.stack([1 - r1, r1 * (1 - r2), r1 * r2], axis=1)
    return geodex.SurfacePoints(f, w)


def _format_points(points: geodex.SurfacePoints) -> List[str]:
    return [
        f"{f} {w[0]!r} {w[1]!r} {w[2]!r}" for f, w in zip(points.faces.tolist(), points.weights)
    ]


def run_query(index: Path, tmp: Path, *args: str, stdin_lines: Optional[List[str]] = None,
              file_flag: Optional[str] = None) -> str:
    """geodex-query INDEX ARGS... [FILE_FLAG FILE with stdin_lines]; its stdout."""
    command = [str(binary("core/geodex-query")), str(index), *args]
    if file_flag is not None:
        path = tmp / f"input{len(list(tmp.iterdir()))}.txt"
        path.write_text("\n".join(stdin_lines or []) + "\n")
        command += [file_flag, str(path)]
    result = subprocess.run(command, capture_output=True, text=True)
    assert result.returncode == 0, f"{' '.join(command)} failed:\n{result.stderr}"
    return result.stdout


def query_distances(index: Path, tmp: Path, a: geodex.SurfacePoints, b: geodex.SurfacePoints,
                    *args: str) -> np.ndarray:
    """geodex-query --pairs on the pairs (a[i], b[i]): the reference answers."""
    lines = [f"{x} {y}" for x, y in zip(_format_points(a), _format_points(b))]
    out = run_query(index, tmp, *args, stdin_lines=lines, file_flag="--pairs")
    return np.array([float(v.split()[0]) for v in out.split("\n") if v.strip()])


def query_points_lines(points: geodex.SurfacePoints) -> List[str]:
    return _format_points(points)


def require_in_process() -> None:
    """Skips (or fails, when ctest requires the module) without geodex._core."""
    if geodex.has_in_process():
        return
    if os.environ.get("GEODEX_REQUIRE_IN_PROCESS") == "1":
        pytest.fail("geodex._core is not importable but this build has it")
    pytest.skip("geodex._core is not built (the in-process index)")
