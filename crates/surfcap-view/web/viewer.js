// surfcap viewer: plays the server's items (mesh sequences) with three.js.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

const GREEN = new THREE.Color(0x2e9e44), RED = new THREE.Color(0xd03030);
const PATH = 0x1f5fbf, CENTRE = 0xe08a00, GRID = 0xb4b4b0, TRANSITION = 0x7b2cbf;
const $ = (id) => document.getElementById(id);
const hex = (c) => `#${new THREE.Color(c).getHexString()}`;

// Rotation that turns the subject's up axis onto three.js's +Y.
function upRotation(up) {
  const e = new THREE.Euler();
  switch (up) {
    case '+z': e.set(-Math.PI / 2, 0, 0); break;
    case '-z': e.set(Math.PI / 2, 0, 0); break;
    case '+x': e.set(0, 0, Math.PI / 2); break;
    case '-x': e.set(0, 0, -Math.PI / 2); break;
    case '-y': e.set(Math.PI, 0, 0); break;
    default: break;
  }
  return e;
}

async function fetchBytes(url) {
  const r = await fetch(url);
  if (!r.ok) throw new Error(`${url}: HTTP ${r.status}`);
  return r.arrayBuffer();
}

const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio);
$('view').appendChild(renderer.domElement);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0xf4f4f2);
scene.add(new THREE.HemisphereLight(0xffffff, 0x888888, 2.0));
const sun = new THREE.DirectionalLight(0xffffff, 1.5);
sun.position.set(3, 6, 4);
scene.add(sun);
const camera = new THREE.PerspectiveCamera(40, 1, 0.01, 1000);
const controls = new OrbitControls(camera, renderer.domElement);
const ground = new THREE.Group();  // the grid and its label, rebuilt with the layout
scene.add(ground);

const state = { items: [], playing: true, time: 0, frame: 0, frames: 1, fps: 30, speed: 1, grid: null, legend: [] };

function line(points, colour) {
  const g = new THREE.BufferGeometry().setFromPoints(points.map((p) => new THREE.Vector3(p[0], p[1], p[2])));
  return new THREE.Line(g, new THREE.LineBasicMaterial({ color: colour }));
}

// Box of every frame of an item and its overlay, in the item's own coordinates: the camera and
// the grid are set from it, so nothing the animation does later leaves the view.
function animationBox(m, positions) {
  const box = new THREE.Box3(), p = new THREE.Vector3();
  for (let i = 0; i < positions.length; i += 3) box.expandByPoint(p.set(positions[i], positions[i + 1], positions[i + 2]));
  if (m.overlay) for (const q of [...(m.overlay.curve || []), ...m.overlay.centres]) box.expandByPoint(p.set(q[0], q[1], q[2]));
  return box;
}

// Start of every frame's vertices and triangles in a frame set's arrays, and its largest frame.
function offsets(vertices, triangles) {
  const v = [0], t = [0];
  let maxTriangles = 0;
  for (let f = 0; f < vertices.length; f++) {
    v.push(v[f] + vertices[f]);
    t.push(t[f] + triangles[f]);
    maxTriangles = Math.max(maxTriangles, triangles[f]);
  }
  return { v, t, maxTriangles };
}

// An item's textures (PNG files), each decoded once and kept: a frame binds its own as the
// material's map. Texture coordinates come in OBJ's convention (v = 1 at the image's top row),
// which is three.js's default `flipY`; sRGB colours, as PNGs hold them.
async function loadTextures(k, n) {
  const loader = new THREE.TextureLoader();
  return Promise.all([...Array(n).keys()].map(async (t) => {
    const texture = await loader.loadAsync(`/api/items/${k}/textures/${t}`);
    texture.colorSpace = THREE.SRGBColorSpace;
    texture.flipY = true;
    return texture;
  }));
}

