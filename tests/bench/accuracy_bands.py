#!/usr/bin/env python3
"""What to expect of the answers: p99 by distance band over the shared meshes.

One measured source, three readers. `measure` runs the accuracy harness on
each shared mesh's default index (geodex-build MESH, no flags but the
threads), in the default mode and the every-distance mode (refine_below 8),
and writes accuracy_bands.tsv beside this script: one line a mesh, mode,
kind of point and band of L1000. `render` turns that file into the
"what to expect" table the README and tests/bench/accuracy.md hold between
the lines <!-- accuracy-bands --> and <!-- /accuracy-bands -->, and into the
chart tests/pictures/accuracy_bands.svg; `check` fails when a page or the
chart differs from what the file renders (ctest: accuracy_bands).

    accuracy_bands.py measure [--build-dir build] [--index-dir DIR] [--mesh NAME ...]
    accuracy_bands.py render    # rewrites the pages' blocks and the chart
    accuracy_bands.py check     # exit 1 when one of them is stale
"""

import argparse
import csv
import os
import re
import statistics
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
TSV = os.path.join(HERE, "accuracy_bands.tsv")
CHART = os.path.join(REPO, "tests", "pictures", "accuracy_bands.svg")
PAGES = [os.path.join(REPO, "README.md"), os.path.join(HERE, "accuracy.md")]
BEGIN, END = "<!-- accuracy-bands -->", "<!-- /accuracy-bands -->"
BANDS = ["0-0.5", "0.5-1", "1-2", "2-4", "4-8", "8-16", ">=16"]
MODES = {"default": "default", "every": "below8"}  # ours: the harness's
KINDS = ["vertex", "interior"]
FIELDS = ["mesh", "m", "mode", "kind", "band", "pairs", "rms", "p99", "max", "coverage"]
# coverage: of the error bounds, % (empty in the default mode, measured without them)
# The harness's row: | case | points | bin | pairs | RMS | p99 | max | coverage | ...
ROW = re.compile(r"^\| (\S+) m=(\d+) (\S+) \| (vertex|interior) \| (\S+) L1000 \| (\d+) \| "
                 r"([0-9.]+)% \| ([0-9.]+)% \| ([0-9.]+)% \| (?:([0-9.]+)%|-) \|")


def measure(args):
    meshes_dir = os.path.join(REPO, "..", "shared", "meshes")
    if not os.path.isdir(meshes_dir):
        print(f"accuracy_bands: {meshes_dir} is absent; skipped", file=sys.stderr)
        return 77
    names = args.mesh or sorted(
        f[:-4] for f in os.listdir(meshes_dir)
        if f.endswith(".obj") and not f.startswith("cow_nonmanifold"))
    os.makedirs(args.index_dir, exist_ok=True)
    rows = []
    for name in names:
        mesh = os.path.join(meshes_dir, name + ".obj")
        index = os.path.join(args.index_dir, name + ".gdx")
        if not os.path.exists(index):
            print(f"{name}: building its default index", file=sys.stderr)
            subprocess.run([os.path.join(args.build_dir, "core", "geodex-build"), mesh, "-o", index,
                            "--threads", str(args.threads)], check=True, stdout=subprocess.DEVNULL)
        print(f"{name}: measuring", file=sys.stderr)
        out = subprocess.run(
            [os.path.join(args.build_dir, "tests", "geodex-accuracy"), mesh, "--index", index,
             "--modes", *MODES.values(), "--target-error", "0.005", "--sources", str(args.sources),
             "--seed", str(args.seed), "--threads", str(args.threads)],
            check=True, capture_output=True, text=True).stdout
        ours = {v: k for k, v in MODES.items()}
        for line in out.splitlines():
            r = ROW.match(line)
            if r and r.group(3) in ours:
                rows.append(dict(zip(FIELDS, [r.group(1), r.group(2), ours[r.group(3)], r.group(4),
                                              r.group(5), r.group(6), r.group(7), r.group(8),
                                              r.group(9), r.group(10) or ""])))
        if not any(row["mesh"] == name for row in rows):
            sys.exit(f"{name}: no row by L1000 band in the harness's output:\n{out}")
    with open(TSV, "w", newline="") as f:
        f.write(f"# tests/bench/accuracy_bands.py measure --sources {args.sources} --seed "
                f"{args.seed}: geodex-accuracy MESH --index <default build> --modes "
                f"{' '.join(MODES.values())} --target-error 0.005\n")
        w = csv.DictWriter(f, FIELDS, delimiter="\t", lineterminator="\n")
        w.writeheader()
        w.writerows(rows)
    return render(args)


