#!/usr/bin/env python3
"""Runs the command and code blocks of the pages, as a reader would.

Every fenced block that a page marks with the line ``<!-- doc-test -->``
right above its fence runs as written, in a scratch folder that holds what a
reader of that page has: the build tree's programs (``build/core/...`` and on
PATH, as after ``cmake --install``), the demo's index served as model
``torus`` (``build/demo/models``, as ``deploy/demo.sh`` leaves it, and
``$GEODEX_SERVER``), the files the examples name (``pairs.txt``,
``sources.txt``, ``X.gdx``, ``bunny.obj``, ...) and, for the README's Python
snippet, ``bunny.gdx`` served as model ``bunny``. Only the ports change: each
``127.0.0.1:PORT`` or ``localhost:PORT`` of a page maps to a free one, so
that the test runs beside others. A block whose command fails (a shell
block under ``set -e -o pipefail``, curl with ``--fail-with-body``; a
Python block that raises) fails the test with its output, and so does a
page without a marked block.

    doc_blocks_test.py --build-dir BUILD [--python PYTHON] [--keep DIR] PAGE...
"""

import argparse
import math
import os
import re
import shutil
import socket
import subprocess
import sys
import tempfile
import time

MARK = "<!-- doc-test -->"
FENCE = re.compile(r"^```(\w+)\s*$")
ADDRESS = re.compile(r"\b(127\.0\.0\.1|localhost):(\d{4,5})\b")
# A server or gateway started in the background by a block: the next lines
# wait until it listens, as a reader typing the next command would.
BACKGROUND_LISTEN = re.compile(r"--listen\s+(\S+).*&\s*$")


def blocks_of(page):
    """(language, first line number, text) of each marked block of a page."""
    lines = open(page, encoding="utf-8").read().splitlines()
    out = []
    i = 0
    while i < len(lines):
        if lines[i].strip() == MARK and i + 1 < len(lines):
            fence = FENCE.match(lines[i + 1].strip())
            if not fence:
                sys.exit(f"{page}:{i + 1}: {MARK} is not followed by a fence")
            body = []
            j = i + 2
            while j < len(lines) and lines[j].strip() != "```":
                body.append(lines[j])
                j += 1
            out.append((fence.group(1), i + 3, "\n".join(body) + "\n"))
            i = j
        i += 1
    return out


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Ports:
    """Each port a page names, mapped to a free one (the same everywhere)."""

    def __init__(self):
        self.map = {}

    def of(self, port):
        if port not in self.map:
            self.map[port] = free_port()
        return self.map[port]

    def rewrite(self, text):
        return ADDRESS.sub(lambda m: f"{m.group(1)}:{self.of(m.group(2))}", text)


def wait_listening(address, process, seconds=60):
    host, port = address.rsplit(":", 1)
    deadline = time.time() + seconds
    while time.time() < deadline:
        if process is not None and process.poll() is not None:
            sys.exit(f"{address}: the server exited ({process.returncode})")
        try:
            with socket.create_connection((host, int(port)), timeout=1):
                return
        except OSError:
            time.sleep(0.1)
    sys.exit(f"{address}: nothing listens after {seconds} s")


def run(cmd, **kwargs):
    r = subprocess.run(cmd, capture_output=True, text=True, **kwargs)
    if r.returncode != 0:
        sys.exit(f"{' '.join(map(str, cmd))}: exit {r.returncode}\n{r.stdout}{r.stderr}")
    return r.stdout


