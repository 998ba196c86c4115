"""geodex in process, with types: build an index of a mesh given as arrays,
then distances between surface points, a distance field and a located
position. ``mypy --strict`` checks this file against the installed package
(tests/integration/python_wheel_test.sh).

    python3 quickstart.py [OUT_DIR]
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path
from typing import Tuple

import numpy as np
import numpy.typing as npt

import geodex


def bumpy_sheet(n: int) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.int32]]:
    """An n x n grid of unit squares, each split in two, with a bump: (V, 3)
    float64 vertices and (F, 3) int32 faces."""
    u, v = np.meshgrid(np.arange(n + 1, dtype=np.float64), np.arange(n + 1, dtype=np.float64))
    height = 2.0 * np.exp(-((u - n / 2) ** 2 + (v - n / 2) ** 2) / n)
    vertices = np.stack([u.ravel(), v.ravel(), height.ravel()], axis=1)
    corner = (np.arange(n)[:, None] * (n + 1) + np.arange(n)[None, :]).ravel()
    lower = np.stack([corner, corner + 1, corner + n + 2], axis=1)
    upper = np.stack([corner, corner + n + 2, corner + n + 1], axis=1)
    return vertices, np.concatenate([lower, upper]).astype(np.int32)


def main(out_dir: Path) -> None:
    vertices, faces = bumpy_sheet(16)
    index: geodex.Index = geodex.build(vertices, faces, out_dir / "sheet.gdx", samples=60)
    print(index)

    # Two pairs of surface points: (N,) int32 faces, (N, 3) float64 weights.
    a = geodex.SurfacePoints(np.array([0, 10], np.int32), np.array([[1.0, 0, 0], [0.2, 0.3, 0.5]]))
    b = geodex.SurfacePoints(np.array([300, 411], np.int32), np.full((2, 3), 1 / 3))
    # With bounds=True the answer is a pair of (N,) float64 arrays.
    answer = index.distance(a, b, bounds=True)
    assert isinstance(answer, tuple)
    d, bounds = answer
    for i in range(d.shape[0]):
        print(f"d(a[{i}], b[{i}]) = {d[i]:.4f} (error at most {bounds[i]:.2g})")

    # The distance from the nearer of a's points to every vertex: (V,) float64.
    field = index.field(a)
    assert isinstance(field, np.ndarray) and field.shape == (vertices.shape[0],)
    print(f"farthest vertex from a: {int(np.argmax(field))} at {float(np.max(field)):.4f}")

    # A position in space, located on the surface, as a source of its own.
    located: geodex.Located = index.locate(np.array([[8.0, 8.0, 3.0]]))
    print(f"closest surface point: face {located.faces[0]}, {located.distances[0]:.3f} away")
    near = index.distance(located, b.take(slice(0, 1)))
    assert isinstance(near, np.ndarray)
    print(f"from there to b[0]: {near[0]:.4f}")


if __name__ == "__main__":
    if len(sys.argv) > 1:
        main(Path(sys.argv[1]))
    else:
        with tempfile.TemporaryDirectory() as tmp:
            main(Path(tmp))
