// adamesh view: the page script, bundled with three.js by esbuild at build time
// (viewer/CMakeLists.txt) and inlined into the HTML that `adamesh view` writes.
//
// Data (the <script id="adamesh-data"> JSON, written by apps/adamesh/cmd_view.cpp): a base64
// little-endian blob and its layout. For a hierarchy (.amh): vertex positions (base vertices,
// then one per split), base triangles, per split the edge (a, b) it bisects and its level and
// error bound. Every cut is computed here from that split list, as the library does: split s
// bisects edge (a, b) with vertex V0+s, replacing each triangle (a, b, c) by (a, m, c) and
// (m, b, c). One replay gives every triangle's birth and death split, so a prefix of k splits is
// {t : birth(t) < k ≤ death(t)} and a uniform level K is the same test on the split levels.
import * as THREE from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';

const data = JSON.parse(document.getElementById('adamesh-data').textContent);
const bin = Uint8Array.from(atob(data.blob), (c) => c.charCodeAt(0)).buffer;
const view = (type, key) => {
  const [offset, count] = data.layout[key];
  return new type(bin, offset, count);
};

const positions = view(Float32Array, 'positions');
const NONE = 0xffffffff;

// ---- Triangle table: corners, birth and death split (NONE: base / never split).
let tri, birth, death, nTri, splitLevel, splitError, nSplits;
if (data.kind === 'hierarchy') {
  const base = view(Uint32Array, 'base_triangles');
  const edges = view(Uint32Array, 'split_edges');
  splitLevel = view(Uint8Array, 'split_levels');
  splitError = view(Float32Array, 'split_errors');
  nSplits = splitError.length;
  const v0 = data.base_vertices;
  const cap = base.length / 3 + 4 * nSplits;
  tri = new Uint32Array(3 * cap);
  birth = new Uint32Array(cap).fill(NONE);
  death = new Uint32Array(cap).fill(NONE);
  tri.set(base);
  nTri = base.length / 3;
  // Live triangles by undirected edge.
  const byEdge = new Map();
  const nv = positions.length / 3;  // keys a·nv + b stay below 2^53 up to 94M vertices
  const key = (a, b) => (a < b ? a * nv + b : b * nv + a);
  const addEdges = (t) => {
    for (let e = 0; e < 3; e++) {
      const k = key(tri[3 * t + e], tri[3 * t + ((e + 1) % 3)]);
      const list = byEdge.get(k);
      if (list) list.push(t);
      else byEdge.set(k, [t]);
    }
  };
  const dropEdges = (t) => {
    for (let e = 0; e < 3; e++) {
      const k = key(tri[3 * t + e], tri[3 * t + ((e + 1) % 3)]);
      const list = byEdge.get(k);
      const i = list.indexOf(t);
      list.splice(i, 1);
      if (list.length === 0) byEdge.delete(k);
    }
  };
  for (let t = 0; t < nTri; t++) addEdges(t);
  for (let s = 0; s < nSplits; s++) {
    const a = edges[2 * s], b = edges[2 * s + 1], m = v0 + s;
    const owners = (byEdge.get(key(a, b)) || []).slice();
    if (owners.length === 0) throw new Error(`split ${s}: edge ${a}-${b} is not in the mesh`);
    for (const t of owners) {
      dropEdges(t);
      death[t] = s;
      const c = [0, 1, 2].find((e) => tri[3 * t + e] !== a && tri[3 * t + e] !== b);
      // Corners in the triangle's own order, starting after c: (c, x, y) with {x, y} = {a, b}.
      const tc = tri[3 * t + c], x = tri[3 * t + ((c + 1) % 3)], y = tri[3 * t + ((c + 2) % 3)];
      for (const [p, q] of [[x, m], [m, y]]) {
        tri[3 * nTri] = tc;
        tri[3 * nTri + 1] = p;
        tri[3 * nTri + 2] = q;
        birth[nTri] = s;
        addEdges(nTri);
        nTri++;
      }
    }
  }
} else {
  tri = view(Uint32Array, 'triangles');
  nTri = tri.length / 3;
  birth = new Uint32Array(nTri).fill(NONE);
  death = new Uint32Array(nTri).fill(NONE);
  nSplits = 0;
}

// ---- Per-triangle figures: minimum angle (degrees) and, for hierarchies, the error bound.
const minAngle = new Float32Array(nTri);
for (let t = 0; t < nTri; t++) {
  const p = [0, 1, 2].map((e) => positions.subarray(3 * tri[3 * t + e], 3 * tri[3 * t + e] + 3));
  let best = 180;
  for (let e = 0; e < 3; e++) {
    const o = p[e], u = p[(e + 1) % 3], w = p[(e + 2) % 3];
    const ux = u[0] - o[0], uy = u[1] - o[1], uz = u[2] - o[2];
    const wx = w[0] - o[0], wy = w[1] - o[1], wz = w[2] - o[2];
    const lu = Math.hypot(ux, uy, uz), lw = Math.hypot(wx, wy, wz);
    const c = lu > 0 && lw > 0 ? (ux * wx + uy * wy + uz * wz) / (lu * lw) : 1;
    best = Math.min(best, (Math.acos(Math.max(-1, Math.min(1, c))) * 180) / Math.PI);
  }
  minAngle[t] = best;
}