async function load() {
  const meta = await (await fetch('/api/items')).json();
  if (meta.report) $('report').innerHTML = `<a href="${meta.report}" target="_blank">open the report</a>`;
  const list = [];
  for (let k = 0; k < meta.items.length; k++) {
    const m = meta.items[k];
    const [pos, faces, colours, uvBytes, textures] = await Promise.all([
      fetchBytes(`/api/items/${k}/positions`),
      fetchBytes(`/api/items/${k}/faces`),
      m.has_colours ? fetchBytes(`/api/items/${k}/colours`) : null,
      m.has_uvs ? fetchBytes(`/api/items/${k}/uvs`) : null,
      loadTextures(k, m.n_textures),
    ]);
    const positions = new Float32Array(pos);
    const faceArray = new Uint32Array(faces);
    // A frame set (every frame its own mesh): where each frame's vertices and triangles start.
    const frameSet = m.frame_vertices ? offsets(m.frame_vertices, m.frame_triangles) : null;
    const geometry = new THREE.BufferGeometry();
    const attr = new THREE.BufferAttribute(positions.slice(0, 3 * m.n_vertices), 3);
    attr.setUsage(THREE.DynamicDrawUsage);
    geometry.setAttribute('position', attr);
    // A frame set's index holds the largest frame's triangles; each frame fills its start.
    const index = new THREE.BufferAttribute(frameSet ? new Uint32Array(3 * frameSet.maxTriangles) : faceArray, 1);
    if (frameSet) index.setUsage(THREE.DynamicDrawUsage);
    geometry.setIndex(index);
    geometry.computeVertexNormals();
    // Per-vertex colours (body parts...), linear RGB in 0..1, replace the frame colour.
    if (colours) geometry.setAttribute('color', new THREE.BufferAttribute(new Float32Array(colours), 3));
    // Texture coordinates, one per vertex as the positions (a frame set's: each frame fills the
    // start of the attribute, as its positions do).
    const uvs = uvBytes ? new Float32Array(uvBytes) : null;
    if (uvs) {
      const uv = new THREE.BufferAttribute(uvs.slice(0, 2 * m.n_vertices), 2);
      if (frameSet) uv.setUsage(THREE.DynamicDrawUsage);
      geometry.setAttribute('uv', uv);
    }
    const textured = !!m.frame_textures;
    const material = new THREE.MeshStandardMaterial({
      color: colours || textured ? 0xffffff : GREEN, vertexColors: !!colours, roughness: 0.7, side: THREE.DoubleSide,
      map: textured ? textures[m.frame_textures[0]] : null,
    });
    const mesh = new THREE.Mesh(geometry, material);
    mesh.frustumCulled = false;  // its bounding sphere is frame 0's
    const group = new THREE.Group();   // the item, in its own coordinates
    group.add(mesh);
    if (m.overlay) {
      if (m.overlay.curve) group.add(line(m.overlay.curve, PATH));
      group.add(line(m.overlay.centres, CENTRE));
    }
    const turned = new THREE.Group();  // turned so its up axis is +Y
    turned.rotation.copy(upRotation(m.up));
    turned.add(group);
    const placed = new THREE.Group();  // moved aside for side-by-side playback
    placed.add(turned);
    scene.add(placed);
    const hue = new THREE.Color().setHSL((k * 0.61803) % 1, 0.6, 0.5);
    list.push({ meta: m, positions, faces: faceArray, frameSet, nv: m.n_vertices, geometry, material, mesh, placed, turned, hue,
      uvs, textures, box: animationBox(m, positions) });
    const vertices = frameSet ? `${m.frame_vertices.reduce((a, b) => Math.min(a, b))}-${m.n_vertices} vertices (a mesh per frame)` : `${m.n_vertices} vertices`;
    const row = document.createElement('div');
    row.textContent = `${m.name}: ${m.n_frames} frames, ${vertices}, ${m.fps} fps` +
      (m.synthetic.some((s) => s) ? `, ${m.synthetic.filter((s) => s).length} synthetic` : '');
    $('items').appendChild(row);
    for (const c of (m.overlay && m.overlay.constraints) || []) {
      const line = document.createElement('div');
      line.className = 'constraint';
      line.textContent = c;
      $('items').appendChild(line);
    }
  }
  state.items = list;
  state.fps = list[0].meta.fps;
  state.frames = Math.max(...list.map((it) => it.meta.n_frames));
  arrange();
}

// Side by side: each item's whole-animation box placed next to the previous one.
function layout() {
  let x = 0;
  for (const it of state.items) {
    it.placed.position.set(0, 0, 0);
    it.placed.updateMatrixWorld(true);
    const box = it.box.clone().applyMatrix4(it.turned.matrixWorld);
    if ($('side').checked) {
      it.placed.position.x = x - box.min.x;
      x += box.max.x - box.min.x + 0.25 * (box.max.y - box.min.y);
    }
    it.placed.updateMatrixWorld(true);
  }
}

