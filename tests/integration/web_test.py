#!/usr/bin/env python3
"""`geodex web` end to end: a real geodex-server, the gateway, and (with
--browser) the viewer in headless Chromium.

  web_test.py --geodex G --server-bin S --build-bin B --query-bin Q --out DIR [--browser]
              [--mesh MESH --samples M --screenshot PNG --panel-screenshot PNG]

Without --browser: the HTTP/JSON API against geodex-query offline (distances,
error bounds, field, path to 1e-9), the merged streams, and the error codes.

With --browser: loads the page in headless Chromium (selenium and Debian's
chromedriver), waits until the mesh is drawn (and checks that WebGL really
drew it), clicks a source and shift-clicks a target with real mouse events at
canvas pixels, moves the mouse over a third point, toggles the geodesic
triangulation, and checks the distances the page shows (data-distance, the
exact number it received) against geodex-query for the surface points the page
sent (read back from window.geodexViewer.state). The build report: the
panel's report equals geodex-query --info --format json, its accuracy table
shows the cells of geodex-query --info's text, its chart draws each bin's p99
and RMS at the report's values (and `geodex info` prints the same text); at
1000x700 and 1400x900 no word or number of the panel is broken across lines.
Screenshots go to DIR.
Exits 77 (ctest: skipped) when chromium, chromedriver or selenium is missing.
"""

import argparse
import json
import math
import os
import random
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.request

SKIP = 77
TOLERANCE = 1e-9


def fail(message):
    print(f"web_test: FAIL: {message}", file=sys.stderr)
    sys.exit(1)


def check(condition, message):
    if not condition:
        fail(message)


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Http:
    def __init__(self, base):
        self.base = base

    def call(self, method, path, body=None, raw=None):
        data = raw if raw is not None else (json.dumps(body).encode() if body is not None else None)
        request = urllib.request.Request(self.base + path.lstrip("/"), data=data, method=method)
        if data is not None:
            request.add_header("Content-Type", "application/json")
        try:
            with urllib.request.urlopen(request, timeout=60) as r:
                return r.status, r.headers.get("Content-Type", ""), r.read()
        except urllib.error.HTTPError as e:
            return e.code, e.headers.get("Content-Type", ""), e.read()

    def json(self, method, path, body=None):
        status, _, content = self.call(method, path, body)
        check(status == 200, f"{method} {path}: HTTP {status}: {content[:300]!r}")
        return json.loads(content)

    def error(self, method, path, want_http, want_code, body=None, raw=None):
        status, ctype, content = self.call(method, path, body, raw)
        check(status == want_http, f"{method} {path}: HTTP {status}, want {want_http}: {content[:200]!r}")
        check(ctype.startswith("application/json"), f"{method} {path}: error content type {ctype}")
        e = json.loads(content)
        check(e.get("code") == want_code and isinstance(e.get("message"), str) and e.get("details") == [],
              f"{method} {path}: error body {e}, want code {want_code}")
        return e


def num(x):
    return float(x) if isinstance(x, str) else x