// ---- Scene.
const canvas = document.getElementById('view');
const renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0xf4f4f0);
const camera = new THREE.PerspectiveCamera(35, 1, 0.01, 1e7);
camera.up.set(0, 0, 1);  // volumes: z is the slice axis (head up for axial scans)
scene.add(new THREE.HemisphereLight(0xffffff, 0x606070, 1.6));
const sun = new THREE.DirectionalLight(0xffffff, 1.6);
scene.add(sun);

const geometry = new THREE.BufferGeometry();
const surfaceMaterial = new THREE.MeshStandardMaterial({
  vertexColors: true, flatShading: true, side: THREE.DoubleSide, roughness: 0.8, metalness: 0,
  polygonOffset: true, polygonOffsetFactor: 1, polygonOffsetUnits: 1,
});
const wireMaterial = new THREE.MeshBasicMaterial({ color: 0x202020, wireframe: true, transparent: true, opacity: 0.35 });
const surface = new THREE.Mesh(geometry, surfaceMaterial);
const wire = new THREE.Mesh(geometry, wireMaterial);
wire.visible = false;
scene.add(surface, wire);

// Bounding box of all vertices: camera framing.
const box = new THREE.Box3().setFromArray(positions);
const centre = box.getCenter(new THREE.Vector3());
const radius = Math.max(box.getSize(new THREE.Vector3()).length() / 2, 1e-9);
const controls = new OrbitControls(camera, canvas);
controls.target.copy(centre);
camera.position.copy(centre).add(new THREE.Vector3(0.2, -1, 0.35).normalize().multiplyScalar(radius * 3.2));
camera.near = radius / 100;
camera.far = radius * 100;
camera.updateProjectionMatrix();
controls.update();  // looks at the target

// ---- Colours.
const ramp = (x) => {  // 0 → red, 0.5 → yellow, 1 → green-blue
  x = Math.max(0, Math.min(1, x));
  return new THREE.Color().setHSL(0.0 + 0.45 * x, 0.75, 0.5);
};
const plain = new THREE.Color(0xd8c8a8);
const finestError = nSplits ? splitError[nSplits - 1] : 0;
const colourOf = {
  plain: () => plain,
  quality: (t) => ramp(minAngle[t] / 60),
  // Distance bound of a leaf: the error of the split that would refine it (its block's sampled
  // max |d| × 1.25); leaves never split are within the last split's bound.
  error: (t) => ramp(1 - Math.sqrt((death[t] === NONE ? finestError : splitError[death[t]]) / (splitError[0] || 1))),
};

// ---- Cuts.
const ui = {
  slider: document.getElementById('splits'),
  level: document.getElementById('level'),
  count: document.getElementById('triangles'),
  info: document.getElementById('cut'),
  colour: document.getElementById('colour'),
  wireframe: document.getElementById('wireframe'),
  legend: document.getElementById('legend'),
};
const state = { mode: 'prefix', k: nSplits, level: -1, triangles: 0 };

function alive(t) {
  if (state.mode === 'prefix') {
    return (birth[t] === NONE || birth[t] < state.k) && (death[t] === NONE || death[t] >= state.k);
  }
  const K = state.level;
  return (birth[t] === NONE || splitLevel[birth[t]] < K) && (death[t] === NONE || splitLevel[death[t]] >= K);
}

function rebuild() {
  const ids = [];
  for (let t = 0; t < nTri; t++) if (alive(t)) ids.push(t);
  const pos = new Float32Array(9 * ids.length);
  const col = new Float32Array(9 * ids.length);
  const colour = colourOf[ui.colour.value] || colourOf.plain;
  ids.forEach((t, i) => {
    const c = colour(t);
    for (let e = 0; e < 3; e++) {
      const v = tri[3 * t + e];
      pos.set(positions.subarray(3 * v, 3 * v + 3), 9 * i + 3 * e);
      col[9 * i + 3 * e] = c.r;
      col[9 * i + 3 * e + 1] = c.g;
      col[9 * i + 3 * e + 2] = c.b;
    }
  });
  geometry.setAttribute('position', new THREE.BufferAttribute(pos, 3));
  geometry.setAttribute('color', new THREE.BufferAttribute(col, 3));
  geometry.computeVertexNormals();
  geometry.computeBoundingSphere();
  state.triangles = ids.length;
  ui.count.textContent = String(ids.length);
  if (data.kind === 'hierarchy') {
    if (state.mode === 'prefix') {
      const bound = state.k < nSplits ? splitError[state.k] : 0;
      ui.info.textContent = `first ${state.k} of ${nSplits} splits` +
        (state.k < nSplits ? `, error bound ${bound.toPrecision(3)}` : ', all splits');
    } else {
      ui.info.textContent = `uniform level ${state.level}`;
    }
  }
  ui.legend.textContent = {
    plain: '',
    quality: 'minimum angle: red 0°, yellow 30°, green ≥ 60°',
    error: 'distance bound of each triangle (from the .amh): red = largest, green = smallest',
  }[ui.colour.value] || '';
  render();
}