function sceneBox() {
  const box = new THREE.Box3();
  for (const it of state.items) box.union(it.box.clone().applyMatrix4(it.turned.matrixWorld));
  return box;
}

// A round grid step (1, 2 or 5 times a power of ten) giving about ten squares across `extent`.
function gridStep(extent) {
  const raw = Math.max(extent, 1e-9) / 10, p = 10 ** Math.floor(Math.log10(raw));
  return [5, 2, 1].map((k) => k * p).find((s) => s <= raw);
}

function unitName(m, step) {
  // `units` is the unit's symbol (`m`, `cm`), or `units` when the size is unknown.
  return `${step} ${m.units}`;
}

function label(text, height) {
  const c = document.createElement('canvas'), g = c.getContext('2d');
  const font = '600 48px system-ui, sans-serif';
  g.font = font;
  c.width = Math.ceil(g.measureText(text).width) + 16;
  c.height = 64;
  g.font = font;
  g.fillStyle = '#555';
  g.textBaseline = 'middle';
  g.fillText(text, 8, 32);
  const texture = new THREE.CanvasTexture(c);
  texture.colorSpace = THREE.SRGBColorSpace;
  const sprite = new THREE.Sprite(new THREE.SpriteMaterial({ map: texture, depthWrite: false }));
  sprite.center.set(0, 0);
  sprite.scale.set(height * c.width / c.height, height, 1);
  return sprite;
}

// The ground grid under the whole animation, in squares of a round number of the subject's unit.
function buildGrid(box) {
  ground.clear();
  const size = box.getSize(new THREE.Vector3());
  const extent = Math.max(size.x, size.y, size.z), step = gridStep(extent);
  const x0 = Math.floor(box.min.x / step - 1) * step, x1 = Math.ceil(box.max.x / step + 1) * step;
  const z0 = Math.floor(box.min.z / step - 1) * step, z1 = Math.ceil(box.max.z / step + 1) * step;
  const y = box.min.y, pts = [];
  for (let x = x0; x <= x1 + step / 2; x += step) pts.push(x, y, z0, x, y, z1);
  for (let z = z0; z <= z1 + step / 2; z += step) pts.push(x0, y, z, x1, y, z);
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.Float32BufferAttribute(pts, 3));
  ground.add(new THREE.LineSegments(g, new THREE.LineBasicMaterial({ color: GRID })));
  const text = `1 square = ${unitName(state.items[0].meta, step)}`;
  const height = Math.max(0.35 * step, extent / 30);
  const tag = label(text, height);
  // Just in front of the footprint's near left corner, as `frameCamera` looks at it.
  if (size.z > size.x) tag.position.set(box.max.x + 0.25 * step, y, box.max.z);
  else tag.position.set(box.min.x, y, box.max.z + 0.25 * step);
  ground.add(tag);
  state.grid = { step, units: state.items[0].meta.units, text, tag: tag.position.clone(), height };
}

// The part of the view the info panel leaves free: right of it or below it, whichever lets the
// scene be drawn larger (measured in `frameCamera`). Rectangles are in view pixels.
function freeRegions(W, H) {
  const v = $('view').getBoundingClientRect(), p = $('panel').getBoundingClientRect(), m = 12;
  const right = p.right - v.left + m, below = p.bottom - v.top + m;
  return [
    { x: right, y: m, w: W - right - m, h: H - 2 * m },
    { x: m, y: below, w: W - 2 * m, h: H - below - m },
  ].filter((r) => r.w > 40 && r.h > 40);
}