class Stack:
    """The model repository, geodex-server and `geodex web`, stopped on exit."""

    def __init__(self, args, work, token=False):
        self.args, self.work, self.procs = args, work, []
        auth = []
        if token:  # the server wants a bearer token; the gateway's gRPC side sends it
            self.token_file = os.path.join(work, "token.txt")
            with open(self.token_file, "w") as f:
                f.write("web-test-secret\n")
            auth = ["--token-file", self.token_file]
        self.name = args.model_name
        self.index = os.path.join(work, "models", self.name, "1", "index.gdx")
        os.makedirs(os.path.dirname(self.index))
        with open(os.path.join(work, "build.log"), "w") as log:
            r = subprocess.run([args.build_bin, args.mesh, "-o", self.index, "--samples", str(args.samples)],
                               stdout=log, stderr=subprocess.STDOUT)
        check(r.returncode == 0, f"geodex-build failed (see {work}/build.log)")
        for attempt in range(3):
            self.grpc = f"127.0.0.1:{free_port()}"
            server = self.start([args.server_bin, "--models", os.path.join(work, "models"), "--listen", self.grpc,
                                 *auth], "server.log")
            time.sleep(0.3)
            if server.poll() is None:
                break
            self.procs.remove(server)
        self.url = self.start_web(auth)
        self.http = Http(self.url)
        deadline = time.time() + 60
        while True:
            status, _, content = self.http.call("GET", "v1/models")
            if status == 200:
                models = {m["name"]: m for m in json.loads(content)["models"]}
                if models.get(self.name, {}).get("state") == "SERVING":
                    self.info = models[self.name]
                    break
            check(time.time() < deadline, f"model {self.name} not SERVING within 60 s ({self.work}/server.log)")
            time.sleep(0.2)

    def start_web(self, auth):
        """Starts `geodex web` on a free port and returns its URL."""
        web = self.start([self.args.geodex, "web", "--server", self.grpc, "--listen", "127.0.0.1:0",
                          "--max-body", "65536", "--timeout", "30", *auth], None, stdout=subprocess.PIPE)
        line = web.stdout.readline().decode()
        check(line.startswith("geodex web: serving http://"), f"geodex web printed {line!r}")
        return line.split()[3]

    def start(self, cmd, log_name, stdout=None):
        out = stdout if stdout is not None else open(os.path.join(self.work, log_name), "w")
        p = subprocess.Popen(cmd, stdout=out, stderr=subprocess.STDOUT if stdout is None else None)
        self.procs.append(p)
        return p

    def stop(self):
        for p in reversed(self.procs):
            if p.poll() is None:
                p.send_signal(signal.SIGTERM)
                try:
                    p.wait(timeout=10)
                except subprocess.TimeoutExpired:
                    p.kill()

    def query(self, *args):
        r = subprocess.run([self.args.query_bin, self.index, *args], capture_output=True, text=True)
        check(r.returncode == 0, f"geodex-query {' '.join(args)}: {r.stderr}")
        return [line.split() for line in r.stdout.splitlines() if line.strip()]

    def write(self, name, lines):
        path = os.path.join(self.work, name)
        with open(path, "w") as f:
            f.write("".join(line + "\n" for line in lines))
        return path


def point_line(p):
    return " ".join([str(p["face"])] + [repr(float(w)) for w in p["weights"]])


def surface_points(points):
    return {"faces": [p["face"] for p in points], "weights": [w for p in points for w in p["weights"]]}


def close(a, b):
    return a == b or abs(a - b) <= TOLERANCE


# --- the HTTP API ------------------------------------------------------------------