def load():
    with open(TSV) as f:
        lines = [line for line in f if not line.startswith("#")]
    rows = list(csv.DictReader(lines, delimiter="\t"))
    for r in rows:
        for k in ("p99", "max", "rms"):
            r[k] = float(r[k])
    return rows


def p99s(rows, mode, kind, band):
    """{mesh: p99} of one cell."""
    return {r["mesh"]: r["p99"] for r in rows
            if r["mode"] == mode and r["kind"] == kind and r["band"] == band}


def percent(x):
    return f"{x:.2f}%" if x >= 0.1 else f"{x:.3f}%"


def table(rows):
    meshes = sorted({r["mesh"] for r in rows})
    head = ("| distance (L1000) | the target | default: vertex | default: interior "
            "| every-distance: vertex | every-distance: interior |\n"
            "|---|---|---|---|---|---|\n")
    body = ""
    for band in BANDS:
        judged = "p99 ≤ 2%" if band in ("8-16", ">=16") else "not judged"
        cells = []
        for mode in MODES:
            for kind in KINDS:
                cell = p99s(rows, mode, kind, band)
                worst = max(cell, key=cell.get)
                named = f" {worst}" if cell[worst] > min(cell.values()) else ""  # not a tie
                cells.append(f"{percent(statistics.median(cell.values()))} · "
                             f"{percent(cell[worst])}{named}")
        body += f"| {band.replace('-', '–').replace('>=', '≥ ')} | {judged} | {' | '.join(cells)} |\n"
    return (f"{BEGIN}\n"
            f"p99 relative error by distance band, median of the {len(meshes)} meshes · worst "
            f"mesh; from [tests/bench/accuracy_bands.tsv](tests/bench/accuracy_bands.tsv) "
            f"(`tests/bench/accuracy_bands.py measure`):\n\n{head}{body}{END}")


def chart(rows):
    """An SVG of the p99 by band: each mode's median line and worst marks."""
    width, height, left, right, top, bottom = 640, 300, 56, 150, 16, 40
    worst_all = max(r["p99"] for r in rows)
    top_value = max(1.0, float(int(worst_all) + 1))
    x_of = lambda i: left + (i + 0.5) * (width - left - right) / len(BANDS)
    y_of = lambda v: top + (1 - v / top_value) * (height - top - bottom)
    colours = {"default": "#c0392b", "every": "#2471a3"}
    names = {"default": "default", "every": "every-distance (refine_below 8)"}
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
           f'font-family="sans-serif" font-size="11">',
           f'<rect width="{width}" height="{height}" fill="white"/>']
    for k in range(int(top_value) + 1):
        y = y_of(k)
        out.append(f'<line x1="{left}" y1="{y:.1f}" x2="{width - right}" y2="{y:.1f}" '
                   f'stroke="#ddd"/><text x="{left - 6}" y="{y + 4:.1f}" '
                   f'text-anchor="end">{k}%</text>')
    target = y_of(2.0)
    out.append(f'<line x1="{x_of(4.5):.1f}" y1="{target:.1f}" x2="{width - right}" '
               f'y2="{target:.1f}" stroke="#333" stroke-dasharray="4 3"/>'
               f'<text x="{x_of(5.5):.1f}" y="{target - 4:.1f}" text-anchor="middle">'
               f'the target: p99 ≤ 2%</text>')
    for i, band in enumerate(BANDS):
        out.append(f'<text x="{x_of(i):.1f}" y="{height - bottom + 16}" text-anchor="middle">'
                   f'{band.replace(">=", "≥ ")}</text>')
    out.append(f'<text x="{(left + width - right) / 2:.1f}" y="{height - 6}" '
               f'text-anchor="middle">distance, L1000 (vertex and interior pairs)</text>')
    for n, mode in enumerate(MODES):
        median, worst = [], []
        for band in BANDS:
            per_mesh = {}
            for kind in KINDS:
                for mesh, v in p99s(rows, mode, kind, band).items():
                    per_mesh[mesh] = max(per_mesh.get(mesh, 0), v)
            median.append(statistics.median(per_mesh.values()))
            worst.append(max(per_mesh.values()))
        c = colours[mode]
        points = " ".join(f"{x_of(i):.1f},{y_of(v):.1f}" for i, v in enumerate(median))
        out.append(f'<polyline points="{points}" fill="none" stroke="{c}" stroke-width="2"/>')
        for i, v in enumerate(worst):
            x, y = x_of(i) + (n - 0.5) * 6, y_of(v)
            out.append(f'<line x1="{x:.1f}" y1="{y_of(median[i]):.1f}" x2="{x:.1f}" y2="{y:.1f}" '
                       f'stroke="{c}" stroke-opacity="0.5"/><circle cx="{x:.1f}" cy="{y:.1f}" '
                       f'r="3" fill="{c}"/>')
        ly = top + 14 + 34 * n
        out.append(f'<line x1="{width - right + 10}" y1="{ly}" x2="{width - right + 28}" '
                   f'y2="{ly}" stroke="{c}" stroke-width="2"/><text x="{width - right + 32}" '
                   f'y="{ly + 4}">{names[mode].split(" (")[0]}</text>')
        if "(" in names[mode]:
            out.append(f'<text x="{width - right + 32}" y="{ly + 17}">'
                       f'({names[mode].split(" (")[1]}</text>')
    ly = top + 14 + 34 * len(MODES)
    out.append(f'<circle cx="{width - right + 19}" cy="{ly}" r="3" fill="#555"/>'
               f'<text x="{width - right + 32}" y="{ly + 4}">worst mesh</text>'
               f'<text x="{width - right + 32}" y="{ly + 17}">line: median mesh</text>')
    out.append("</svg>")
    return "\n".join(out) + "\n"