function render() {
  const w = canvas.clientWidth, h = canvas.clientHeight;
  if (canvas.width !== Math.floor(w * renderer.getPixelRatio()) || canvas.height !== Math.floor(h * renderer.getPixelRatio())) {
    renderer.setSize(w, h, false);
    camera.aspect = w / Math.max(h, 1);
    camera.updateProjectionMatrix();
  }
  sun.position.copy(camera.position);
  renderer.render(scene, camera);
}

if (data.kind === 'hierarchy') {
  ui.slider.max = String(nSplits);
  ui.slider.value = String(nSplits);
  ui.slider.addEventListener('input', () => {
    state.mode = 'prefix';
    state.k = Number(ui.slider.value);
    ui.level.value = '';
    rebuild();
  });
  let maxLevel = 0;
  for (let s = 0; s < nSplits; s++) maxLevel = Math.max(maxLevel, splitLevel[s] + 1);
  for (let K = 0; K <= maxLevel; K++) {
    const o = document.createElement('option');
    o.value = String(K);
    o.textContent = `level ${K}`;
    ui.level.appendChild(o);
  }
  ui.level.addEventListener('change', () => {
    if (ui.level.value === '') return;
    state.mode = 'level';
    state.level = Number(ui.level.value);
    rebuild();
  });
} else {
  document.getElementById('hierarchy-controls').style.display = 'none';
  for (const o of ui.colour.options) if (o.value === 'error') o.disabled = true;
}
ui.colour.addEventListener('change', rebuild);
ui.wireframe.addEventListener('change', () => {
  wire.visible = ui.wireframe.checked;
  render();
});
controls.addEventListener('change', render);
window.addEventListener('resize', render);

// ---- Report figures (extract --report), when given.
if (data.report) {
  const r = data.report;
  const rows = [];
  const fmt = (v) => (typeof v === 'number' ? (Number.isInteger(v) ? v.toLocaleString('en') : v.toPrecision(4)) : String(v));
  const add = (label, v) => { if (v !== undefined && v !== null) rows.push([label, fmt(v)]); };
  add('input', r.input);
  add('iso-value', r.iso);
  add('surfels', r.surfels);
  if (r.base) {
    add('base mesh M0 triangles', r.base.triangles);
    add('M0 components / χ', `${r.base.components} / ${r.base.euler}`);
  }
  if (r.refine) {
    add('refinement', r.refine.chosen);
    add('splits', r.refine.splits);
    add('final triangles', r.refine.triangles);
    add('depth', r.refine.depth);
  }
  if (r.timings_s) add('time (s)', Object.values(r.timings_s).reduce((a, b) => a + b, 0));
  add('peak memory (MiB)', r.peak_rss_mb);
  let html = '<table>' + rows.map(([k, v]) => `<tr><th>${k}</th><td>${escapeHtml(v)}</td></tr>`).join('') + '</table>';
  if (Array.isArray(r.levels)) {
    html += '<table class="levels"><tr><th>mesh</th><th>triangles</th><th>RMS</th><th>max</th><th>min angle median</th><th>&lt; 20°</th></tr>' +
      r.levels.map((l) => `<tr><td>${l.level === 0 ? 'M0' : escapeHtml(String(l.level))}</td><td>${fmt(l.triangles)}</td>` +
        `<td>${fmt(l.rms)}</td><td>${fmt(l.max)}</td><td>${l.min_angle ? fmt(l.min_angle.median) + '°' : ''}</td>` +
        `<td>${l.pct_min_angle_below_20 !== undefined ? fmt(l.pct_min_angle_below_20) + ' %' : ''}</td></tr>`).join('') + '</table>';
  }
  document.getElementById('report').innerHTML = html;
}
function escapeHtml(s) {
  return String(s).replace(/[&<>"]/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;' }[c]));
}

rebuild();
// For scripted checks (the browser test reads the page as a user sees it, through the DOM).
window.adameshViewer = { state, nSplits, ready: true };
document.body.dataset.ready = '1';