// Puts the camera where every point of the whole animation (and the grid's label) projects
// inside a free region, centred there: the principal point moves to the region's centre through
// `setViewOffset`, so orbiting still turns about the scene's centre.
function frameCamera() {
  const v = $('view'), W = v.clientWidth, H = Math.max(1, v.clientHeight);
  const box = sceneBox();
  const pts = [];
  for (let k = 0; k < 8; k++) {
    pts.push(new THREE.Vector3(k & 1 ? box.max.x : box.min.x, k & 2 ? box.max.y : box.min.y, k & 4 ? box.max.z : box.min.z));
  }
  if (state.grid) pts.push(state.grid.tag.clone().add(new THREE.Vector3(0, state.grid.height, 0)));
  // Looking across the longer side of the ground footprint (a walk along z is seen from the side).
  const c = box.getCenter(new THREE.Vector3()), size = box.getSize(new THREE.Vector3());
  const dir = (size.z > size.x ? new THREE.Vector3(1.6, 0.5, -0.2) : new THREE.Vector3(0.2, 0.5, 1.6)).normalize();
  camera.clearViewOffset();
  camera.position.copy(c).add(dir);
  camera.up.set(0, 1, 0);
  camera.lookAt(c);
  camera.updateMatrixWorld();
  const right = new THREE.Vector3().setFromMatrixColumn(camera.matrixWorld, 0);
  const up = new THREE.Vector3().setFromMatrixColumn(camera.matrixWorld, 1);
  const f = H / (2 * Math.tan(THREE.MathUtils.degToRad(20)));  // focal length in pixels: a 40 degree view
  // A point at `rel` from the centre is inside a w x h window at distance d when its depth
  // d - rel.dir is at least 2 f |rel.right| / w and 2 f |rel.up| / h.
  const distance = (r) => Math.max(...pts.map((p) => {
    const rel = p.clone().sub(c);
    return rel.dot(dir) + 2 * f * Math.max(Math.abs(rel.dot(right)) / r.w, Math.abs(rel.dot(up)) / r.h);
  }));
  const regions = freeRegions(W, H);
  if (!regions.length) regions.push({ x: 0, y: 0, w: W, h: H });
  const best = regions.map((r) => ({ r, d: distance(r) })).reduce((a, b) => (b.d < a.d ? b : a));
  const { r, d } = best, cx = r.x + r.w / 2, cy = r.y + r.h / 2;
  const FW = 2 * Math.max(cx, W - cx), FH = 2 * Math.max(cy, H - cy);
  camera.aspect = FW / FH;
  camera.fov = THREE.MathUtils.radToDeg(2 * Math.atan(FH / (2 * f)));
  camera.setViewOffset(FW, FH, FW / 2 - cx, FH / 2 - cy, W, H);
  const radius = size.length() / 2 || 1e-3;
  camera.position.copy(c).addScaledVector(dir, d);
  camera.near = Math.max(radius / 1000, (d - radius) / 10);
  camera.far = d + 100 * radius;
  camera.updateProjectionMatrix();
  controls.target.copy(c);
  controls.update();
  state.region = r;
}

function arrange() {
  layout();
  buildGrid(sceneBox());
  buildLegend();
  frameCamera();
  drawTrack();
}

function resize() {
  const v = $('view');
  renderer.setSize(v.clientWidth, v.clientHeight);
  if (state.items.length) frameCamera();
  else { camera.aspect = v.clientWidth / Math.max(1, v.clientHeight); camera.updateProjectionMatrix(); }
  const t = $('track');
  t.width = Math.round(t.clientWidth * devicePixelRatio);
  t.height = Math.round(t.clientHeight * devicePixelRatio);
  drawTrack();
}
window.addEventListener('resize', resize);

// Only what is drawn: frame colours that occur (or the sequences' own colours), the overlays
// that exist, the grid's square.
function buildLegend() {
  const entries = [];
  for (const it of state.items) for (const [colour, text] of it.meta.colour_legend || []) entries.push([colour, text]);
  if (state.items.some((it) => it.meta.frame_textures)) entries.push(['#a0a0a0', 'texture per frame']);
  const plain = state.items.filter((it) => !it.meta.has_colours && !it.meta.frame_textures);
  if ($('hues').checked) {
    for (const it of plain) entries.push([hex(it.hue), it.meta.name]);
  } else {
    const labels = plain.flatMap((it) => it.meta.synthetic);
    if (labels.some((s) => !s)) entries.push([hex(GREEN), 'original frame']);
    if (labels.some((s) => s)) entries.push([hex(RED), 'synthetic frame']);
  }
  if (state.items.some((it) => it.meta.overlay && it.meta.overlay.curve)) entries.push([hex(PATH), 'requested path']);
  if (state.items.some((it) => it.meta.overlay)) entries.push([hex(CENTRE), 'achieved centre of mass']);
  if (state.items.some((it) => it.meta.overlay && it.meta.overlay.transitions.length)) entries.push([hex(TRANSITION), 'transition (timeline)']);
  if (state.grid) entries.push([hex(GRID), `grid: ${state.grid.text}`]);
  $('legend').replaceChildren(...entries.map(([colour, text]) => {
    const row = document.createElement('div'), swatch = document.createElement('span');
    swatch.style.background = colour;
    row.append(swatch, text);
    return row;
  }));
  state.legend = entries.map(([, text]) => text);
}

