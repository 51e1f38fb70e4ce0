// surfcap viewer: plays the server's items (mesh sequences) with three.js.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

const GREEN = new THREE.Color(0x2e9e44), RED = new THREE.Color(0xd03030), NEUTRAL = new THREE.Color(0xc8c8c4);
const PATH = 0x1f5fbf, CENTRE = 0xe08a00, GRID = 0xb4b4b0, TRANSITION = 0x7b2cbf, HIP = 0xb07030;
const PAST = new THREE.Color(0x3b6fd8), FUTURE = new THREE.Color(0xd8843b);
const $ = (id) => document.getElementById(id);
const hex = (c) => `#${new THREE.Color(c).getHexString()}`;
const params = new URLSearchParams(location.search);
// `?ui=0`: the bare scene (no panel, legend, timeline; `bar=1` keeps a colour map's bar).
const BARE = params.get('ui') === '0';
if (BARE) document.body.classList.add('bare');
if (BARE && params.get('bar') === '1') document.body.classList.add('with-bar');
const PRESETS = ['top', 'front', 'side', 'three-quarter', 'follow'];

// Viridis (matplotlib's perceptually uniform colour map), 9 stops in sRGB: low values dark
// purple, high values yellow.
const VIRIDIS = [0x440154, 0x472d7b, 0x3b528b, 0x2c728e, 0x21918c, 0x28ae80, 0x5ec962, 0xaddc30, 0xfde725]
  .map((c) => new THREE.Color().setHex(c, THREE.SRGBColorSpace));
const NO_VALUE = new THREE.Color(0x9a9a9a);
function viridis(t, out) {
  if (!Number.isFinite(t)) return out.copy(NO_VALUE);
  const x = Math.min(1, Math.max(0, t)) * (VIRIDIS.length - 1), k = Math.min(VIRIDIS.length - 2, Math.floor(x));
  return out.copy(VIRIDIS[k]).lerp(VIRIDIS[k + 1], x - k);
}

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
ground.name = 'grid';
scene.add(ground);
const groundTracks = new THREE.Group();  // overlays projected onto the ground plane, world coordinates
groundTracks.name = 'ground overlays';
scene.add(groundTracks);
const labels = new THREE.Group();  // the figures' labels, world coordinates
labels.name = 'labels';
scene.add(labels);

const state = {
  items: [], playing: true, pos: 0, frame: 0, frames: 1, fps: 30, speed: 1, grid: null, legend: [],
  view: null, followAt: null, mode: 'frames', loop: null, bar: null,
};

// A clay-like matcap (lit sphere) drawn once: shape only, no lights needed.
function matcapTexture() {
  const c = document.createElement('canvas');
  c.width = c.height = 256;
  const g = c.getContext('2d'), r = g.createRadialGradient(98, 88, 8, 128, 128, 128);
  r.addColorStop(0, '#fbf3ea');
  r.addColorStop(0.45, '#c9ad98');
  r.addColorStop(0.85, '#6d5548');
  r.addColorStop(1, '#3b2d26');
  g.fillStyle = '#3b2d26';
  g.fillRect(0, 0, 256, 256);
  g.fillStyle = r;
  g.beginPath();
  g.arc(128, 128, 128, 0, 2 * Math.PI);
  g.fill();
  const t = new THREE.CanvasTexture(c);
  t.colorSpace = THREE.SRGBColorSpace;
  return t;
}
const MATCAP = matcapTexture();

function line(points, colour) {
  const g = new THREE.BufferGeometry().setFromPoints(points.map((p) => new THREE.Vector3(p[0], p[1], p[2])));
  return new THREE.Line(g, new THREE.LineBasicMaterial({ color: colour }));
}

