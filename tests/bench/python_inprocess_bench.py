#!/usr/bin/env python3
"""The in-process Python batch (geodex.Index.distance, one thread) against
the C++ batch on the same pairs, side by side in one run.

    PYTHONPATH=build/python python3 tests/bench/python_inprocess_bench.py \\
        --index model.gdx [--pairs 1000000] [--near-pairs unfold] [--repeat 5]

Draws area-uniform pairs on the index's mesh file (faces in proportion to
their area, weights uniform on the triangle), in the file's ids as users
give them. The C++ figure is tests/bench/pairs_rate on those pairs: read
through the facade (InputQueries::Read) and answered by DistanceBatch in
batches of 8,192 pairs (the blocks the binding reads and answers in), one
thread, per CPU-second of that thread. The Python figure is
Index(threads=1).distance on the same numpy arrays, per CPU-second of the
process (numpy's checks, the binding, the read and the answers), the best
of --repeat runs. Both answer the same pairs to the bit: the script checks
that the answers' digests are equal. Prints both rates and their ratio;
exits 1 if the digests differ. Without --index, builds builtin:torus with
200 samples first.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import geodex
from python_client_bench import area_uniform  # the same pairs as the client's bench

REPO = Path(__file__).resolve().parents[2]


def digest(values: np.ndarray) -> int:
    """pairs_rate's digest: FNV-1a over the answers' 64-bit patterns, one
    multiply a value (vectorised in blocks is not possible: each step needs
    the last; 1M values take about a second)."""
    h = 14695981039346656037
    for bits in values.view(np.uint64).tolist():
        h = ((h ^ bits) * 1099511628211) & 0xFFFFFFFFFFFFFFFF
    return h


def write_pairs(path: Path, a: geodex.SurfacePoints, b: geodex.SurfacePoints) -> None:
    rows = np.column_stack([a.faces, a.weights, b.faces, b.weights])
    # %.17g: the weights read back to the same doubles.
    np.savetxt(path, rows, fmt=["%d", "%.17g", "%.17g", "%.17g", "%d", "%.17g", "%.17g", "%.17g"])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--index", type=Path,
                        help="index file (.gdx); default: builtin:torus, m = 200")
    parser.add_argument("--build-dir", type=Path, default=REPO / "build")
    parser.add_argument("--pairs", type=int, default=1_000_000)
    parser.add_argument("--repeat", type=int, default=5, help="timed Python runs (the best)")
    parser.add_argument("--near-pairs", choices=["path", "unfold", "exact"], default="unfold",
                        help="near-pair mode (default unfold: the pure O(1) answer)")
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()

    with tempfile.TemporaryDirectory(prefix="geodex-inprocess-bench-") as tmp:
        work = Path(tmp)
        index = args.index
        if index is None:
            index = work / "torus.gdx"
            subprocess.run([str(args.build_dir / "core/geodex-build"), "builtin:torus",
                            "--samples", "200", "-o", str(index)],
                           check=True, stdout=subprocess.DEVNULL)
        in_process = geodex.Index(index, threads=1)
        vertices, faces = in_process.mesh()
        a = area_uniform(vertices, faces, args.pairs, args.seed)
        b = area_uniform(vertices, faces, args.pairs, args.seed + 1)
        pairs = work / "pairs.txt"
        write_pairs(pairs, a, b)

        cpp = subprocess.run(
            [str(args.build_dir / "tests/pairs_rate"), "--index", str(index), "--pairs", str(pairs),
             "--batch", "8192", "--passes", str(args.repeat),
             "--near-pairs", args.near_pairs],
            check=True, capture_output=True, text=True).stdout
        # "| index | pairs | 1234.5K | digest |"
        cells = [c.strip() for c in cpp.strip().split("|")[1:-1]]
        cpp_rate, cpp_digest = float(cells[2].rstrip("K")) * 1e3, int(cells[3], 16)

        answers = in_process.distance(a, b, near_pairs=args.near_pairs)  # warm-up
        best = float("inf")
        for _ in range(args.repeat):
            start = time.process_time()
            answers = in_process.distance(a, b, near_pairs=args.near_pairs)
            best = min(best, time.process_time() - start)
        py_rate = args.pairs / best
        same = digest(answers) == cpp_digest

        print(f"index {index} ({in_process.num_vertices} vertices, m = {in_process.num_samples}), "
              f"{args.pairs} area-uniform pairs in the file's ids, near pairs: {args.near_pairs}, "
              "one thread")
        print("| how | pairs/s |")
        print("|---|---|")
        print(f"| C++: InputQueries::Read + DistanceBatch (pairs_rate) | {cpp_rate / 1e6:.3f}M |")
        print(f"| Python: Index.distance | {py_rate / 1e6:.3f}M |")
        print(f"Python / C++: {py_rate / cpp_rate:.2f}; answers equal to the bit: {same}")
        return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
