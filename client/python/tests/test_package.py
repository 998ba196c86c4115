"""What Python code sees of the package before any call: its names
(``__all__``, ``dir(geodex)``) and how its objects print. No server needed."""

from __future__ import annotations

import os

import pytest

import geodex


def test_dir_and_all_list_the_public_names_only():
    names = dir(geodex)
    for helper in ("NoReturn", "TYPE_CHECKING", "annotations", "_errors", "_typing"):
        assert helper not in names
    assert set(geodex.__all__) <= set(names)
    assert "__version__" in names
    for name in geodex.__all__:
        if name in ("connect", "Client") and os.environ.get("GEODEX_WITHOUT_CLIENT") == "1":
            continue
        assert getattr(geodex, name) is not None, name
    assert len(set(geodex.__all__)) == len(geodex.__all__)
    assert "error_for_code" not in geodex.__all__


def test_a_model_prints_as_one_line_and_keeps_its_report():
    # A report as large as a real build's: printing the list of models
    # shows none of it.
    report = {
        "target": {"verdict": "0.500% met in 1 round (m = 1010); the closest check ..."},
        "build_report": {f"key_{i}": "x" * 40 for i in range(250)},
    }
    model = geodex.Model(
        name="bunny", version=3, available_versions=(1, 3), state="SERVING", reason="",
        num_vertices=5000, num_faces=9996, num_samples=1010, num_triangles=2016,
        bbox_min=(0.0, 0.0, 0.0), bbox_max=(1.0, 1.0, 1.0), requested_samples=1000, seed=1,
        samples_added_by_repair=10, builder_version="geodex-build 0.1",
        build_report={k: v for k, v in report["build_report"].items()},
        mapped_bytes=3 * 1048576, report=report,
    )
    text = repr([model])
    assert len(text) < 250, text
    assert "bunny" in text and "version 3" in text and "SERVING" in text
    assert "5000 vertices" in text and "m = 1010" in text and "3.00 MiB" in text
    assert "0.500% met" in text
    # The report is one attribute away, whole.
    assert model.report is report and model.verdict.startswith("0.500% met")
    failed = geodex.Model(
        name="x", version=1, available_versions=(1,), state="FAILED", reason="bad file",
        num_vertices=0, num_faces=0, num_samples=0, num_triangles=0, bbox_min=(),
        bbox_max=(), requested_samples=0, seed=0, samples_added_by_repair=0,
        builder_version="",
    )
    assert repr(failed) == "geodex.Model('x', version 1, FAILED: bad file)"
    assert failed.verdict == ""


def test_a_client_shows_its_address_but_not_its_token():
    pytest.importorskip("grpc")
    # Connecting is lazy: nothing listens on this port, nothing is called.
    with geodex.connect("localhost:1", token="s3cret", timeout=5) as client:
        text = repr(client)
    assert "'localhost:1'" in text and "plaintext" in text and "token" in text
    assert "s3cret" not in text
    assert client.address == "localhost:1"