def test_http(stack):
    http, info = stack.http, stack.info
    faces, vertices = int(info["numFaces"]), int(info["numVertices"])
    for path, ctype in (("", "text/html"), ("viewer.js", "application/javascript"),
                        ("three.min.js", "application/javascript"), ("OrbitControls.js", "application/javascript"),
                        ("viewer.css", "text/css")):
        status, got, content = http.call("GET", path)
        check(status == 200 and got.startswith(ctype) and content, f"GET /{path}: {status} {got}")

    rng = random.Random(7)

    def random_point():
        w = [rng.random() + 0.01 for _ in range(3)]
        s = sum(w)
        return {"face": rng.randrange(faces), "weights": [x / s for x in w]}

    a = [random_point() for _ in range(40)]
    b = [random_point() for _ in range(40)]
    pairs = stack.write("pairs.txt", [point_line(p) + " " + point_line(q) for p, q in zip(a, b)])
    expected = stack.query("--pairs", pairs, "--error-bounds")
    got = http.json("POST", f"v1/models/{stack.name}:distance",
                    {"a": surface_points(a), "b": surface_points(b), "errorBounds": True})
    check(len(got["distances"]) == 40 and len(got["bounds"]) == 40, f"distance answer {got}")
    for i, (d, bound) in enumerate(zip(got["distances"], got["bounds"])):
        check(close(num(d), float(expected[i][0])), f"pair {i}: HTTP {d} != geodex-query {expected[i][0]}")
        check(close(num(bound), float(expected[i][1])), f"pair {i}: bound {bound} != {expected[i][1]}")
    check(got["version"] == "1", f"version {got['version']!r}")

    field = http.json("POST", f"v1/models/{stack.name}:field", {"sources": surface_points(a[:1])})
    check(len(field["distances"]) == vertices and field["vertexOffset"] == "0", "field: not one merged chunk")
    sources = stack.write("sources.txt", [point_line(a[0])])
    for v, (d, e) in enumerate(zip(field["distances"], stack.query("--field", sources))):
        check(close(num(d), float(e[0])), f"field vertex {v}: {d} != {e[0]}")

    path = http.json("POST", f"v1/models/{stack.name}:path", {"a": surface_points(a[:1]), "b": surface_points(b[:1])})
    xyz = [num(x) for x in path["paths"][0]["positions"]["xyz"]]
    lines = stack.query("--paths", stack.write("pair1.txt", [point_line(a[0]) + " " + point_line(b[0])]))
    check(lines[0][:4] == ["#", "path", "0", "length"], f"geodex-query --paths: {lines[0]}")
    check(close(num(path["paths"][0]["length"]), float(lines[0][4])),
          f"path length {path['paths'][0]['length']} != geodex-query's {lines[0][4]}")
    want = lines[1:]
    check(len(xyz) == 3 * len(want), f"path: {len(xyz) // 3} points, geodex-query {len(want)}")
    for i, line in enumerate(want):
        for k in range(3):
            check(close(xyz[3 * i + k], float(line[k])), f"path point {i}: {xyz[3 * i:3 * i + 3]} != {line}")

    mesh = http.json("GET", f"v1/models/{stack.name}/mesh")
    check(len(mesh["positions"]) == 3 * vertices and len(mesh["faces"]) == 3 * faces, "mesh: incomplete")
    located = http.json("POST", f"v1/models/{stack.name}:locate", {"positions": {"xyz": mesh["positions"][:3]}})
    check(num(located["distances"][0]) < 1e-9, f"locate of vertex 0: {located}")
    tri = http.json("GET", f"v1/models/{stack.name}/triangulation")
    m = int(info["numSamples"])
    check(len(tri["sampleVertices"]) == m and len(tri["samplePoints"]["faces"]) == m, "triangulation: samples")
    check(len(tri["triangleCorners"]) == 3 * int(info["numTriangles"]), "triangulation: triangles")
    check(len(tri["vertexTriangles"]) == vertices, "triangulation: vertex triangles")

    # Errors: grpc-gateway's codes and body.
    http.error("GET", "v1/models/nope", 404, 5)
    http.error("POST", "v1/models/nope:distance", 404, 5, body={})
    http.error("POST", f"v1/models/{stack.name}:distance", 400, 3, body={"tolerence": 0.1})
    http.error("POST", f"v1/models/{stack.name}:distance", 400, 3, raw=b"{not json")
    http.error("POST", f"v1/models/{stack.name}:distance", 400, 11,
               body={"a": {"faces": [faces], "weights": [1, 0, 0]}, "b": {"faces": [0], "weights": [1, 0, 0]}})
    http.error("POST", f"v1/models/{stack.name}:distance", 400, 3,
               body={"a": {"faces": [0], "weights": [0.5, 0, 0]}, "b": {"faces": [0], "weights": [1, 0, 0]}})
    http.error("GET", f"v1/models/{stack.name}:distance", 405, 12)
    http.error("GET", "v1/models/x/y/z", 404, 5)
    http.error("POST", f"v1/models/{stack.name}:distance", 413, 8, raw=b" " * 70000)
    # The server wants a token: a gateway started without one gets 401, UNAUTHENTICATED.
    Http(stack.start_web([])).error("GET", "v1/models", 401, 16)
    print(f"web_test: HTTP API ok ({vertices} vertices, 40 pairs, field, path, mesh, triangulation, errors)")


# --- the page in headless Chromium -----------------------------------------------------


def browser_or_skip(launch=True):
    """A headless Chromium under selenium; exits 77 (skipped) when one is missing."""
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    driver = shutil.which("chromedriver")
    try:
        from selenium import webdriver
    except ImportError:
        print("web_test: SKIP: python3-selenium is not installed (deploy/install-deps.sh installs it)")
        sys.exit(SKIP)
    if not chromium or not driver:
        print("web_test: SKIP: chromium or chromedriver is not installed (deploy/install-deps.sh installs them)")
        sys.exit(SKIP)
    if not launch:
        return None
    from selenium.webdriver.chrome.options import Options
    from selenium.webdriver.chrome.service import Service
    options = Options()
    options.binary_location = chromium
    for flag in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--window-size=1280,800",
                 "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist",
                 "--force-device-scale-factor=1"):
        options.add_argument(flag)
    return webdriver.Chrome(service=Service(executable_path=driver), options=options)