// Runs of original/synthetic frames per item (shorter items loop, as they play).
function spans(m) {
  const out = [];
  for (let f = 0; f < state.frames; f++) {
    const s = m.synthetic[f % m.n_frames], last = out[out.length - 1];
    if (last && last.synthetic === s) last.to = f + 1;
    else out.push({ from: f, to: f + 1, synthetic: s });
  }
  return out;
}

// The timeline: one row per item, green and red spans, and the current frame.
function drawTrack() {
  const t = $('track'), g = t.getContext('2d'), W = t.width, H = t.height;
  g.clearRect(0, 0, W, H);
  if (!state.items.length) return;
  const n = state.items.length, rowH = H / n, x = (f) => (f / state.frames) * W;
  state.items.forEach((it, k) => {
    for (const s of spans(it.meta)) {
      g.fillStyle = hex(s.synthetic ? RED : GREEN);
      g.fillRect(x(s.from), k * rowH + 1, Math.max(1, x(s.to) - x(s.from)), rowH - 2);
    }
    // Transitions (shorter items loop, so are their marks).
    const m = it.meta, marks = (m.overlay && m.overlay.transitions) || [];
    g.fillStyle = hex(TRANSITION);
    for (let r = 0; r * m.n_frames < state.frames; r++) {
      for (const f of marks) g.fillRect(x(r * m.n_frames + f) - 1, k * rowH, Math.max(2, W / state.frames / 3), rowH);
    }
  });
  g.fillStyle = '#111';
  const w = Math.max(2, W / state.frames);
  g.fillRect(Math.min(W - w, x(state.frame)), 0, w, H);
}

function showFrame(f) {
  state.frame = f;
  for (const it of state.items) {
    const m = it.meta, k = f % m.n_frames, n = 3 * m.n_vertices;  // shorter sequences loop
    const attr = it.geometry.getAttribute('position');
    if (it.frameSet) {
      // This frame's own mesh: its vertices and triangles at the start of the arrays, the rest
      // of the index zeroed (degenerate) and left out of the draw range.
      const { v, t } = it.frameSet, index = it.geometry.getIndex();
      attr.array.set(it.positions.subarray(3 * v[k], 3 * v[k + 1]));
      index.array.set(it.faces.subarray(3 * t[k], 3 * t[k + 1]));
      index.array.fill(0, 3 * (t[k + 1] - t[k]));
      index.needsUpdate = true;
      it.geometry.setDrawRange(0, 3 * (t[k + 1] - t[k]));
      it.nv = v[k + 1] - v[k];
      if (it.uvs) {
        const uv = it.geometry.getAttribute('uv');
        uv.array.set(it.uvs.subarray(2 * v[k], 2 * v[k + 1]));
        uv.needsUpdate = true;
      }
    } else {
      attr.array.set(it.positions.subarray(k * n, (k + 1) * n));
    }
    attr.needsUpdate = true;
    it.geometry.computeVertexNormals();
    if (m.frame_textures) it.material.map = it.textures[m.frame_textures[k]];
    else if (!m.has_colours) it.material.color.copy($('hues').checked ? it.hue : (m.synthetic[k] ? RED : GREEN));
  }
  const first = state.items[0].meta, k = f % first.n_frames;
  $('counter').textContent =
    `frame ${f} / ${state.frames - 1} (${first.synthetic[k] ? 'synthetic' : 'original'}) ${(f / state.fps).toFixed(2)} s`;
  drawTrack();
}

function setPlaying(on) {
  state.playing = on;
  $('play').textContent = on ? 'Pause' : 'Play';
}

// Shows frame `f` paused, wrapping around the ends.
function seek(f) {
  setPlaying(false);
  const n = state.frames, g = ((Math.round(f) % n) + n) % n;
  state.time = (g + 0.5) / state.fps;
  showFrame(g);
}

