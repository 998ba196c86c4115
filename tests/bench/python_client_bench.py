#!/usr/bin/env python3
"""Throughput of the Python client's distance (geodex.Client.distance) on
loopback, against the same pairs answered in process (geodex.Index) in the
same run.

    PYTHONPATH=build/python python3 tests/bench/python_client_bench.py \\
        --index model.gdx [--pairs 1000000] [--repeat 3] [--near-pairs unfold]

Starts build/server/geodex-server on a free loopback port over a model
repository holding the index (a symbolic link), draws area-uniform pairs on
its mesh (faces in proportion to their area, weights uniform on the
triangle), and times client.distance on all of them: numpy arrays in, one
StreamDistances call in batches, numpy out, the server and the client on the
same machine. The in-process figure is geodex.Index.distance on the same
pairs with as many threads as the server has workers; both must give the
same answers to the bit (checked). Without --index, builds builtin:torus
with 200 samples first.
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import geodex

REPO = Path(__file__).resolve().parents[2]


def area_uniform(vertices: np.ndarray, faces: np.ndarray, n: int, seed: int):
    rng = np.random.default_rng(seed)
    p = vertices[faces]
    area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
    f = rng.choice(faces.shape[0], size=n, p=area / area.sum()).astype(np.int32)
    r1, r2 = np.sqrt(rng.random(n)), rng.random(n)
    return geodex.SurfacePoints(f, np.stack([1 - r1, r1 * (1 - r2), r1 * r2], axis=1))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--index", type=Path,
                        help="index file (.gdx); default: builtin:torus, m = 200")
    parser.add_argument("--build-dir", type=Path, default=REPO / "build")
    parser.add_argument("--pairs", type=int, default=1_000_000)
    parser.add_argument("--repeat", type=int, default=3,
                        help="timed runs of each (best and median)")
    parser.add_argument("--batch-size", type=int, default=32768, help="pairs per stream batch")
    parser.add_argument("--workers", type=int, default=0, help="server workers (0: one per core)")
    parser.add_argument("--near-pairs", choices=["path", "unfold", "exact"], default=None,
                        help="near-pair mode (default: the model's, i.e. path)")
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()

    work = Path(tempfile.mkdtemp(prefix="geodex-pybench-"))
    index = args.index
    if index is None:
        index = work / "torus.gdx"
        subprocess.run([str(args.build_dir / "core/geodex-build"), "builtin:torus",
                        "--samples", "200", "-o", str(index)],
                       check=True, stdout=subprocess.DEVNULL)
    model_dir = work / "models" / "bench" / "1"
    model_dir.mkdir(parents=True)
    (model_dir / "index.gdx").symlink_to(index.resolve())
    workers = args.workers or os.cpu_count() or 1
    server = subprocess.Popen(
        [str(args.build_dir / "server/geodex-server"), "--models", str(work / "models"),
         "--listen", "127.0.0.1:0", "--workers", str(workers), "--log-level", "warn"],
        stdout=subprocess.PIPE, text=True)
    try:
        line = server.stdout.readline()
        if not line.startswith("listening on port "):
            print(f"geodex-server did not start: {line!r}", file=sys.stderr)
            return 1
        address = f"127.0.0.1:{int(line.split()[-1])}"
        client = geodex.connect(address, batch_size=args.batch_size)
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            try:
                if client.model("bench").state == "SERVING":
                    break
            except (geodex.Unavailable, geodex.NotFound):
                pass
            time.sleep(0.2)
        vertices, faces = client.mesh("bench")
        a = area_uniform(vertices, faces, args.pairs, args.seed)
        b = area_uniform(vertices, faces, args.pairs, args.seed + 1)
        in_process = geodex.Index(index, threads=workers)

        def timed(fn):
            fn()  # warm-up (and the answer to compare)
            seconds = []
            for _ in range(args.repeat):
                start = time.perf_counter()
                fn()
                seconds.append(time.perf_counter() - start)
            return min(seconds), statistics.median(seconds)

        d_client = client.distance("bench", a, b, near_pairs=args.near_pairs)
        d_local = in_process.distance(a, b, near_pairs=args.near_pairs)
        same = bool(np.array_equal(d_client, d_local))
        mode = args.near_pairs
        client_best, client_median = timed(lambda: client.distance("bench", a, b, near_pairs=mode))
        local_best, local_median = timed(lambda: in_process.distance(a, b, near_pairs=mode))
        n = args.pairs
        model = client.model("bench")
        print(f"index {index} ({model.num_vertices} vertices, m = {model.num_samples}), "
              f"{n} area-uniform pairs, near pairs: {args.near_pairs or 'model default (path)'}, "
              f"server workers {workers}, batch {args.batch_size}, {os.cpu_count()} cores")
        print("| how | best | median | pairs/s (best) |")
        print("|---|---|---|---|")
        print(f"| client.distance over loopback | {client_best:.3f} s | {client_median:.3f} s | "
              f"{n / client_best / 1e6:.3f}M |")
        print(f"| Index.distance in process | {local_best:.3f} s | {local_median:.3f} s | "
              f"{n / local_best / 1e6:.3f}M |")
        print(f"client / in process: {local_best / client_best:.2f}; "
              f"answers equal to the bit: {same}")
        return 0 if same else 1
    finally:
        server.terminate()
        server.wait(30)
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