def wait_for(driver, script, what, timeout=60):
    """Waits until `script` returns a true value and the page has drawn what it shows."""
    deadline = time.time() + timeout
    while time.time() < deadline:
        value = driver.execute_script(script)
        if value and not driver.execute_script("return window.geodexViewer.state.renderPending"):
            return driver.execute_script(script)
        errors = driver.execute_script("return window.geodexViewer ? window.geodexViewer.state.errors : []")
        check(not errors, f"the page reports errors while waiting for {what}: {errors}")
        time.sleep(0.1)
    fail(f"timed out waiting for {what}")


# Counts the canvas's pixels that differ from the background and its distinct
# colours (test code run in the page; the renderer keeps its drawing buffer).
PIXELS = """
const c = document.getElementById('canvas');
const t = document.createElement('canvas'); t.width = c.width; t.height = c.height;
const ctx = t.getContext('2d'); ctx.drawImage(c, 0, 0);
const d = ctx.getImageData(0, 0, t.width, t.height).data;
let drawn = 0; const colours = new Set();
for (let i = 0; i < d.length; i += 4) {
  if (Math.abs(d[i] - 244) + Math.abs(d[i + 1] - 244) + Math.abs(d[i + 2] - 242) > 6) drawn++;
  colours.add((d[i] >> 3) * 1024 + (d[i + 1] >> 3) * 32 + (d[i + 2] >> 3));
}
return [drawn / (d.length / 4), colours.size];
"""

# Vertices facing the camera, well inside the canvas, as canvas pixels.
CANDIDATES = """
const s = window.geodexViewer.state, out = [];
const c = document.getElementById('canvas').getBoundingClientRect();
for (let v = 0; v < s.numVertices; v += Math.max(1, Math.floor(s.numVertices / 3000))) {
  const p = window.geodexViewer.projectVertex(v);
  if (p.facing && p.x > 0.15 * c.width && p.x < 0.85 * c.width && p.y > 0.15 * c.height && p.y < 0.85 * c.height)
    out.push([v, p.x, p.y]);
}
return [out, c.width, c.height];
"""


# Every visible word of the panel laid out on one line: words whose text
# ranges span more than one line, and whether the panel scrolls sideways
# (test code run in the page).
BROKEN_WORDS = """
const panel = document.getElementById('panel'), broken = [];
let words = 0;
const walker = document.createTreeWalker(panel, NodeFilter.SHOW_TEXT);
for (let n = walker.nextNode(); n; n = walker.nextNode()) {
  const el = n.parentElement;
  if (!el || el.closest('[hidden]') || el.getClientRects().length === 0) continue;  // not shown
  for (const m of n.textContent.matchAll(/\\S+/g)) {
    const range = document.createRange();
    range.setStart(n, m.index);
    range.setEnd(n, m.index + m[0].length);
    const rects = Array.from(range.getClientRects()).filter((r) => r.width > 0 && r.height > 0);
    if (rects.length === 0) continue;
    ++words;
    const lines = new Set(rects.map((r) => Math.round(r.top + r.height / 2)));
    if (lines.size > 1) broken.push(m[0]);
  }
}
const table = document.getElementById('accuracy-table').getBoundingClientRect();
const box = panel.getBoundingClientRect();
return {broken, words, overflow: panel.scrollWidth - panel.clientWidth,
        tableInside: table.right <= box.right && table.left >= box.left,
        chart: document.querySelectorAll('#accuracy-chart svg').length};
"""

# The chart as drawn: its frame and each figure's bin, value and position.
CHART = """
const svg = document.querySelector('#accuracy-chart svg');
const frame = {};
for (const k of ['error-max', 'plot-left', 'plot-right', 'plot-top', 'plot-bottom', 'axis-min', 'axis-max'])
  frame[k] = Number(svg.getAttribute('data-' + k));
const series = Array.from(svg.querySelectorAll('line[data-series]')).map((e) => ({
  series: e.dataset.series, bin: e.dataset.bin, value: e.dataset.value,
  x1: Number(e.getAttribute('x1')), x2: Number(e.getAttribute('x2')), y: Number(e.getAttribute('y1'))}));
const limit = svg.querySelector('path[data-series=limit]');
return {frame, series, limit: limit.dataset.values, limitPath: limit.getAttribute('d')};
"""