def rendered_pages(rows):
    """{page: its text with the block replaced} for every page."""
    block = table(rows)
    out = {}
    for page in PAGES:
        text = open(page, encoding="utf-8").read()
        start, end = text.find(BEGIN), text.find(END)
        if start < 0 or end < start:
            sys.exit(f"{page}: no {BEGIN} ... {END} block")
        link = os.path.relpath(os.path.join(HERE, "accuracy_bands.tsv"), os.path.dirname(page))
        out[page] = text[:start] + block.replace("(tests/bench/accuracy_bands.tsv)",
                                                 f"({link})") + text[end + len(END):]
    return out


def render(_args=None):
    rows = load()
    for page, text in rendered_pages(rows).items():
        with open(page, "w", encoding="utf-8") as f:
            f.write(text)
    with open(CHART, "w", encoding="utf-8") as f:
        f.write(chart(rows))
    return 0


def check(_args=None):
    rows = load()
    stale = [page for page, text in rendered_pages(rows).items()
             if open(page, encoding="utf-8").read() != text]
    if not os.path.exists(CHART) or open(CHART, encoding="utf-8").read() != chart(rows):
        stale.append(CHART)
    for page in stale:
        print(f"accuracy_bands: {os.path.relpath(page, REPO)} differs from what "
              f"tests/bench/accuracy_bands.tsv renders (run accuracy_bands.py render)")
    if not stale:
        print("accuracy_bands: the pages and the chart render the measured file")
    return 1 if stale else 0


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="command", required=True)
    m = sub.add_parser("measure")
    m.add_argument("--build-dir", default=os.path.join(REPO, "build"))
    m.add_argument("--index-dir", default="/tmp/geodex_default_indexes",
                   help="default indexes, MESH.gdx (built when missing)")
    m.add_argument("--mesh", nargs="*", help="names under ../shared/meshes (default: all but the cow)")
    m.add_argument("--sources", type=int, default=40)
    m.add_argument("--seed", type=int, default=7)
    m.add_argument("--threads", type=int, default=2)
    sub.add_parser("render")
    sub.add_parser("check")
    args = ap.parse_args()
    return {"measure": measure, "render": render, "check": check}[args.command](args)


if __name__ == "__main__":
    sys.exit(main())