// Box of every frame of an item and its overlay, in the item's own coordinates: the camera and
// the grid are set from it, so nothing the animation does later leaves the view. Also the
// largest box of any single frame (the follow camera frames one frame at a time).
function animationBox(m, positions, frameSet) {
  const box = new THREE.Box3(), p = new THREE.Vector3(), frame = new THREE.Box3(), size = new THREE.Vector3();
  const largest = new THREE.Vector3();
  const starts = frameSet ? frameSet.v.map((v) => 3 * v) : [...Array(m.n_frames + 1).keys()].map((f) => 3 * f * m.n_vertices);
  for (let f = 0; f < m.n_frames; f++) {
    frame.makeEmpty();
    for (let i = starts[f]; i < starts[f + 1]; i += 3) frame.expandByPoint(p.set(positions[i], positions[i + 1], positions[i + 2]));
    largest.max(frame.getSize(size));
    box.union(frame);
  }
  if (m.overlay) for (const q of [...(m.overlay.curve || []), ...m.overlay.centres]) box.expandByPoint(p.set(q[0], q[1], q[2]));
  return { box, largest };
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

// A text sprite (grid label, figure label): `height` in world units, anchored at `center`.
function textSprite(text, height, colour = '#555', center = [0, 0]) {
  const c = document.createElement('canvas'), g = c.getContext('2d');
  const font = '600 48px system-ui, sans-serif';
  g.font = font;
  c.width = Math.ceil(g.measureText(text).width) + 16;
  c.height = 64;
  g.font = font;
  g.fillStyle = colour;
  g.textBaseline = 'middle';
  g.fillText(text, 8, 32);
  const texture = new THREE.CanvasTexture(c);
  texture.colorSpace = THREE.SRGBColorSpace;
  const sprite = new THREE.Sprite(new THREE.SpriteMaterial({ map: texture, depthWrite: false }));
  sprite.center.set(center[0], center[1]);
  sprite.scale.set(height * c.width / c.height, height, 1);
  return sprite;
}

async function load() {
  const meta = await (await fetch('/api/items')).json();
  if (meta.report) $('report').innerHTML = `<a href="${meta.report}" target="_blank">open the report</a>`;
  const list = [];
  for (let k = 0; k < meta.items.length; k++) {
    const m = meta.items[k];
    const played = m.played ? await openPlayed(m, k) : null;  // a stream or rig the page decodes (formats_player.js)
    const [pos, faces, colours, uvBytes, textures, field] = await Promise.all([
      played ? played.positions.buffer : fetchBytes(`/api/items/${k}/positions`),
      played ? played.faces.buffer : fetchBytes(`/api/items/${k}/faces`),
      m.has_colours ? fetchBytes(`/api/items/${k}/colours`) : null,
      m.has_uvs ? fetchBytes(`/api/items/${k}/uvs`) : null,
      loadTextures(k, m.n_textures),
      m.has_field ? fetchBytes(`/api/items/${k}/field`) : null,
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
    const partColours = colours ? new THREE.BufferAttribute(new Float32Array(colours), 3) : null;
    if (partColours) geometry.setAttribute('color', partColours);
    // A per-vertex scalar field ([frames][vertices]) drawn as colours in the colour-map mode.
    const fieldValues = field ? new Float32Array(field) : null;
    const fieldColours = field ? new THREE.BufferAttribute(new Float32Array(3 * m.n_vertices), 3) : null;
    if (fieldColours) fieldColours.setUsage(THREE.DynamicDrawUsage);
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
    // The other looks: a neutral grey, a matcap (shape only), the colour map.
    const looks = {
      frames: material,
      neutral: new THREE.MeshStandardMaterial({ color: NEUTRAL, roughness: 0.8, side: THREE.DoubleSide }),
      matcap: new THREE.MeshMatcapMaterial({ matcap: MATCAP, side: THREE.DoubleSide }),
      field: new THREE.MeshStandardMaterial({ color: 0xffffff, vertexColors: true, roughness: 0.8, side: THREE.DoubleSide }),
    };
    const mesh = new THREE.Mesh(geometry, material);
    mesh.name = 'figure';
    mesh.frustumCulled = false;  // its bounding sphere is frame 0's
    const group = new THREE.Group();   // the item, in its own coordinates
    group.add(mesh);
    // The centre track at the height the synthesis measured it (hip height): optional.
    const hip = m.overlay ? line(m.overlay.centres, HIP) : null;
    if (hip) { hip.name = 'centre at hip height'; hip.visible = $('hip').checked; group.add(hip); }
    const turned = new THREE.Group();  // turned so its up axis is +Y
    turned.rotation.copy(upRotation(m.up));
    turned.add(group);
    const placed = new THREE.Group();  // moved aside for side-by-side playback
    placed.add(turned);
    scene.add(placed);
    if (played) played.attach(group, mesh);
    const hue = new THREE.Color().setHSL((k * 0.61803) % 1, 0.6, 0.5);
    const { box, largest } = played && played.box ? played.box : animationBox(m, positions, frameSet);
    list.push({ meta: m, played, positions, faces: faceArray, frameSet, nv: m.n_vertices, geometry, material, looks, mesh, group, placed,
      turned, hue, uvs, textures, box, largest, hip, partColours, fieldValues, fieldColours, ghosts: [], label: null, errorRow: null });
    const vertices = frameSet ? `${m.frame_vertices.reduce((a, b) => Math.min(a, b))}-${m.n_vertices} vertices (a mesh per frame)` : `${m.n_vertices} vertices`;
    const row = document.createElement('div');
    row.textContent = `${m.label || m.name}: ${m.n_frames} frames, ${vertices}, ${m.fps} fps` +
      (m.synthetic.some((s) => s) ? `, ${m.synthetic.filter((s) => s).length} synthetic` : '');
    $('items').appendChild(row);
    for (const c of (m.overlay && m.overlay.constraints) || []) {
      const line = document.createElement('div');
      line.className = 'constraint';
      line.textContent = c;
      $('items').appendChild(line);
    }
    if (m.overlay && m.overlay.centre_errors) {
      const e = document.createElement('div');
      e.className = 'constraint centre-error';
      $('items').appendChild(e);
      list[list.length - 1].errorRow = e;
    }
  }
  state.items = list;
  state.fps = list[0].meta.fps;
  state.frames = Math.max(...list.map((it) => it.meta.n_frames));
  // The colour map's option only when an item has one; then it is what the page starts with.
  const hasField = list.some((it) => it.fieldValues);
  $('mode-field').hidden = !hasField;
  $('mode-field').disabled = !hasField;
  if (hasField) $('mode').value = 'field';
  else if ($('mode').value === 'field') $('mode').value = 'frames';
  state.mode = $('mode').value;
  // Frame sets draw each frame's own mesh: no onion skin for them.
  $('onion').disabled = list.every((it) => it.frameSet);
  // Labels by default when figures could be mistaken for one another, or were given labels.
  $('labels').checked = list.length > 1 || list.some((it) => it.meta.label);
  $('loop-from').max = $('loop-to').max = state.frames - 1;
  if (!state.loop) $('loop-to').value = state.frames - 1;
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
  const tag = textSprite(text, height);
  // Just in front of the footprint's near left corner, as `frameCamera` looks at it.
  if (size.z > size.x) tag.position.set(box.max.x + 0.25 * step, y, box.max.z);
  else tag.position.set(box.min.x, y, box.max.z + 0.25 * step);
  ground.add(tag);
  state.grid = { step, units: state.items[0].meta.units, text, tag: tag.position.clone(), height, y, extent };
}

// The requested path and the achieved centre track projected onto the ground plane (the grid's
// height), where they can be compared from any view: the synthesis measures the path error in
// that plane. World coordinates, so each item's turn and side-by-side place are applied first.
function buildGroundTracks() {
  groundTracks.clear();
  const y = state.grid.y, p = new THREE.Vector3();
  for (const it of state.items) {
    const o = it.meta.overlay;
    if (!o) continue;
    const flat = (pts, colour, name) => {
      const world = pts.map((q) => p.set(q[0], q[1], q[2]).applyMatrix4(it.group.matrixWorld).clone().setY(y));
      const l = new THREE.Line(new THREE.BufferGeometry().setFromPoints(world), new THREE.LineBasicMaterial({ color: colour }));
      l.name = name;
      l.renderOrder = 1;  // over the grid where they cross
      groundTracks.add(l);
    };
    if (o.curve) flat(o.curve, PATH, 'requested path');
    flat(o.centres, CENTRE, 'achieved centre on the ground');
  }
}

// The part of the view the info panel leaves free: right of it or below it, whichever lets the
// scene be drawn larger (measured in `fitCamera`). Rectangles are in view pixels. The bare
// scene (`?ui=0`) has the whole view.
function freeRegions(W, H) {
  const m = 12;
  if (BARE) return [{ x: m, y: m, w: W - 2 * m, h: H - 2 * m }];
  const v = $('view').getBoundingClientRect(), p = $('panel').getBoundingClientRect();
  const right = p.right - v.left + m, below = p.bottom - v.top + m;
  return [
    { x: right, y: m, w: W - right - m, h: H - 2 * m },
    { x: m, y: below, w: W - 2 * m, h: H - below - m },
  ].filter((r) => r.w > 40 && r.h > 40);
}

// Where the camera looks from (unit vector from the target to the camera) for each preset:
// top looks down (-y, the screen's up is -z), front along -z, side along -x, three-quarter
// from the front right and above; follow as three-quarter, following the first figure.
function presetDirection(view, size) {
  switch (view) {
    case 'top': return new THREE.Vector3(0, 1, 1e-4).normalize();
    case 'front': return new THREE.Vector3(0, 0, 1);
    case 'side': return new THREE.Vector3(1, 0, 0);
    case 'three-quarter': case 'follow': return new THREE.Vector3(1, 0.6, 1).normalize();
    default:
      // Looking across the longer side of the ground footprint (a walk along z is seen from the side).
      return (size.z > size.x ? new THREE.Vector3(1.6, 0.5, -0.2) : new THREE.Vector3(0.2, 0.5, 1.6)).normalize();
  }
}

// Puts the camera on `dir` from `c` where every point of `pts` projects inside a free region,
// centred there: the principal point moves to the region's centre through `setViewOffset`, so
// orbiting still turns about `c`.
function fitCamera(pts, c, dir) {
  const v = $('view'), W = v.clientWidth, H = Math.max(1, v.clientHeight);
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
  const radius = Math.max(...pts.map((p) => p.distanceTo(c))) || 1e-3;
  camera.position.copy(c).addScaledVector(dir, d);
  camera.near = Math.max(radius / 1000, (d - radius) / 10);
  camera.far = d + 100 * radius;
  camera.updateProjectionMatrix();
  controls.target.copy(c);
  controls.update();
  state.region = r;
}

const corners = (box) => [...Array(8).keys()].map((k) =>
  new THREE.Vector3(k & 1 ? box.max.x : box.min.x, k & 2 ? box.max.y : box.min.y, k & 4 ? box.max.z : box.min.z));

// The camera of the current view: the whole animation (and the grid's label) in view from the
// preset's direction, or, following, the largest single frame of the first figure around where
// it is now.
function frameCamera() {
  const box = sceneBox(), size = box.getSize(new THREE.Vector3());
  const dir = presetDirection(state.view, size);
  if (state.view === 'follow') {
    const it = state.items[0], c = figureBox(it).getCenter(new THREE.Vector3());
    const half = it.largest.clone().applyMatrix3(new THREE.Matrix3().setFromMatrix4(it.turned.matrixWorld));
    half.set(Math.abs(half.x), Math.abs(half.y), Math.abs(half.z)).multiplyScalar(0.6);
    fitCamera(corners(new THREE.Box3(c.clone().sub(half), c.clone().add(half))), c, dir);
    state.followAt = c;
    return;
  }
  const pts = corners(box);
  if (state.grid) pts.push(state.grid.tag.clone().add(new THREE.Vector3(0, state.grid.height, 0)));
  fitCamera(pts, box.getCenter(new THREE.Vector3()), dir);
  state.followAt = null;
}

// The box of the frame an item shows now, in world coordinates.
function figureBox(it) {
  it.geometry.computeBoundingBox();
  it.mesh.updateMatrixWorld(true);
  const b = it.geometry.boundingBox.clone();
  // A frame set's attribute holds stale vertices past this frame's: bound only its own.
  if (it.frameSet) {
    b.makeEmpty();
    const a = it.geometry.getAttribute('position').array, p = new THREE.Vector3();
    for (let i = 0; i < 3 * it.nv; i += 3) b.expandByPoint(p.set(a[i], a[i + 1], a[i + 2]));
  }
  return b.applyMatrix4(it.mesh.matrixWorld);
}

// Labels over the figures: the `--labels` given, else the sequences' names; drawn when asked
// and whenever several figures are shown (side by side they look alike).
function buildLabels() {
  labels.clear();
  const height = 0.045 * (state.grid ? state.grid.extent : 1);
  for (const it of state.items) {
    const colour = $('hues').checked ? hex(it.hue) : '#333';
    it.label = textSprite(it.meta.label || it.meta.name, height, colour, [0.5, 0]);
    it.label.name = 'label';
    it.label.material.depthTest = false;
    it.label.renderOrder = 3;
    labels.add(it.label);
  }
  labels.visible = $('labels').checked;
}

function placeLabels() {
  const lift = 0.02 * (state.grid ? state.grid.extent : 1);
  for (const it of state.items) {
    if (!it.label) continue;
    const b = figureBox(it), c = b.getCenter(new THREE.Vector3());
    it.label.position.set(c.x, b.max.y + lift, c.z);
  }
}

function arrange() {
  layout();
  buildGrid(sceneBox());
  buildGroundTracks();
  buildLabels();
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

// What each item draws in the current mode: its frame colours (or parts, or texture), neutral
// grey, the matcap, or its colour map (items without one keep their frame colours).
function look(it) {
  return state.mode === 'field' && !it.fieldValues ? 'frames' : state.mode;
}

// Only what is drawn: frame colours that occur (or the sequences' own colours), the looks and
// overlays in use, the grid's square.
function buildLegend() {
  const entries = [];
  const framed = state.items.filter((it) => look(it) === 'frames');
  for (const it of framed) for (const [colour, text] of it.meta.colour_legend || []) entries.push([colour, text]);
  if (framed.some((it) => it.meta.frame_textures)) entries.push(['#a0a0a0', 'texture per frame']);
  const plain = framed.filter((it) => !it.meta.has_colours && !it.meta.frame_textures);
  if ($('hues').checked) {
    for (const it of plain) entries.push([hex(it.hue), it.meta.name]);
  } else {
    const labels = plain.flatMap((it) => it.meta.synthetic);
    if (labels.some((s) => !s)) entries.push([hex(GREEN), 'original frame']);
    if (labels.some((s) => s)) entries.push([hex(RED), 'synthetic frame']);
  }
  if (state.mode === 'neutral') entries.push([hex(NEUTRAL), 'neutral material']);
  if (state.mode === 'matcap') entries.push(['#c9ad98', 'matcap (shape only)']);
  if (state.items.some((it) => look(it) === 'field')) entries.push([hex(VIRIDIS[4]), 'colour map (see its bar)']);
  if ($('onion').checked && state.items.some((it) => !it.frameSet)) {
    entries.push([hex(PAST), 'earlier frames (onion skin)'], [hex(FUTURE), 'later frames (onion skin)']);
  }
  if (state.items.some((it) => it.meta.overlay && it.meta.overlay.curve)) entries.push([hex(PATH), 'requested path (on the ground)']);
  if (state.items.some((it) => it.meta.overlay)) entries.push([hex(CENTRE), 'achieved centre of mass (on the ground)']);
  if ($('hip').checked && state.items.some((it) => it.meta.overlay)) entries.push([hex(HIP), 'centre of mass at its height']);
  if (state.items.some((it) => it.meta.overlay && it.meta.overlay.transitions.length)) entries.push([hex(TRANSITION), 'transition (timeline)']);
  if (state.grid) entries.push([hex(GRID), `grid: ${state.grid.text}`]);
  $('legend').replaceChildren(...entries.map(([colour, text]) => {
    const row = document.createElement('div'), swatch = document.createElement('span');
    swatch.style.background = colour;
    row.append(swatch, text);
    return row;
  }));
  state.legend = entries.map(([, text]) => text);
  buildColourBar();
}

// A short number for the bar's ticks.
function tickText(x) {
  if (x === 0) return '0';
  const a = Math.abs(x);
  return a >= 1e4 || a < 1e-3 ? x.toExponential(1) : Number(x.toPrecision(3)).toString();
}

// The colour bar of the colour map drawn: its name, range and unit, one range over every item
// that has the field (so the items' colours compare).
function buildColourBar() {
  const shown = state.items.filter((it) => look(it) === 'field');
  const el = $('colourbar');
  if (!shown.length) { el.hidden = true; state.bar = null; return; }
  const fields = shown.map((it) => it.meta.field);
  const lo = Math.min(...fields.map((f) => f.range[0])), hi = Math.max(...fields.map((f) => f.range[1]));
  const max = Math.max(...fields.map((f) => f.max));
  const names = [...new Set(fields.map((f) => f.name))], units = [...new Set(fields.map((f) => f.unit))];
  state.bar = { name: names.join('; '), unit: units.join(', '), range: [lo, hi], max, about: fields[0].about };
  $('bar-name').textContent = `${state.bar.name} (${state.bar.unit})`;
  $('bar-name').title = state.bar.about;
  const c = $('bar-gradient'), g = c.getContext('2d'), col = new THREE.Color();
  for (let x = 0; x < c.width; x++) {
    g.fillStyle = `#${viridis(x / (c.width - 1), col).getHexString(THREE.SRGBColorSpace)}`;
    g.fillRect(x, 0, 1, c.height);
  }
  const ticks = [0, 0.25, 0.5, 0.75, 1].map((t) => {
    const s = document.createElement('span');
    // Values above the range (the top 1%) are drawn in the top colour: the bar says so.
    s.textContent = (t === 1 && max > hi ? '≥ ' : '') + tickText(lo + t * (hi - lo)) + (t === 1 ? ` ${state.bar.unit}` : '');
    if (t === 1 && max > hi) s.title = `largest ${tickText(max)} ${state.bar.unit}`;
    return s;
  });
  $('bar-ticks').replaceChildren(...ticks);
  el.hidden = false;
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

// The timeline: one row per item, green and red spans, the loop range, and the current frame.
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
  // Outside the loop range: dimmed.
  if (state.loop) {
    g.fillStyle = 'rgba(255,255,255,0.7)';
    g.fillRect(0, 0, x(state.loop[0]), H);
    g.fillRect(x(state.loop[1] + 1), 0, W - x(state.loop[1] + 1), H);
  }
  g.fillStyle = '#111';
  const w = Math.max(2, W / state.frames);
  g.fillRect(Math.min(W - w, x(state.frame)), 0, w, H);
}

// Onion skin: `count` earlier and later frames, `step` frames apart, drawn see-through (earlier
// blue, later orange, fainter further away) with the figure's own triangles.
function ghost(it, j) {
  while (it.ghosts.length <= j) {
    const g = new THREE.BufferGeometry();
    const a = new THREE.BufferAttribute(new Float32Array(3 * it.meta.n_vertices), 3);
    a.setUsage(THREE.DynamicDrawUsage);
    g.setAttribute('position', a);
    g.setIndex(it.geometry.getIndex());
    const m = new THREE.MeshStandardMaterial({ transparent: true, depthWrite: false, roughness: 0.9, side: THREE.DoubleSide });
    const mesh = new THREE.Mesh(g, m);
    mesh.name = 'onion skin';
    mesh.frustumCulled = false;
    mesh.renderOrder = 2;
    it.group.add(mesh);
    it.ghosts.push(mesh);
  }
  return it.ghosts[j];
}

function showGhosts(it, k) {
  const on = $('onion').checked && !it.frameSet;
  const count = on ? Math.max(1, Math.min(5, Number($('onion-count').value) || 2)) : 0;
  const step = Math.max(1, Number($('onion-step').value) || 5), n = 3 * it.meta.n_vertices;
  for (const g of it.ghosts) g.visible = false;
  for (let j = 1; on && j <= count; j++) {
    for (const [side, f] of [[0, k - j * step], [1, k + j * step]]) {
      if (f < 0 || f >= it.meta.n_frames) continue;
      const g = ghost(it, 2 * (j - 1) + side), a = g.geometry.getAttribute('position');
      a.array.set(it.positions.subarray(f * n, (f + 1) * n));
      a.needsUpdate = true;
      g.geometry.computeVertexNormals();
      g.material.color.copy(side ? FUTURE : PAST);
      g.material.opacity = 0.35 / j;
      g.material.wireframe = $('wireframe').checked;
      g.visible = true;
    }
  }
}

// The item's colour map at its frame `k`, onto its colour attribute.
function paintField(it, k) {
  const nv = it.meta.n_vertices, v = it.fieldValues, out = it.fieldColours.array, c = new THREE.Color();
  const [lo, hi] = state.bar ? state.bar.range : it.meta.field.range, span = hi > lo ? hi - lo : 1;
  for (let i = 0; i < nv; i++) {
    viridis((v[k * nv + i] - lo) / span, c);
    out[3 * i] = c.r; out[3 * i + 1] = c.g; out[3 * i + 2] = c.b;
  }
  it.fieldColours.needsUpdate = true;
}

function showFrame(f) {
  state.frame = f;
  for (const it of state.items) {
    const m = it.meta, n = 3 * m.n_vertices;
    const k = it.played ? it.played.frame(f % m.n_frames) : f % m.n_frames;  // shorter sequences loop
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
    const kind = look(it);
    it.mesh.material = it.looks[kind];
    for (const mat of Object.values(it.looks)) mat.wireframe = $('wireframe').checked;
    // The colour attribute: the colour map's in its mode, else the parts' (when given).
    const want = kind === 'field' ? it.fieldColours : it.partColours;
    if (want && it.geometry.getAttribute('color') !== want) it.geometry.setAttribute('color', want);
    if (!want && it.geometry.getAttribute('color')) it.geometry.deleteAttribute('color');
    if (kind === 'field') paintField(it, k);
    if (m.frame_textures) it.material.map = it.textures[m.frame_textures[k]];
    else if (!m.has_colours) it.material.color.copy($('hues').checked ? it.hue : (m.synthetic[k] ? RED : GREEN));
    showGhosts(it, k);
    if (it.errorRow) {
      const e = m.overlay.centre_errors, worst = e.reduce((b, x, i) => (x > e[b] ? i : b), 0);
      it.errorRow.textContent = `centre's distance from the path: ${tickText(e[k])} ${m.units} at this frame; ` +
        `largest ${tickText(e[worst])} ${m.units} (frame ${m.name}:${worst})`;
    }
  }
  placeLabels();
  follow();
  const first = state.items[0].meta, k = f % first.n_frames;
  $('counter').textContent =
    `frame ${f} / ${state.frames - 1} (${first.name}:${k}, ${first.synthetic[k] ? 'synthetic' : 'original'}) ${(f / state.fps).toFixed(2)} s`;
  drawTrack();
}

// The follow camera moves with the first figure: the target and the camera shift by how far
// the figure's centre moved, so an orbit the user made is kept.
function follow() {
  if (state.view !== 'follow' || !state.followAt) return;
  const c = figureBox(state.items[0]).getCenter(new THREE.Vector3()), d = c.clone().sub(state.followAt);
  camera.position.add(d);
  controls.target.add(d);
  state.followAt = c;
}

function setPlaying(on) {
  state.playing = on;
  $('play').textContent = on ? 'Pause' : 'Play';
}

// Shows frame `f` paused, wrapping around the ends.
function seek(f) {
  setPlaying(false);
  const n = state.frames, g = ((Math.round(f) % n) + n) % n;
  state.pos = g + 0.5;
  showFrame(g);
}

function renderNow() {
  controls.update();
  renderer.render(scene, camera);
}

function setView(preset) {
  if (preset !== null && !PRESETS.includes(preset)) {
    throw new Error(`unknown view ${JSON.stringify(preset)}: expected one of ${PRESETS.join(', ')}`);
  }
  state.view = preset;
  for (const b of document.querySelectorAll('#views button')) b.classList.toggle('on', b.dataset.view === String(preset));
  frameCamera();
  renderNow();
}

function setMode(mode) {
  $('mode').value = mode;
  state.mode = $('mode').value;
  buildLegend();
  showFrame(state.frame);
}

// The loop range `[a, b]` (frames, inclusive), or none: playback wraps inside it.
function setLoop(a, b) {
  if (a === null) {
    state.loop = null;
    $('loop').checked = false;
  } else {
    const lo = Math.max(0, Math.min(a, b)), hi = Math.min(state.frames - 1, Math.max(a, b));
    state.loop = [lo, hi];
    $('loop').checked = true;
    $('loop-from').value = lo;
    $('loop-to').value = hi;
  }
  drawTrack();
}

// A frame typed as a number (`57`) or as `sequence:frame` (`walk:12`): shown paused; an error
// names what exists.
function gotoFrame(text) {
  const s = text.trim(), err = $('goto-error');
  err.textContent = '';
  const m = /^(?:(.*):)?(\d+)$/.exec(s);
  if (!m) { err.textContent = `"${s}": expected a frame number or sequence:frame`; return false; }
  const f = Number(m[2]);
  let n = state.frames;
  if (m[1] !== undefined) {
    const it = state.items.find((x) => x.meta.name === m[1]);
    if (!it) { err.textContent = `no sequence "${m[1]}"; there are ${state.items.map((x) => x.meta.name).join(', ')}`; return false; }
    n = it.meta.n_frames;
  }
  if (f >= n) { err.textContent = `${m[1] !== undefined ? m[1] : 'the animation'} has ${n} frames (0 to ${n - 1})`; return false; }
  seek(f);
  return true;
}

$('play').addEventListener('click', () => setPlaying(!state.playing));
// The select gives the keyboard back, so the arrow keys step frames again rather than the speed.
$('speed').addEventListener('change', () => { state.speed = Number($('speed').value); $('speed').blur(); });
$('side').addEventListener('change', arrange);
$('hues').addEventListener('change', () => { buildLabels(); buildLegend(); showFrame(state.frame); });
$('labels').addEventListener('change', () => { labels.visible = $('labels').checked; });
$('hip').addEventListener('change', () => {
  for (const it of state.items) if (it.hip) it.hip.visible = $('hip').checked;
  buildLegend();
});
$('mode').addEventListener('change', () => { setMode($('mode').value); $('mode').blur(); });
for (const id of ['wireframe', 'onion', 'onion-count', 'onion-step']) {
  $(id).addEventListener('change', () => { buildLegend(); showFrame(state.frame); });
}
for (const b of document.querySelectorAll('#views button')) {
  b.addEventListener('click', () => setView(b.dataset.view === 'null' ? null : b.dataset.view));
}
const loopInputs = () => setLoop($('loop').checked ? Number($('loop-from').value) : null, Number($('loop-to').value));
for (const id of ['loop', 'loop-from', 'loop-to']) $(id).addEventListener('change', loopInputs);
$('goto').addEventListener('keydown', (e) => {
  if (e.key === 'Enter') { if (gotoFrame($('goto').value)) $('goto').blur(); e.preventDefault(); }
  e.stopPropagation();
});
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
  else if (e.key === '[') setLoop(state.frame, state.loop ? state.loop[1] : state.frames - 1);
  else if (e.key === ']') setLoop(state.loop ? state.loop[0] : 0, state.frame);
  else return;
  e.preventDefault();
});

// Projects a world point to view pixels.
function toScreen(p) {
  const v = $('view'), q = p.clone().project(camera);
  return { x: ((q.x + 1) / 2) * v.clientWidth, y: ((1 - q.y) / 2) * v.clientHeight };
}

// Pixel rectangle of the current frame's vertices of item `only` (every item when undefined),
// as drawn (for tests).
function screenBounds(only) {
  const v = $('view'), p = new THREE.Vector3(), r = { left: Infinity, top: Infinity, right: -Infinity, bottom: -Infinity };
  camera.updateMatrixWorld();
  for (const [k, it] of state.items.entries()) {
    if (only !== undefined && k !== only) continue;
    it.mesh.updateMatrixWorld(true);
    const a = it.geometry.getAttribute('position').array;
    for (let i = 0; i < 3 * it.nv; i += 3) {
      const s = toScreen(p.set(a[i], a[i + 1], a[i + 2]).applyMatrix4(it.mesh.matrixWorld));
      r.left = Math.min(r.left, s.x); r.right = Math.max(r.right, s.x);
      r.top = Math.min(r.top, s.y); r.bottom = Math.max(r.bottom, s.y);
    }
  }
  const pr = $('panel').getBoundingClientRect(), vr = v.getBoundingClientRect();
  return { subject: r, view: { width: v.clientWidth, height: v.clientHeight },
    panel: { left: pr.left - vr.left, top: pr.top - vr.top, right: pr.right - vr.left, bottom: pr.bottom - vr.top } };
}

// Removes every item from the scene (before `reload`).
function clear() {
  for (const it of state.items) {
    scene.remove(it.placed);
    it.geometry.dispose();
    for (const g of it.ghosts) g.geometry.dispose();
    for (const m of Object.values(it.looks)) m.dispose();
    for (const t of it.textures) t.dispose();
  }
  state.items = [];
  labels.clear();
  groundTracks.clear();
  $('items').replaceChildren();
}

let readyOnce = false;
async function start() {
  await load();
  showFrame(0);
  // What the address asks for: `?view=`, `?frame=`, `?loop=a-b`.
  const loop = /^(\d+)-(\d+)$/.exec(params.get('loop') || '');
  if (loop) setLoop(Number(loop[1]), Number(loop[2]));
  if (params.has('view')) setView(params.get('view'));
  if (params.has('frame')) window.surfcapViewer.setFrame(Number(params.get('frame')));
  window.surfcapViewer.ready = true;
  window.dispatchEvent(new Event('surfcap-ready'));
  if (!readyOnce) { readyOnce = true; requestAnimationFrame(tick); }
}

// For scripting, tests and `surfcap render`: the current frame, ways to set the frame and the
// view that render at once, the three.js objects, and what is drawn.
window.surfcapViewer = {
  ready: false,
  scene, camera, renderer, controls,
  get nFrames() { return state.frames; },
  get fps() { return state.fps; },
  // The ground plane's height (the grid's), in world coordinates.
  get groundY() { return state.grid ? state.grid.y : 0; },
  get unitSymbol() { return state.items.length ? state.items[0].meta.units : ''; },
  get frame() { return state.frame; },
  get frames() { return state.frames; },
  get playing() { return state.playing; },
  get speed() { return state.speed; },
  get view() { return state.view; },
  get mode() { return state.mode; },
  get loop() { return state.loop && state.loop.slice(); },
  get legend() { return state.legend.slice(); },
  get colourBar() { return state.bar && { ...state.bar, range: state.bar.range.slice() }; },
  get grid() { return state.grid && { step: state.grid.step, units: state.grid.units, text: state.grid.text }; },
  get overlays() { return state.items.map((it) => ({ curve: !!(it.meta.overlay && it.meta.overlay.curve), centres: !!it.meta.overlay })); },
  get spans() { return state.items.map((it) => spans(it.meta)); },
  get colours() { return state.items.map((it) => !!it.meta.has_colours); },
  // The labels drawn over the figures: text, the label's anchor and its figure's rectangle in
  // view pixels (empty when labels are hidden).
  get labels() {
    if (!labels.visible) return [];
    return state.items.map((it, k) => ({ text: it.meta.label || it.meta.name, at: toScreen(it.label.position), figure: screenBounds(k).subject }));
  },
  // The texture bound as each item's map now: its index among the item's textures (null: none).
  get boundTextures() { return state.items.map((it) => (it.material.map ? it.textures.indexOf(it.material.map) : null)); },
  // Vertices and triangles of the mesh drawn now, per item (a frame set's change frame by frame).
  get vertexCounts() { return state.items.map((it) => it.nv); },
  get triangleCounts() { return state.items.map((it) => it.geometry.drawRange.count === Infinity ? it.geometry.getIndex().count / 3 : it.geometry.drawRange.count / 3); },
  // Pauses, shows frame `f` (clamped to the animation) and renders it before returning.
  setFrame(f) {
    setPlaying(false);
    const g = Math.max(0, Math.min(state.frames - 1, Math.round(f)));
    state.pos = g + 0.5;
    showFrame(g);
    renderNow();
  },
  // 'top' | 'front' | 'side' | 'three-quarter' | 'follow' (null: the default framing); renders.
  setView,
  // 'frames' | 'neutral' | 'matcap' | 'field' (the colour map, when an item has one).
  setMode(mode) { setMode(mode); renderNow(); },
  setLoop,
  gotoFrame,
  screenBounds,
  // Fetches /api/items again and rebuilds the scene (what the server serves may have changed).
  async reload() {
    window.surfcapViewer.ready = false;
    clear();
    await start();
  },
};

let last = performance.now();
function tick(now) {
  const dt = (now - last) / 1000;
  last = now;
  if (state.items.length) {
    if (state.playing) {
      // Playback position in frames; it wraps inside the loop range, or the whole animation.
      const [a, b] = state.loop || [0, state.frames - 1], len = b - a + 1;
      state.pos += dt * state.speed * state.fps;
      if (state.pos < a || state.pos >= b + 1) state.pos = a + ((((state.pos - a) % len) + len) % len);
      const f = Math.min(b, Math.floor(state.pos));
      if (f !== state.frame) showFrame(f);
    }
    controls.update();
    renderer.render(scene, camera);
  }
  requestAnimationFrame(tick);
}

resize();
start().catch((e) => {
  $('error').textContent = `could not load: ${e.message}`;
  console.error(e);
});

// ---- director ----
// Directing from the page (web/director.js, web/graph_timeline.js), attached once the items are
// loaded, on the viewer's contract (window.surfcapViewer). What the director needs and the
// contract lacks is added here, only when missing: the scene's objects, the ground's height,
// play(), reload() (refetch /api/items and rebuild) and toItem(point, k) (a world point in item
// k's own axes, as the server's subject has them).
import { attachDirector } from './director.js';
{
  const whenReady = () => new Promise((resolve) => {
    const done = () => window.surfcapViewer && window.surfcapViewer.ready;
    if (done()) { resolve(); return; }
    window.addEventListener('surfcap-ready', () => resolve(), { once: true });
    const poll = setInterval(() => { if (done()) { clearInterval(poll); resolve(); } }, 100);
  });
  whenReady().then(() => {
    const v = window.surfcapViewer;
    const add = (name, value) => { if (!(name in v)) v[name] = value; };
    add('scene', scene);
    add('camera', camera);
    add('renderer', renderer);
    add('controls', controls);
    if (!('groundY' in v)) Object.defineProperty(v, 'groundY', { get: () => sceneBox().min.y });
    add('play', () => setPlaying(true));
    add('toItem', (p, k = 0) => state.items[k].turned.worldToLocal(p.clone()));
    add('reload', async () => {
      for (const it of state.items) {
        scene.remove(it.placed);
        it.geometry.dispose();
        it.material.dispose();
      }
      state.items = [];
      $('items').replaceChildren();
      await load();
      showFrame(0);
    });
    return attachDirector(v);
  }).catch((e) => {
    $('error').textContent = `directing is not available: ${e.message}`;
    console.error(e);
  });
}
// ---- end director ----

// ---- played files ----
// Streams and skinned rigs the page decodes itself (formats_player.js): `load` takes an item's
// positions and faces from `openPlayed` when the server marks it `played`, frames a stream by
// its grid box, lets the file attach what it draws to the item's group, and `showFrame` asks it
// which frame to draw (a rig poses its skeleton there; a stream holds its last decoded frame).
// `ready` (what `surfcap render` and tests wait for) also waits until every frame of every
// played file is decoded, so a script that sets frames gets each one; the page itself plays
// from the first decoded frame on.
import { openPlayed } from './formats_player.js';
{
  const v = window.surfcapViewer;
  let loaded = v.ready;
  Object.defineProperty(v, 'ready', {
    get: () => loaded && (window.surfcapPlayed || []).every((p) => !p || p.decoded === p.total),
    set: (x) => { loaded = x; },
    enumerable: true,
    configurable: true,
  });
}
// ---- end played files ----