def chart_steps(accuracy):
    """What the chart draws (core/index/report_chart.h MakeChartLayout),
    computed here apart: the axis, each series' steps by range key, and the
    limit's steps. Bands by L1000 when the report has them, else bins by L."""
    bands = accuracy.get("bands") or []
    if bands:
        lo, hi = 0.25, 64
        rows = [(b["key"], b["from"], b["to"], {"p99-vertex": b["p99_vertex"],
                                                 "p99-interior": b["p99_interior"]}, b["p99_limit"])
                for b in bands]
    else:
        lo, hi = 0.1, 100
        rows = [(b["key"], b["from_L"], b["to_L"], {"p99": b["p99"], "rms": b["rms"]}, b["p99_limit"])
                for b in accuracy["bins"]]
    series, limit = {}, []
    for key, frm, to, values, lim in rows:
        rng = (max(frm, lo), min(to if to is not None else math.inf, hi))
        for name, v in values.items():
            if v is not None:
                series[(name, key)] = (rng, v)
        if lim is not None:
            limit.append((rng, lim))
    return lo, hi, series, limit


def chart_error_max(series, limit):
    """The chart's top (core/index/report_chart.h ChartErrorMax), computed here apart."""
    top = max([v for _, v in series.values()] + [v for _, v in limit] + [0])
    top = 1.1 * top if top > 0 else 0.01
    decade = 10 ** math.floor(math.log10(top / 7))
    for f in (1, 2, 5, 10):
        step = f * decade
        if top / step <= 7:
            break
    return math.ceil(top / step - 1e-9) * step


def check_table(driver, report, text):
    """The panel's accuracy table holds the report's values and shows the
    text report's cells: its bands by L1000, or the bins of an index of a
    format before them."""
    from selenium.webdriver.common.by import By
    rows = [line for line in text.splitlines() if line.startswith(" " * 18)]
    bands = report["accuracy"].get("bands") or []
    if bands:
        for b in bands:
            cells = driver.find_elements(By.CSS_SELECTOR, f"#accuracy-table tr[data-band='{b['key']}'] td")
            check([float(c.get_attribute("data-value")) if c.get_attribute("data-value") != "null" else None
                   for c in cells[1:3]] == [b["p99_vertex"], b["p99_interior"]],
                  f"the panel's {b['label']} row holds other values than the report")
            row = next((line for line in rows if line[18:].startswith(b["label"] + " ")), None)
            check(row is not None, f"geodex-query --info has no row {b['label']}")
            want = row[18 + len(b["label"]):].split()[:3]
            got = [c.text for c in cells[1:4]]
            check(got == want, f"the panel's {b['label']} row shows {got}, geodex-query --info {want}")
        return
    for b in report["accuracy"]["bins"]:
        cells = driver.find_elements(By.CSS_SELECTOR, f"#accuracy-table tr[data-bin='{b['key']}'] td")
        check([float(c.get_attribute("data-value")) for c in cells[1:4]] == [b["rms"], b["p99"], b["p99_limit"]],
              f"the panel's {b['label']} row holds other values than the report")


