// The geodex viewer: a client of `geodex web`'s HTTP/JSON gateway
// (client/cli/web/web_gateway.h), drawn with three.js r111 (global THREE).
//
// Click: the distance field from that point (colours and isolines, one
// DistanceField call). Mouse move: the distance to the point under the mouse
// (one Distance call in flight at a time; the latest position waits). Shift-
// click: the target; its distance (with its error bound when the index is
// calibrated) and the geodesic path. The triangulation toggle draws the
// index's geodesic triangles as patches with their borders and samples.
//
// Test hook: window.geodexViewer.state holds what the page shows and the
// exact surface points it sent (face and barycentric weights), so that a
// browser test can compare the shown distances with geodex-query.
'use strict';

(function () {
  const $ = (id) => document.getElementById(id);
  // The report's chart and percentages (report_chart.js, loaded first).
  const { formatPercent, formatMiB, drawChart } = window.geodexReportChart;
  const state = {
    model: null,          // name
    version: 0,           // the mesh's version; every later call is pinned to it
    meshDrawn: false,
    numVertices: 0,
    numFaces: 0,
    source: null,         // {face, weights}
    fieldReady: false,
    maxDistance: 0,
    hover: null,          // {point, distance, bound}
    target: null,
    pair: null,           // {distance, bound}
    path: null,           // {length, points}
    triangulationShown: false,
    numSamples: 0,
    frames: 0,
    // A frame is requested and not drawn yet: what the state says is on the
    // canvas only once this is false (state changes and their render
    // requests happen in the same task).
    renderPending: false,
    errors: [],
    timings: {},          // milliseconds of the last call of each kind, for diagnosis
    report: null,         // the model's build report (its JSON, parsed)
  };
  window.geodexViewer = { state, formatPercent };

  // --- the HTTP API -------------------------------------------------------------

  async function api(method, path, body) {
    const start = performance.now();
    const kind = path.replace(/^\/v1\/models\/[^/:?]*/, '').replace(/\?.*/, '') || 'models';
    const response = await fetch(path, {
      method,
      headers: body ? { 'Content-Type': 'application/json' } : {},
      body: body ? JSON.stringify(body) : undefined,
    });
    const text = await response.text();
    let json;
    try {
      json = JSON.parse(text);
    } catch (e) {
      throw new Error(`HTTP ${response.status}: ${text.slice(0, 200)}`);
    }
    state.timings[kind] = Math.round(performance.now() - start);
    if (!response.ok) {
      const error = new Error(json.message || `HTTP ${response.status}`);
      error.code = json.code;
      throw error;
    }
    return json;
  }
  // protobuf's JSON mapping prints int64 and non-finite doubles as strings.
  const num = (x) => (typeof x === 'string' ? Number(x) : x === undefined ? 0 : x);
  const modelPath = (suffix) => `/v1/models/${encodeURIComponent(state.model)}${suffix}`;
  const pinned = () => ({ name: state.model, version: String(state.version) });
  const pointsOf = (...points) => ({
    faces: points.map((p) => p.face),
    weights: [].concat(...points.map((p) => p.weights)),
  });

  function setStatus(text, kind) {
    const s = $('status');
    s.textContent = text;
    s.dataset.state = kind;
  }
  function reportError(what, error) {
    state.errors.push(`${what}: ${error.message}`);
    setStatus(`${what}: ${error.message}`, 'error');
  }

  function formatDistance(d, bound) {
    if (!Number.isFinite(d)) return 'unreachable';
    const digits = state.maxDistance > 0 ? Math.max(4, 4 - Math.floor(Math.log10(state.maxDistance))) : 6;
    let text = d.toFixed(Math.min(digits, 12));
    if (bound !== undefined && bound !== null && bound > 0) text += ` ± ${bound.toPrecision(2)}`;
    return text;
  }

  // --- three.js scene -----------------------------------------------------------

  const canvas = $('canvas');
  const renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0xf4f4f2);
  const camera = new THREE.PerspectiveCamera(35, 1, 0.01, 100);
  const controls = new THREE.OrbitControls(camera, canvas);
  controls.enableDamping = false;
  controls.addEventListener('change', requestRender);

  // Viridis as a polynomial fit (the same in the shader and the legend).
  const VIRIDIS = [
    [0.2777273272234177, 0.005407344544966578, 0.3340998053353061],
    [0.1050930431085774, 1.404613529898575, 1.384590162594685],
    [-0.3308618287255563, 0.214847559468213, 0.09509516302823659],
    [-4.634230498983486, -5.799100973351585, -19.33244095627987],
    [6.228269936347081, 14.17993336680509, 56.69055260068105],
    [4.776384997670288, -13.74514537774601, -65.35303263337234],
    [-5.435455855934631, 4.645852612178535, 26.3124352495832],
  ];
  const glslVec = (c) => `vec3(${c.map((x) => x.toFixed(12)).join(',')})`;

  const material = new THREE.ShaderMaterial({
    uniforms: {
      mode: { value: 0 },            // 0 plain, 1 distance field, 2 triangulation patches
      maxDistance: { value: 1 },
      spacing: { value: 0.1 },
      isolines: { value: 1 },
    },
    vertexShader: `
      attribute float distance;
      attribute vec3 patchColor;
      varying float vDistance;
      varying vec3 vPatch;
      varying vec3 vNormal;
      varying vec3 vView;
      void main() {
        vDistance = distance;
        vPatch = patchColor;
        vNormal = normalize(normalMatrix * normal);
        vec4 mv = modelViewMatrix * vec4(position, 1.0);
        vView = -mv.xyz;
        gl_Position = projectionMatrix * mv;
      }`,
    fragmentShader: `
      uniform int mode;
      uniform float maxDistance;
      uniform float spacing;
      uniform float isolines;
      varying float vDistance;
      varying vec3 vPatch;
      varying vec3 vNormal;
      varying vec3 vView;
      vec3 viridis(float t) {
        t = clamp(t, 0.0, 1.0);
        return ${glslVec(VIRIDIS[0])} + t * (${glslVec(VIRIDIS[1])} + t * (${glslVec(VIRIDIS[2])} +
               t * (${glslVec(VIRIDIS[3])} + t * (${glslVec(VIRIDIS[4])} + t * (${glslVec(VIRIDIS[5])} +
               t * ${glslVec(VIRIDIS[6])})))));
      }
      void main() {
        vec3 n = normalize(vNormal);
        if (!gl_FrontFacing) n = -n;
        vec3 base = vec3(0.80, 0.78, 0.74);
        if (mode == 1) {
          if (vDistance < 0.0) {
            base = vec3(0.55);  // unreachable
          } else {
            base = viridis(vDistance / maxDistance);
            if (isolines > 0.5) {
              float f = vDistance / spacing;
              float w = max(fwidth(f), 1e-4);
              float line = 1.0 - smoothstep(0.5 * w, 1.5 * w, abs(fract(f - 0.5) - 0.5));
              base = mix(base, vec3(0.04), 0.8 * line);
            }
          }
        } else if (mode == 2) {
          base = vPatch;
        }
        vec3 l = normalize(vec3(0.35, 0.55, 1.0));  // a light near the eye
        vec3 v = normalize(vView);
        float diffuse = max(dot(n, l), 0.0);
        float specular = pow(max(dot(n, normalize(l + v)), 0.0), 48.0) * 0.22;
        gl_FragColor = vec4(base * (0.32 + 0.68 * diffuse) + vec3(specular), 1.0);
      }`,
    side: THREE.DoubleSide,
    polygonOffset: true,  // lines (path, borders) drawn on the surface stay in front
    polygonOffsetFactor: 1,
    polygonOffsetUnits: 1,
    extensions: { derivatives: true },
  });

  let mesh = null;          // THREE.Mesh
  let overlay = new THREE.Group();  // markers, path, triangulation
  scene.add(overlay);
  let positions = null;     // Float32Array, 3 per vertex
  let faces = null;         // Uint32Array, 3 per face
  let radius = 1;
  let triangulationGroup = null;
  function requestRender() {
    if (state.renderPending) return;
    state.renderPending = true;
    requestAnimationFrame(() => {
      state.renderPending = false;
      const start = performance.now();
      renderer.render(scene, camera);
      state.timings.render = Math.round(performance.now() - start);
      state.frames++;
    });
  }

  function resize() {
    const view = $('view');
    const w = Math.max(1, view.clientWidth), h = Math.max(1, view.clientHeight);
    renderer.setSize(w, h, false);
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
    requestRender();
  }
  window.addEventListener('resize', resize);

  function clearGroup(group) {
    for (const child of [...group.children]) {
      group.remove(child);
      if (child.geometry) child.geometry.dispose();
      if (child.material) child.material.dispose();
    }
  }

  // --- loading a model ----------------------------------------------------------

  async function loadModels() {
    const list = await api('GET', '/v1/models');
    const select = $('model');
    select.innerHTML = '';
    const models = list.models || [];
    for (const m of models) {
      const option = document.createElement('option');
      option.value = m.name;
      option.textContent = `${m.name} (${m.state === 'SERVING' ? num(m.numVertices) + ' vertices' : m.state})`;
      select.appendChild(option);
    }
    if (models.length === 0) {
      setStatus('The server has no models.', 'error');
      return;
    }
    const wanted = new URLSearchParams(location.search).get('model');
    const serving = models.find((m) => m.state === 'SERVING');
    const chosen = models.find((m) => m.name === wanted) || serving || models[0];
    select.value = chosen.name;
    await loadModel(chosen.name);
  }

  async function loadModel(name) {
    Object.assign(state, {
      model: name, meshDrawn: false, source: null, fieldReady: false, hover: null, target: null,
      pair: null, path: null, triangulationShown: false, maxDistance: 0,
    });
    $('show-triangulation').checked = false;
    resetReadout();
    setStatus(`Loading ${name}…`, 'loading');
    const info = await api('GET', modelPath(''));
    showReport(info);
    const chunk = await api('GET', `${modelPath('/mesh')}?version=${num(info.version)}`);
    state.version = num(chunk.version);
    state.numVertices = num(chunk.numVertices);
    state.numFaces = num(chunk.numFaces);
    const start = performance.now();
    positions = Float32Array.from(chunk.positions || []);
    faces = Uint32Array.from(chunk.faces || []);
    buildMesh();
    state.timings.build = Math.round(performance.now() - start);
    setStatus(`${name} v${state.version}: ${state.numVertices} vertices, ${state.numFaces} faces`, 'ready');
    state.meshDrawn = true;
  }

  function buildMesh() {
    if (mesh) {
      scene.remove(mesh);
      mesh.geometry.dispose();
    }
    clearGroup(overlay);
    triangulationGroup = null;
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
    geometry.setIndex(new THREE.BufferAttribute(faces, 1));
    geometry.computeVertexNormals();
    geometry.setAttribute('distance', new THREE.BufferAttribute(new Float32Array(state.numVertices), 1));
    geometry.setAttribute('patchColor', new THREE.BufferAttribute(new Float32Array(3 * state.numVertices), 3));
    geometry.computeBoundingSphere();
    mesh = new THREE.Mesh(geometry, material);
    scene.add(mesh);
    material.uniforms.mode.value = 0;
    const sphere = geometry.boundingSphere;
    radius = sphere.radius || 1;
    controls.target.copy(sphere.center);
    camera.near = radius / 100;
    camera.far = radius * 100;
    camera.position.copy(sphere.center).add(new THREE.Vector3(0.35, 0.45, 1).normalize().multiplyScalar(radius * 3.2));
    camera.updateProjectionMatrix();
    controls.update();
    resize();
  }

  // --- the build report -----------------------------------------------------------
  // The server's report JSON (ModelInfo.reportJson; keys in core/index/README.md),
  // laid out as geodex-query --info lays it out: the same figures, formatted
  // the same way (formatPercent is the core's FormatPercent).

  function addRows(table, rows) {
    for (const [k, v] of rows) {
      const tr = table.insertRow();
      tr.insertCell().textContent = k;
      tr.insertCell().textContent = String(v);
    }
  }

  function showReport(info) {
    const facts = $('report-table'), raw = $('report-raw'), accuracyTable = $('accuracy-table');
    facts.innerHTML = raw.innerHTML = accuracyTable.innerHTML = '';
    $('accuracy-chart').innerHTML = '';
    $('target-verdict').textContent = '';
    state.report = info.reportJson ? JSON.parse(info.reportJson) : null;
    const r = state.report;
    const rows = [['model', `${info.name} v${num(info.version)} (${info.state})`]];
    if (r) {
      const vertexFaces = `${r.mesh.vertices} vertices, ${r.mesh.faces} faces`;
      rows.push(['mesh', vertexFaces]);
      if (r.mesh.index_vertices !== r.mesh.vertices || r.mesh.index_faces !== r.mesh.faces) {
        rows.push(['answered on', `${r.mesh.index_vertices} vertices, ${r.mesh.index_faces} faces`]);
      }
      rows.push(['repairs', r.mesh.repairs]);
      rows.push(['split', r.mesh.split_midpoints ? `${r.mesh.split_midpoints} midpoints` : 'none']);
      rows.push(['samples', `m = ${r.samples.final} (${r.samples.requested} requested)`]);
      rows.push(['triangles', `${r.triangles} geodesic triangles`]);
      const largest = r.size.sections[0];
      rows.push(['index size', `${formatMiB(r.size.bytes)}${largest ? `, ${largest.label} ${formatMiB(largest.bytes)}` : ''}`]);
      rows.push(['error bounds', r.error_bounds ? 'yes (calibrated)' : 'no']);
      rows.push(['builder', `${r.builder}, format ${r.format}`]);
      $('target-verdict').textContent = `Error target: ${r.target.verdict}.`;
    } else {
      rows.push(['vertices / faces', `${num(info.numVertices)} / ${num(info.numFaces)}`]);
      rows.push(['samples', `m = ${num(info.numSamples)}`]);
    }
    addRows(facts, rows);
    // Every stored key = value, for the curious (closed by default).
    const report = info.buildReport || {};
    addRows(raw, Object.keys(report).sort().map((k) => [k, report[k]]));
    if (!r || !r.accuracy) {
      $('accuracy').hidden = true;
      return;
    }
    $('accuracy').hidden = false;
    const a = r.accuracy;
    const head = accuracyTable.createTHead().insertRow();
    const body = accuracyTable.createTBody();
    if (a.bands && a.bands.length > 0) {
      // The text report's table: p99 by L1000 band, vertex and interior
      // pairs, the bands the target judges, how the default mode answers.
      $('accuracy-note').textContent =
        `p99 relative error of the default answer over ${a.pairs} held-out pairs, by distance in ` +
        `L1000 = ${Number(a.band_unit.toPrecision(4))} (the spacing of 1000 samples on this surface); ` +
        `answers are walked or exact below ${Number(a.refined_below.toPrecision(3))} L1000, O(1) above.`;
      for (const h of ['L1000', 'vertex', 'interior', 'target']) head.appendChild(document.createElement('th')).textContent = h;
      for (const b of a.bands) {
        const tr = body.insertRow();
        tr.dataset.band = b.key;
        tr.insertCell().textContent = b.label;
        for (const key of ['p99_vertex', 'p99_interior']) {
          const td = tr.insertCell();
          td.textContent = formatPercent(b[key]);
          td.dataset.value = String(b[key]);
          if (b.p99_limit !== null && b[key] > b.p99_limit) td.className = 'over';
        }
        tr.insertCell().textContent = b.p99_limit === null ? '-' : 'judged';
      }
    } else {
      // An index of a format before the bands: its bins by its own L.
      $('accuracy-note').textContent =
        `Relative error of the default answer over ${a.pairs} held-out pairs; L = ${Number(a.scale_length.toPrecision(4))}.`;
      for (const h of ['distance', 'RMS', 'p99', 'p99 limit']) head.appendChild(document.createElement('th')).textContent = h;
      for (const b of a.bins) {
        const tr = body.insertRow();
        tr.dataset.bin = b.key;
        tr.insertCell().textContent = b.label;
        for (const key of ['rms', 'p99', 'p99_limit']) {
          const td = tr.insertCell();
          td.textContent = formatPercent(b[key]);
          td.dataset.value = String(b[key]);
          if (key === 'p99' && b.p99 > b.p99_limit) td.className = 'over';
        }
      }
    }
    drawChart(a, r.target);
  }

  function resetReadout() {
    $('source').textContent = 'click the surface';
    setDistance($('hover'), null, '–');
    setDistance($('pair'), null, 'shift-click');
    $('path-length').textContent = '–';
    $('path-length').dataset.length = '';
    drawLegend();
  }

  // Shows a distance; its exact value (shortest round-trip decimal) goes in
  // data-distance, the bound in data-bound.
  function setDistance(element, value, text) {
    element.textContent = text;
    element.dataset.distance = value === null ? '' : String(value.distance);
    element.dataset.bound = value === null || value.bound === undefined ? '' : String(value.bound);
  }

  // --- picking --------------------------------------------------------------------

  const raycaster = new THREE.Raycaster();
  function pick(clientX, clientY) {
    if (!mesh) return null;
    const rect = canvas.getBoundingClientRect();
    const ndc = new THREE.Vector2(((clientX - rect.left) / rect.width) * 2 - 1,
                                  -((clientY - rect.top) / rect.height) * 2 + 1);
    raycaster.setFromCamera(ndc, camera);
    const start = performance.now();
    const hits = raycaster.intersectObject(mesh);
    state.timings.pick = Math.round(performance.now() - start);
    if (hits.length === 0) return null;
    const hit = hits[0];
    const f = hit.faceIndex;
    const corner = (k) => new THREE.Vector3().fromArray(positions, 3 * faces[3 * f + k]);
    const bary = new THREE.Triangle(corner(0), corner(1), corner(2)).getBarycoord(hit.point, new THREE.Vector3());
    // The hit lies in the face up to rounding: clamp, then make the weights sum to 1.
    let w = [bary.x, bary.y, bary.z].map((x) => (Number.isFinite(x) ? Math.max(0, x) : 0));
    const sum = w[0] + w[1] + w[2];
    w = sum > 0 ? w.map((x) => x / sum) : [1, 0, 0];
    return { face: f, weights: w, position: hit.point.clone() };
  }

  function marker(position, color) {
    const m = new THREE.Mesh(new THREE.SphereBufferGeometry(radius * 0.018, 16, 12),
                             new THREE.MeshBasicMaterial({ color }));
    m.position.copy(position);
    return m;
  }
  let sourceMarker = null, targetMarker = null, pathLine = null;
  function replace(old, replacement) {
    if (old) {
      overlay.remove(old);
      old.geometry.dispose();
      old.material.dispose();
    }
    if (replacement) overlay.add(replacement);
    requestRender();
    return replacement;
  }

  // --- the distance field, hover distance, target and path ------------------------

  function niceStep(x) {
    const p = Math.pow(10, Math.floor(Math.log10(x)));
    for (const m of [1, 2, 2.5, 5, 10]) if (m * p >= x) return m * p;
    return 10 * p;
  }

  async function setSource(point) {
    const source = { face: point.face, weights: point.weights };
    state.source = source;
    state.fieldReady = false;
    state.target = null;
    state.pair = null;
    state.path = null;
    state.hover = null;
    sourceMarker = replace(sourceMarker, marker(point.position, 0xe8463a));
    targetMarker = replace(targetMarker, null);
    pathLine = replace(pathLine, null);
    setDistance($('pair'), null, 'shift-click');
    $('path-length').textContent = '–';
    $('source').textContent = `face ${point.face}`;
    setStatus('Computing the distance field…', 'loading');
    const field = await api('POST', modelPath(':field'), { model: pinned(), sources: pointsOf(point) });
    if (state.source !== source) return;  // superseded by another click or model
    const d = (field.distances || []).map(num);
    const attr = mesh.geometry.getAttribute('distance');
    let max = 0;
    for (let i = 0; i < d.length; i++) {
      const finite = Number.isFinite(d[i]);
      attr.array[i] = finite ? d[i] : -1;
      if (finite && d[i] > max) max = d[i];
    }
    attr.needsUpdate = true;
    state.maxDistance = max;
    material.uniforms.maxDistance.value = max > 0 ? max : 1;
    material.uniforms.spacing.value = max > 0 ? niceStep(max / 16) : 1;
    if (!state.triangulationShown) material.uniforms.mode.value = 1;
    state.fieldReady = true;
    drawLegend();
    setStatus(`Distance field from face ${point.face} (max ${formatDistance(max)})`, 'ready');
    requestRender();
  }

  let hoverInFlight = false, hoverWaiting = null, boundsAvailable = true;
  async function distance(a, b) {
    try {
      const r = await api('POST', modelPath(':distance'), { model: pinned(), a: pointsOf(a), b: pointsOf(b), errorBounds: boundsAvailable });
      return { distance: num(r.distances[0]), bound: boundsAvailable ? num(r.bounds[0]) : undefined };
    } catch (e) {
      // An index without accuracy calibration has no bounds: ask again without.
      if (boundsAvailable && e.code === 9 /* FAILED_PRECONDITION */) {
        boundsAvailable = false;
        return distance(a, b);
      }
      throw e;
    }
  }

  async function hoverDistance(point) {
    if (hoverInFlight) {
      hoverWaiting = point;  // only the latest position is asked next
      return;
    }
    hoverInFlight = true;
    try {
      const source = state.source;
      const d = await distance(source, point);
      if (state.source === source) {
        state.hover = { point: { face: point.face, weights: point.weights }, distance: d.distance, bound: d.bound };
        setDistance($('hover'), d, formatDistance(d.distance, d.bound));
      }
    } catch (e) {
      reportError('distance', e);
    } finally {
      hoverInFlight = false;
      if (hoverWaiting && state.source) {
        const next = hoverWaiting;
        hoverWaiting = null;
        hoverDistance(next);
      }
    }
  }

  async function setTarget(point) {
    const target = { face: point.face, weights: point.weights };
    state.target = target;
    state.pair = null;
    state.path = null;
    targetMarker = replace(targetMarker, marker(point.position, 0x2f7fe0));
    setDistance($('pair'), null, '…');
    const [d, paths] = await Promise.all([
      distance(state.source, point),
      api('POST', modelPath(':path'), { model: pinned(), a: pointsOf(state.source), b: pointsOf(point) }),
    ]);
    if (state.target !== target) return;  // superseded
    state.pair = d;
    setDistance($('pair'), d, formatDistance(d.distance, d.bound));
    const polyline = paths.paths[0];
    const xyz = ((polyline.positions || {}).xyz || []).map(num);
    const length = num(polyline.length);
    state.path = { length, points: xyz.length / 3 };
    $('path-length').textContent = formatDistance(length);
    $('path-length').dataset.length = String(length);
    if (xyz.length >= 6) {
      // A thin tube: WebGL draws lines one pixel wide whatever linewidth says.
      const n = xyz.length / 3;
      const curve = new THREE.Curve();
      curve.getPoint = (t, target = new THREE.Vector3()) => {
        const x = Math.min(t, 1) * (n - 1), i = Math.min(Math.floor(x), n - 2), f = x - i;
        return target.set(xyz[3 * i] + f * (xyz[3 * i + 3] - xyz[3 * i]),
                          xyz[3 * i + 1] + f * (xyz[3 * i + 4] - xyz[3 * i + 1]),
                          xyz[3 * i + 2] + f * (xyz[3 * i + 5] - xyz[3 * i + 2]));
      };
      const tube = new THREE.TubeBufferGeometry(curve, Math.min(4 * n, 4000), radius * 0.005, 6, false);
      pathLine = replace(pathLine, new THREE.Mesh(tube, new THREE.MeshBasicMaterial({ color: 0xff2d55 })));
    } else {
      pathLine = replace(pathLine, null);
    }
  }

  // --- the geodesic triangulation -------------------------------------------------

  function patchColor(t, out, i) {
    if (t < 0) {
      out[3 * i] = out[3 * i + 1] = out[3 * i + 2] = 0.6;
      return;
    }
    const c = new THREE.Color().setHSL((t * 0.6180339887) % 1, 0.55, 0.62);
    out[3 * i] = c.r;
    out[3 * i + 1] = c.g;
    out[3 * i + 2] = c.b;
  }

  async function showTriangulation(show) {
    state.triangulationShown = false;
    if (!show) {
      if (triangulationGroup) triangulationGroup.visible = false;
      material.uniforms.mode.value = state.fieldReady ? 1 : 0;
      drawLegend();
      requestRender();
      return;
    }
    if (!triangulationGroup) {
      setStatus('Loading the geodesic triangulation…', 'loading');
      const t = await api('GET', `${modelPath('/triangulation')}?version=${state.version}`);
      const tri = t.vertexTriangles || [];
      const colors = mesh.geometry.getAttribute('patchColor');
      for (let v = 0; v < tri.length; v++) patchColor(tri[v], colors.array, v);
      colors.needsUpdate = true;
      // Patch borders: in each face whose vertices lie in different geodesic
      // triangles, join the midpoints of the edges that cross a border.
      const border = [];
      const p = (v, k) => positions[3 * v + k];
      for (let f = 0; f < faces.length / 3; f++) {
        const v = [faces[3 * f], faces[3 * f + 1], faces[3 * f + 2]];
        const t3 = v.map((x) => tri[x]);
        if (t3[0] === t3[1] && t3[1] === t3[2]) continue;
        const mids = [];
        for (let k = 0; k < 3; k++) {
          const a = v[k], b = v[(k + 1) % 3];
          if (tri[a] !== tri[b]) mids.push([0, 1, 2].map((c) => 0.5 * (p(a, c) + p(b, c))));
        }
        if (mids.length === 2) {
          border.push(...mids[0], ...mids[1]);
        } else if (mids.length === 3) {
          const centre = [0, 1, 2].map((c) => (p(v[0], c) + p(v[1], c) + p(v[2], c)) / 3);
          for (const m of mids) border.push(...centre, ...m);
        }
      }
      triangulationGroup = new THREE.Group();
      const borderGeometry = new THREE.BufferGeometry();
      borderGeometry.setAttribute('position', new THREE.BufferAttribute(Float32Array.from(border), 3));
      triangulationGroup.add(new THREE.LineSegments(borderGeometry, new THREE.LineBasicMaterial({ color: 0x1d1d1d })));
      const samples = ((t.samplePositions || {}).xyz || []).map(num);
      const sampleGeometry = new THREE.BufferGeometry();
      sampleGeometry.setAttribute('position', new THREE.BufferAttribute(Float32Array.from(samples), 3));
      triangulationGroup.add(new THREE.Points(sampleGeometry,
          new THREE.PointsMaterial({ color: 0x111111, size: 6, sizeAttenuation: false })));
      overlay.add(triangulationGroup);
      state.numSamples = samples.length / 3;
      state.numTriangles = (t.triangleCorners || []).length / 3;
    }
    triangulationGroup.visible = true;
    material.uniforms.mode.value = 2;
    state.triangulationShown = true;
    drawLegend();
    setStatus(`${state.numSamples} samples, ${state.numTriangles} geodesic triangles`, 'ready');
    requestRender();
  }

  // --- legend ---------------------------------------------------------------------

  function drawLegend() {
    const bar = $('legend-bar');
    const ctx = bar.getContext('2d');
    for (let x = 0; x < bar.width; x++) {
      const t = x / (bar.width - 1);
      const c = [0, 1, 2].map((k) => {
        let v = VIRIDIS[6][k];
        for (let i = 5; i >= 0; i--) v = VIRIDIS[i][k] + t * v;
        return Math.round(255 * Math.min(1, Math.max(0, v)));
      });
      ctx.fillStyle = `rgb(${c[0]},${c[1]},${c[2]})`;
      ctx.fillRect(x, 0, 1, bar.height);
    }
    const note = $('legend-note');
    bar.style.visibility = state.triangulationShown ? 'hidden' : 'visible';
    $('legend-min').textContent = state.triangulationShown ? '' : '0';
    if (state.triangulationShown) {
      $('legend-max').textContent = '';
      note.textContent = `Patches: the ${state.numTriangles} geodesic triangles over ${state.numSamples} samples (dots); lines: their borders.`;
    } else if (state.fieldReady) {
      $('legend-max').textContent = formatDistance(state.maxDistance);
      note.textContent = `Geodesic distance from the source${$('show-isolines').checked ? `; isolines every ${material.uniforms.spacing.value}` : ''}. Grey: unreachable.`;
    } else {
      $('legend-max').textContent = '–';
      note.textContent = 'Click the surface for the distance field.';
    }
  }

  // --- events ---------------------------------------------------------------------

  let down = null;
  canvas.addEventListener('mousedown', (e) => {
    if (e.button === 0) down = { x: e.clientX, y: e.clientY };
  });
  canvas.addEventListener('mouseup', (e) => {
    if (e.button !== 0 || !down) return;
    const moved = Math.hypot(e.clientX - down.x, e.clientY - down.y);
    down = null;
    if (moved > 4 || !state.meshDrawn) return;  // a drag rotates; only a click picks
    const point = pick(e.clientX, e.clientY);
    if (!point) return;
    if (e.shiftKey && state.source) {
      setTarget(point).catch((err) => reportError('path', err));
    } else {
      setSource(point).catch((err) => reportError('distance field', err));
    }
  });
  let hoverFrame = null;
  canvas.addEventListener('mousemove', (e) => {
    if (!state.source || down) return;
    // At most one pick per frame: raycasting a large mesh is not free.
    hoverFrame = { x: e.clientX, y: e.clientY };
    requestAnimationFrame(() => {
      if (!hoverFrame) return;
      const point = pick(hoverFrame.x, hoverFrame.y);
      hoverFrame = null;
      if (point && state.source) hoverDistance(point);
    });
  });
  $('model').addEventListener('change', (e) => {
    loadModel(e.target.value).catch((err) => reportError('model', err));
  });
  $('show-triangulation').addEventListener('change', (e) => {
    showTriangulation(e.target.checked).catch((err) => reportError('triangulation', err));
  });
  $('show-isolines').addEventListener('change', (e) => {
    material.uniforms.isolines.value = e.target.checked ? 1 : 0;
    drawLegend();
    requestRender();
  });

  // Test hook: where vertex v appears on the canvas, in CSS pixels from the
  // canvas's top-left corner, and whether it faces the camera.
  window.geodexViewer.projectVertex = (v) => {
    const p = new THREE.Vector3().fromArray(positions, 3 * v);
    const n = new THREE.Vector3().fromArray(mesh.geometry.getAttribute('normal').array, 3 * v);
    const facing = n.dot(camera.position.clone().sub(p)) > 0;
    p.project(camera);
    const rect = canvas.getBoundingClientRect();
    return { x: (p.x + 1) / 2 * rect.width, y: (1 - p.y) / 2 * rect.height, facing };
  };

  resize();
  drawLegend();
  loadModels().catch((err) => reportError('models', err));
})();