$('play').addEventListener('click', () => setPlaying(!state.playing));
// The select gives the keyboard back, so the arrow keys step frames again rather than the speed.
$('speed').addEventListener('change', () => { state.speed = Number($('speed').value); $('speed').blur(); });
$('side').addEventListener('change', arrange);
$('hues').addEventListener('change', () => { buildLegend(); showFrame(state.frame); });
const track = $('track');
const seekAt = (e) => {
  const r = track.getBoundingClientRect();
  seek(Math.min(state.frames - 1, Math.max(0, Math.floor(((e.clientX - r.left) / r.width) * state.frames))));
};
track.addEventListener('pointerdown', (e) => { track.setPointerCapture(e.pointerId); seekAt(e); });
track.addEventListener('pointermove', (e) => { if (track.hasPointerCapture(e.pointerId)) seekAt(e); });
window.addEventListener('keydown', (e) => {
  const t = e.target;
  if (!state.items.length || t.tagName === 'SELECT' || (t.tagName === 'INPUT' && t.type !== 'checkbox')) return;
  const step = e.shiftKey ? 10 : 1;
  if (e.key === 'ArrowRight') seek(state.frame + step);
  else if (e.key === 'ArrowLeft') seek(state.frame - step);
  else if (e.key === 'Home') seek(0);
  else if (e.key === 'End') seek(state.frames - 1);
  else if (e.key === ' ' && t.tagName !== 'BUTTON') setPlaying(!state.playing);
  else return;
  e.preventDefault();
});

// Pixel rectangle of the current frame's vertices, every item, as drawn (for tests).
function screenBounds() {
  const v = $('view'), p = new THREE.Vector3(), r = { left: Infinity, top: Infinity, right: -Infinity, bottom: -Infinity };
  camera.updateMatrixWorld();
  for (const it of state.items) {
    it.mesh.updateMatrixWorld(true);
    const a = it.geometry.getAttribute('position').array;
    for (let i = 0; i < 3 * it.nv; i += 3) {
      p.set(a[i], a[i + 1], a[i + 2]).applyMatrix4(it.mesh.matrixWorld).project(camera);
      const x = ((p.x + 1) / 2) * v.clientWidth, y = ((1 - p.y) / 2) * v.clientHeight;
      r.left = Math.min(r.left, x); r.right = Math.max(r.right, x);
      r.top = Math.min(r.top, y); r.bottom = Math.max(r.bottom, y);
    }
  }
  const pr = $('panel').getBoundingClientRect(), vr = v.getBoundingClientRect();
  return { subject: r, view: { width: v.clientWidth, height: v.clientHeight },
    panel: { left: pr.left - vr.left, top: pr.top - vr.top, right: pr.right - vr.left, bottom: pr.bottom - vr.top } };
}

// For tests and scripting: the current frame, a way to jump, and what is drawn.
window.surfcapViewer = {
  get frame() { return state.frame; },
  get frames() { return state.frames; },
  get playing() { return state.playing; },
  get speed() { return state.speed; },
  get legend() { return state.legend.slice(); },
  get grid() { return state.grid && { step: state.grid.step, units: state.grid.units, text: state.grid.text }; },
  get overlays() { return state.items.map((it) => ({ curve: !!(it.meta.overlay && it.meta.overlay.curve), centres: !!it.meta.overlay })); },
  get spans() { return state.items.map((it) => spans(it.meta)); },
  get colours() { return state.items.map((it) => !!it.meta.has_colours); },
  // The texture bound as each item's map now: its index among the item's textures (null: none).
  get boundTextures() { return state.items.map((it) => (it.material.map ? it.textures.indexOf(it.material.map) : null)); },
  // Vertices and triangles of the mesh drawn now, per item (a frame set's change frame by frame).
  get vertexCounts() { return state.items.map((it) => it.nv); },
  get triangleCounts() { return state.items.map((it) => it.geometry.drawRange.count === Infinity ? it.geometry.getIndex().count / 3 : it.geometry.drawRange.count / 3); },
  setFrame(f) { state.time = (f + 0.5) / state.fps; showFrame(Math.max(0, Math.min(state.frames - 1, f))); },
  screenBounds,
  ready: false,
};

let last = performance.now();
function tick(now) {
  const dt = (now - last) / 1000;
  last = now;
  if (state.items.length) {
    if (state.playing) {
      state.time += dt * state.speed;
      const f = Math.floor(state.time * state.fps) % state.frames;
      if (f !== state.frame) showFrame(f);
    }
    controls.update();
    renderer.render(scene, camera);
  }
  requestAnimationFrame(tick);
}

resize();
load().then(() => {
  showFrame(0);
  window.surfcapViewer.ready = true;
  requestAnimationFrame(tick);
}).catch((e) => {
  $('error').textContent = `could not load: ${e.message}`;
  console.error(e);
});