def check_report(driver, stack):
    """The panel's report, its table and its chart show the figures of
    geodex-query --info (text and JSON) for the served index, and `geodex
    info` prints the same."""
    from selenium.webdriver.common.by import By
    wait_for(driver, "return window.geodexViewer.state.report", "the build report")
    shown = driver.execute_script("return window.geodexViewer.state.report")
    r = subprocess.run([stack.args.query_bin, stack.index, "--info", "--format", "json"],
                       capture_output=True, text=True)
    check(r.returncode == 0, f"geodex-query --info --format json: {r.stderr}")
    report = json.loads(r.stdout)
    check(shown == report, "the page's report differs from geodex-query --info --format json")
    text = subprocess.run([stack.args.query_bin, stack.index, "--info"], capture_output=True,
                          text=True).stdout
    cli = subprocess.run([stack.args.geodex, "info", "--server", stack.grpc, "--model", stack.name],
                         capture_output=True, text=True)
    check(cli.returncode == 0 and cli.stdout.splitlines()[1:] == text.splitlines()[1:],
          f"geodex info's text differs from geodex-query --info's:\n{cli.stdout}\n{text}")
    cli_json = subprocess.run([stack.args.geodex, "info", "--server", stack.grpc, "--model", stack.name,
                               "--format", "json"], capture_output=True, text=True)
    check(json.loads(cli_json.stdout)["report"] == report, "geodex info --format json's report differs")
    check_table(driver, report, text)
    # The chart: every step at the value and place the frame gives, the
    # limit over the judged ranges only.
    lo, hi, series, limit = chart_steps(report["accuracy"])
    chart = driver.execute_script(CHART)
    frame = chart["frame"]
    check((frame["axis-min"], frame["axis-max"]) == (lo, hi),
          f"the chart's axis runs {frame['axis-min']}-{frame['axis-max']}, not {lo}-{hi}")
    error_max = chart_error_max(series, limit)
    check(abs(frame["error-max"] - error_max) < 1e-12,
          f"the chart's error axis ends at {frame['error-max']}, not {error_max}")

    def x(d):
        return frame["plot-left"] + (math.log10(d) - math.log10(lo)) / (math.log10(hi) - math.log10(lo)) * (
            frame["plot-right"] - frame["plot-left"])

    def y(e):
        return frame["plot-bottom"] - e / frame["error-max"] * (frame["plot-bottom"] - frame["plot-top"])

    drawn = {(s["series"], s["bin"]): s for s in chart["series"]}
    check(set(drawn) == set(series), f"the chart draws {sorted(drawn)}, the report has {sorted(series)}")
    for (name, key), ((a, b), v) in series.items():
        s = drawn[(name, key)]
        check(float(s["value"]) == v, f"the chart's {name} of {key} is {s['value']}, the report's {v}")
        check(abs(s["y"] - y(v)) < 0.01 and abs(s["x1"] - x(a)) < 0.01 and abs(s["x2"] - x(b)) < 0.01,
              f"the chart draws the {name} of {key} at {s}, not at y {y(v)}")
    check([float(v) for v in chart["limit"].split()] == [v for _, v in limit],
          f"the chart's target line is {chart['limit']}")
    if limit:
        start = [float(v) for v in chart["limitPath"].lstrip("M").split()[:2]]
        check(abs(start[0] - x(limit[0][0][0])) < 0.01 and abs(start[1] - y(limit[0][1])) < 0.01,
              f"the target line starts at {start}")
    print(f"web_test: the panel's table and chart show geodex-query --info's figures "
          f"({len(chart['series'])} steps, axis to {frame['error-max']:.4g})")


def check_layout(driver, out_dir, panel_screenshot):
    """At 1000x700 and 1400x900 the panel breaks no word and no number."""
    for width, height in ((1000, 700), (1400, 900)):
        driver.execute_cdp_cmd("Emulation.setDeviceMetricsOverride",
                               {"width": width, "height": height, "deviceScaleFactor": 1, "mobile": False})
        time.sleep(0.5)  # the resize reflows the page and redraws the canvas
        got = driver.execute_script(BROKEN_WORDS)
        check(got["words"] > 50, f"{width}x{height}: only {got['words']} words in the panel")
        check(not got["broken"], f"{width}x{height}: words broken across lines: {got['broken']}")
        check(got["overflow"] <= 0, f"{width}x{height}: the panel scrolls sideways by {got['overflow']} px")
        check(got["tableInside"] and got["chart"] == 1, f"{width}x{height}: accuracy table or chart missing: {got}")
        driver.execute_script("document.getElementById('report').scrollIntoView()")
        path = os.path.join(out_dir, f"web_viewer_{width}x{height}.png")
        driver.save_screenshot(path)
        if panel_screenshot and width == 1000:
            driver.save_screenshot(panel_screenshot)
        print(f"web_test: {width}x{height}: {got['words']} words, none broken; {path}")
    driver.execute_cdp_cmd("Emulation.clearDeviceMetricsOverride", {})


