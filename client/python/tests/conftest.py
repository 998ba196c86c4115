"""Fixtures of the geodex package's tests (helpers in support.py): a model
repository built from generated meshes, a geodex-server started on it on a
free loopback port, and a client of it."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Iterator

import pytest

import geodex
from support import Server, build_index


@pytest.fixture(scope="session")
def models_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A model repository: "torus" (calibrated, so with error bounds) and
    "cube" (built without calibration)."""
    root = tmp_path_factory.mktemp("models")
    build_index("builtin:torus", root / "torus" / "1" / "index.gdx", "--samples", "200")
    build_index("builtin:cube", root / "cube" / "1" / "index.gdx", "--samples", "64",
                "--no-calibration")
    return root


@pytest.fixture(scope="session")
def torus_index(models_dir: Path) -> Path:
    return models_dir / "torus" / "1" / "index.gdx"


@pytest.fixture(scope="session")
def server(models_dir: Path, tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    # The wheel test's environment without grpcio (GEODEX_WITHOUT_CLIENT=1)
    # skips what needs the client; anywhere else a missing grpcio fails.
    if os.environ.get("GEODEX_WITHOUT_CLIENT") == "1":
        pytest.skip("the client's dependencies are not installed (GEODEX_WITHOUT_CLIENT=1)")
    s = Server(models_dir, tmp_path_factory.mktemp("server") / "server.log")
    try:
        s.wait_serving(["torus", "cube"])
        yield s
    finally:
        s.stop()


@pytest.fixture(scope="session")
def client(server: Server) -> Iterator[geodex.Client]:
    c = geodex.connect(server.address)
    yield c
    c.close()


@pytest.fixture(scope="session")
def torus_mesh(client: geodex.Client):
    """The torus's (V, 3) vertices and (F, 3) faces, as the server gives them."""
    return client.mesh("torus")