// ---- render contract (minimal; the viewer part's replaces it) ----
// What `surfcap render` (and other scripts) rely on: `?ui=0` shows the bare scene (no panel,
// legend or timeline); `?view=<preset>` and `?frame=<i>` are applied once every item is loaded;
// window.surfcapViewer gains nFrames, fps, setFrame(i) (pause, show frame i, render it now),
// setView('top'|'front'|'side'|'three-quarter'|'follow'), scene, camera, renderer, controls,
// groundY, unitSymbol and reload(); `ready` turns true, and the window gets a 'surfcap-ready'
// event, only after the URL's view and frame are applied.
{
  const params = new URLSearchParams(location.search);
  if (params.get('ui') === '0') {
    for (const id of ['panel', 'bar']) $(id).style.display = 'none';
    $('view').style.inset = '0';
    resize();
  }
  const api = window.surfcapViewer;
  // Directions the camera looks from, towards the scene's centre (+Y up; front looks along -Z).
  const presets = { top: [0, 1, 1e-3], front: [0, 0.2, 1], side: [1, 0.2, 0], 'three-quarter': [1, 0.6, 1], follow: [1, 0.45, 1] };
  let follow = null;  // the follow camera's offset from the first item's centre
  // The centre of the first item's mesh as drawn now, in the scene's coordinates.
  const itemCentre = () => {
    const it = state.items[0];
    it.geometry.computeBoundingBox();
    it.mesh.updateMatrixWorld(true);
    return it.geometry.boundingBox.clone().applyMatrix4(it.mesh.matrixWorld);
  };
  // Puts the camera on `dir` from `box`'s centre, far enough to see a sphere around the box.
  function lookFrom(dir, box) {
    const v = $('view'), c = box.getCenter(new THREE.Vector3());
    const radius = box.getSize(new THREE.Vector3()).length() / 2 || 1e-3;
    camera.clearViewOffset();
    camera.aspect = v.clientWidth / Math.max(1, v.clientHeight);
    camera.fov = 40;
    const half = THREE.MathUtils.degToRad(20), across = Math.atan(Math.tan(half) * camera.aspect);
    const d = radius / Math.sin(Math.min(half, across));
    camera.position.copy(c).addScaledVector(new THREE.Vector3(...dir).normalize(), d);
    camera.up.set(0, 1, 0);
    camera.near = Math.max(radius / 1000, (d - radius) / 10);
    camera.far = d + 100 * radius;
    camera.lookAt(c);
    camera.updateProjectionMatrix();
    controls.target.copy(c);
    controls.update();
  }
  function setView(preset) {
    if (!presets[preset]) throw new Error(`unknown view ${preset}: expected ${Object.keys(presets).join(', ')}`);
    if (preset === 'follow') {
      const box = itemCentre();
      lookFrom(presets.follow, box.expandByScalar(box.getSize(new THREE.Vector3()).length() * 0.3));
      follow = camera.position.clone().sub(controls.target);
    } else {
      follow = null;
      lookFrom(presets[preset], sceneBox());
    }
    renderer.render(scene, camera);
  }
  function setFrame(i) {
    seek(Math.max(0, Math.min(state.frames - 1, Math.round(i))));
    if (follow) {
      const c = itemCentre().getCenter(new THREE.Vector3());
      controls.target.copy(c);
      camera.position.copy(c).add(follow);
      camera.lookAt(c);
    }
    controls.update();
    renderer.render(scene, camera);
  }
  function reload() {
    for (const it of state.items) scene.remove(it.placed);
    state.items = [];
    $('items').replaceChildren();
    api.ready = false;
    return load().then(() => { showFrame(0); api.ready = true; });
  }
  let ready = false;
  Object.defineProperty(api, 'ready', {
    get: () => ready,
    // The page's loader sets it once the items are in: apply the URL's view and frame first.
    set(on) {
      if (on && !ready) {
        if (params.get('view')) setView(params.get('view'));
        if (params.get('frame') !== null) setFrame(Number(params.get('frame')));
      }
      ready = !!on;
      if (ready) window.dispatchEvent(new Event('surfcap-ready'));
    },
  });
  Object.defineProperties(api, {
    nFrames: { get: () => state.frames },
    fps: { get: () => state.fps },
    groundY: { get: () => sceneBox().min.y },
    unitSymbol: { get: () => (state.items[0] ? state.items[0].meta.units : null) },
  });
  Object.assign(api, { setFrame, setView, reload, scene, camera, renderer, controls });
}