def test_browser(stack, out_dir, screenshot, panel_screenshot=None):
    driver = browser_or_skip()
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys
    start = time.time()
    try:
        driver.get(f"{stack.url}?model={stack.name}")
        wait_for(driver, "return window.geodexViewer && window.geodexViewer.state.meshDrawn && "
                         "window.geodexViewer.state.frames > 0", "the mesh to be drawn")
        drawn, colours = driver.execute_script(PIXELS)
        check(drawn > 0.05 and colours > 20, f"WebGL drew nothing visible: {drawn:.3f} of the canvas, {colours} colours")
        check_report(driver, stack)
        candidates, width, height = driver.execute_script(CANDIDATES)
        check(len(candidates) >= 3, f"only {len(candidates)} vertices in view")
        candidates.sort(key=lambda c: c[1])
        a, b, h = candidates[0], candidates[-1], candidates[len(candidates) // 2]
        canvas = driver.find_element(By.ID, "canvas")

        def at(p):  # selenium offsets are from the element's centre
            return ActionChains(driver).move_to_element_with_offset(canvas, int(p[1] - width / 2), int(p[2] - height / 2))

        at(a).click().perform()
        wait_for(driver, "return window.geodexViewer.state.fieldReady", "the distance field")
        _, field_colours = driver.execute_script(PIXELS)
        check(field_colours > colours, f"the field did not colour the mesh ({field_colours} <= {colours} colours)")
        at(h).perform()
        hover = wait_for(driver, "return window.geodexViewer.state.hover", "the distance under the mouse")
        at(b).key_down(Keys.SHIFT).click().key_up(Keys.SHIFT).perform()
        wait_for(driver, "return window.geodexViewer.state.pair && window.geodexViewer.state.path",
                 "the target's distance and path")
        s = driver.execute_script("return window.geodexViewer.state")
        pair = driver.find_element(By.ID, "pair")
        shown = float(pair.get_attribute("data-distance"))
        check(shown == s["pair"]["distance"], "data-distance differs from the page's state")
        check(pair.text.split()[0] == f"{shown:.{len(pair.text.split()[0].split('.')[-1])}f}",
              f"the shown text {pair.text!r} is not the distance {shown}")
        lines = [point_line(s["source"]) + " " + point_line(s["target"]),
                 point_line(s["source"]) + " " + point_line(hover["point"])]
        expected = stack.query("--pairs", stack.write("page_pairs.txt", lines), "--error-bounds")
        check(close(shown, float(expected[0][0])),
              f"the page shows {shown!r}, geodex-query says {expected[0][0]} for {lines[0]}")
        bound = pair.get_attribute("data-bound")
        check(bound and close(float(bound), float(expected[0][1])), f"bound {bound} != {expected[0][1]}")
        check(close(hover["distance"], float(expected[1][0])),
              f"hover: the page shows {hover['distance']!r}, geodex-query says {expected[1][0]}")
        check(s["path"]["points"] >= 2 and s["path"]["length"] >= shown * 0.9, f"path {s['path']}")
        print(f"web_test: page distance {shown!r} == geodex-query {expected[0][0]} "
              f"(faces {s['source']['face']} -> {s['target']['face']}); hover {hover['distance']!r} == {expected[1][0]}")
        os.makedirs(out_dir, exist_ok=True)
        driver.execute_script("document.body.style.cursor = 'default'")
        driver.save_screenshot(os.path.join(out_dir, "web_viewer.png"))
        if screenshot:
            driver.save_screenshot(screenshot)

        driver.find_element(By.ID, "show-triangulation").click()
        wait_for(driver, "return window.geodexViewer.state.triangulationShown", "the triangulation")
        s = driver.execute_script("return window.geodexViewer.state")
        check(s["numSamples"] == int(stack.info["numSamples"]), f"{s['numSamples']} samples drawn")
        driver.save_screenshot(os.path.join(out_dir, "web_viewer_triangulation.png"))
        check_layout(driver, out_dir, panel_screenshot)
        print(f"web_test: browser ok in {time.time() - start:.1f} s; screenshots in {out_dir}")
    finally:
        driver.quit()


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    for flag in ("--geodex", "--server-bin", "--build-bin", "--query-bin"):
        parser.add_argument(flag, required=True)
    parser.add_argument("--out", required=True, help="directory for screenshots and the work files")
    parser.add_argument("--browser", action="store_true")
    parser.add_argument("--mesh", default="builtin:torus")
    parser.add_argument("--model-name", default="torus")
    parser.add_argument("--samples", type=int, default=100)
    parser.add_argument("--screenshot", help="also save the field screenshot here")
    parser.add_argument("--panel-screenshot", help="also save the 1000x700 screenshot (the panel's layout) here")
    args = parser.parse_args()
    if args.browser:
        browser_or_skip(launch=False)  # skip before building anything
    os.makedirs(args.out, exist_ok=True)
    work = tempfile.mkdtemp(prefix="web_test_", dir=args.out)
    stack = Stack(args, work, token=not args.browser)
    try:
        if args.browser:
            test_browser(stack, args.out, args.screenshot, args.panel_screenshot)
        else:
            test_http(stack)
    finally:
        stack.stop()
    shutil.rmtree(work, ignore_errors=True)
    print("web_test: ok")


if __name__ == "__main__":
    main()