def write_sphere_obj(path, subdivisions=4, bumps=0.05):
    """An icosphere with a ripple: the README's bunny.obj stand-in."""
    t = (1 + 5 ** 0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
         (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
         (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
         (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    v = [tuple(c / math.sqrt(sum(x * x for x in p)) for c in p) for p in v]
    for _ in range(subdivisions):
        mid = {}

        def middle(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                p = [(x + y) / 2 for x, y in zip(v[a], v[b])]
                n = math.sqrt(sum(x * x for x in p))
                v.append(tuple(x / n for x in p))
                mid[key] = len(v) - 1
            return mid[key]

        nf = []
        for a, b, c in f:
            ab, bc, ca = middle(a, b), middle(b, c), middle(c, a)
            nf += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = nf
    with open(path, "w") as out:
        for x, y, z in v:
            r = 1 + bumps * math.sin(5 * x) * math.sin(5 * y)
            out.write(f"v {r * x:.9f} {r * y:.9f} {r * z:.9f}\n")
        for a, b, c in f:
            out.write(f"f {a + 1} {b + 1} {c + 1}\n")


class Stage:
    """The scratch folder, its files and the servers the pages expect."""

    def __init__(self, build, work, ports):
        self.build, self.work, self.ports = build, work, ports
        self.servers = []
        self.env = dict(os.environ)
        os.makedirs(os.path.join(work, "build"))
        for part in ("core", "client", "server", "tests", "python"):
            if os.path.isdir(os.path.join(build, part)):
                os.symlink(os.path.join(build, part), os.path.join(work, "build", part))
        self.env["PATH"] = os.pathsep.join(
            [os.path.join(build, "client"), os.path.join(build, "core"),
             os.path.join(build, "server"), self.env.get("PATH", "")])
        self.env["PYTHONPATH"] = os.path.join(build, "python")
        self.env.pop("GEODEX_SERVER", None)

    def bin(self, part, name):
        return os.path.join(self.build, part, name)

    def files(self):
        w = self.work
        torus = os.path.join(w, "build", "demo", "models", "torus", "1", "index.gdx")
        os.makedirs(os.path.dirname(torus))
        run([self.bin("core", "geodex-build"), "builtin:torus", "-o", torus, "--samples", "200",
             "--threads", "2"], cwd=w)
        shutil.copy(torus, os.path.join(w, "X.gdx"))
        # Points of the torus's first faces (it has 9,216), as the examples'.
        pairs = ["0 1 0 0 100 0.2 0.3 0.5", "5 0.5 0.5 0 4000 0.1 0.1 0.8",
                 "17 0.2 0.2 0.6 9000 0.3 0.3 0.4"]
        self.write("pairs.txt", pairs)
        self.write("path_pairs.txt", pairs[:1])
        # Vertex ids ("v ID") in place of points, alone and mixed.
        self.write("vertex_pairs.txt", ["v 0 v 4000", "v 17 100 0.2 0.3 0.5"])
        self.write("sources.txt", ["0 1 0 0", "100 0.2 0.3 0.5"])
        self.write("s.txt", ["0 1 0 0", "100 0.2 0.3 0.5"])
        self.write("t.txt", ["5 0.5 0.5 0", "4000 0.1 0.1 0.8", "9000 0.3 0.3 0.4"])
        self.write("points.txt", ["2.7 0 0", "0 1.3 0.7"])
        self.write("xyz.txt", ["2.7 0 0 0 1.3 0.7"])
        write_sphere_obj(os.path.join(w, "bunny.obj"))
        bunny = os.path.join(w, "served", "bunny", "1", "index.gdx")
        os.makedirs(os.path.dirname(bunny))
        run([self.bin("core", "geodex-build"), os.path.join(w, "bunny.obj"), "-o", bunny,
             "--samples", "1000", "--threads", "2"], cwd=w)
        return torus

    def write(self, name, lines):
        with open(os.path.join(self.work, name), "w") as f:
            f.write("".join(line + "\n" for line in lines))

    def serve(self, models, address):
        log = open(os.path.join(self.work, f"server_{address.rsplit(':', 1)[1]}.log"), "w")
        p = subprocess.Popen([self.bin("server", "geodex-server"), "--models", models,
                              "--listen", address], stdout=log, stderr=subprocess.STDOUT)
        self.servers.append(p)
        wait_listening(address, p)

    def stop(self):
        for p in self.servers:
            p.terminate()
        for p in self.servers:
            try:
                p.wait(timeout=10)
            except subprocess.TimeoutExpired:
                p.kill()


SHELL_PRELUDE = r"""set -e -o pipefail
trap 'kill $(jobs -p) 2> /dev/null || true; wait 2> /dev/null || true' EXIT
curl() { command curl --fail-with-body "$@"; }
wait_listening() {
  for _ in $(seq 600); do (exec 3<> "/dev/tcp/${1%:*}/${1##*:}") 2> /dev/null && return 0; sleep 0.1; done
  echo "nothing listens on $1" >&2; return 1
}
"""


def shell_script(text, ports):
    out = []
    for line in ports.rewrite(text).splitlines():
        out.append(line)
        started = BACKGROUND_LISTEN.search(line)
        if started:
            out.append(f"wait_listening {started.group(1)}")
    return SHELL_PRELUDE + "\n".join(out) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--build-dir", required=True)
    ap.add_argument("--python", default=sys.executable,
                    help="the python3 with the package's needs (numpy, grpcio, protobuf)")
    ap.add_argument("--keep", help="work in this folder and keep it")
    ap.add_argument("pages", nargs="+")
    args = ap.parse_args()
    build = os.path.abspath(args.build_dir)
    for b in (("core", "geodex-build"), ("server", "geodex-server"), ("client", "geodex")):
        if not os.access(os.path.join(build, *b), os.X_OK):
            print(f"doc_blocks: SKIPPED: no {os.path.join(build, *b)}")
            return 77
    marked = {page: blocks_of(page) for page in args.pages}
    for page, blocks in marked.items():
        if not blocks:
            sys.exit(f"{page}: no block marked {MARK}")

    work = os.path.abspath(args.keep) if args.keep else tempfile.mkdtemp(prefix="geodex_doc_")
    os.makedirs(work, exist_ok=True)
    ports = Ports()
    stage = Stage(build, work, ports)
    failed = 0
    try:
        stage.files()
        cli = f"127.0.0.1:{free_port()}"
        stage.serve(os.path.join(work, "build", "demo", "models"), cli)
        stage.env["GEODEX_SERVER"] = cli
        # The README's Python snippet asks 127.0.0.1:8980 for model "bunny".
        stage.serve(os.path.join(work, "served"), f"127.0.0.1:{ports.of('8980')}")
        for page, blocks in marked.items():
            for k, (language, line, text) in enumerate(blocks):
                name = f"{os.path.basename(os.path.dirname(os.path.abspath(page)))}_{k}"
                if language in ("sh", "bash"):
                    script = os.path.join(work, name + ".sh")
                    with open(script, "w") as f:
                        f.write(shell_script(text, ports))
                    cmd = ["bash", script]
                elif language == "python":
                    script = os.path.join(work, name + ".py")
                    with open(script, "w") as f:
                        f.write(ports.rewrite(text))
                    cmd = [args.python, script]
                else:
                    sys.exit(f"{page}:{line}: a marked block in {language}, which this test cannot run")
                start = time.time()
                r = subprocess.run(cmd, cwd=work, env=stage.env, capture_output=True, text=True,
                                   timeout=600)
                took = time.time() - start
                if r.returncode == 0:
                    print(f"ok    {page}:{line} ({language}, {took:.1f} s)")
                else:
                    failed += 1
                    print(f"FAIL  {page}:{line} ({language}, exit {r.returncode})\n"
                          f"--- the block as run ({script}):\n{open(script).read()}"
                          f"--- its output:\n{r.stdout}{r.stderr}")
    finally:
        stage.stop()
        if not args.keep:
            shutil.rmtree(work, ignore_errors=True)
    print(f"doc_blocks: {sum(map(len, marked.values())) - failed} of "
          f"{sum(map(len, marked.values()))} blocks ran")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
