// surfcap viewer: plays the server's items (mesh sequences) with three.js.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

const GREEN = new THREE.Color(0x2e9e44), RED = new THREE.Color(0xd03030);
const $ = (id) => document.getElementById(id);

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

const state = { items: [], playing: true, time: 0, frame: 0, frames: 1, fps: 30 };

function resize() {
  const v = $('view');
  renderer.setSize(v.clientWidth, v.clientHeight);
  camera.aspect = v.clientWidth / Math.max(1, v.clientHeight);
  camera.updateProjectionMatrix();
}
window.addEventListener('resize', resize);

function line(points, colour) {
  const g = new THREE.BufferGeometry().setFromPoints(points.map((p) => new THREE.Vector3(p[0], p[1], p[2])));
  return new THREE.Line(g, new THREE.LineBasicMaterial({ color: colour }));
}

async function load() {
  const meta = await (await fetch('/api/items')).json();
  if (meta.report) $('report').innerHTML = `<a href="${meta.report}" target="_blank">open the report</a>`;
  const list = [];
  for (let k = 0; k < meta.items.length; k++) {
    const m = meta.items[k];
    const [pos, faces] = await Promise.all([fetchBytes(`/api/items/${k}/positions`), fetchBytes(`/api/items/${k}/faces`)]);
    const positions = new Float32Array(pos);
    const geometry = new THREE.BufferGeometry();
    const attr = new THREE.BufferAttribute(positions.slice(0, 3 * m.n_vertices), 3);
    attr.setUsage(THREE.DynamicDrawUsage);
    geometry.setAttribute('position', attr);
    geometry.setIndex(new THREE.BufferAttribute(new Uint32Array(faces), 1));
    geometry.computeVertexNormals();
    const material = new THREE.MeshStandardMaterial({ color: GREEN, roughness: 0.7, side: THREE.DoubleSide });
    const mesh = new THREE.Mesh(geometry, material);
    const group = new THREE.Group();   // the item, in its own coordinates
    group.add(mesh);
    if (m.overlay) {
      group.add(line(m.overlay.curve, 0x1f5fbf));
      group.add(line(m.overlay.centres, 0xe08a00));
    }
    const turned = new THREE.Group();  // turned so its up axis is +Y
    turned.rotation.copy(upRotation(m.up));
    turned.add(group);
    const placed = new THREE.Group();  // moved aside for side-by-side playback
    placed.add(turned);
    scene.add(placed);
    const hue = new THREE.Color().setHSL((k * 0.61803) % 1, 0.6, 0.5);
    list.push({ meta: m, positions, geometry, material, placed, turned, hue });
    const row = document.createElement('div');
    row.textContent = `${m.name}: ${m.n_frames} frames, ${m.n_vertices} vertices, ${m.fps} fps` +
      (m.synthetic.some((s) => s) ? `, ${m.synthetic.filter((s) => s).length} synthetic` : '');
    $('items').appendChild(row);
  }
  state.items = list;
  state.fps = list[0].meta.fps;
  state.frames = Math.max(...list.map((it) => it.meta.n_frames));
  $('scrub').max = String(state.frames - 1);
  layout();
  frameCamera();
}

// Side by side: each item's first-frame bounding box placed next to the previous one.
function layout() {
  let x = 0;
  for (const it of state.items) {
    it.placed.position.set(0, 0, 0);
    it.placed.updateMatrixWorld(true);
    const box = new THREE.Box3().setFromObject(it.turned);
    if ($('side').checked) {
      it.placed.position.x = x - box.min.x;
      x += box.max.x - box.min.x + 0.25 * (box.max.y - box.min.y);
    }
  }
}

function frameCamera() {
  const box = new THREE.Box3();
  for (const it of state.items) { it.placed.updateMatrixWorld(true); box.expandByObject(it.placed); }
  const c = box.getCenter(new THREE.Vector3()), s = box.getSize(new THREE.Vector3());
  const r = Math.max(s.x, s.y, s.z, 1e-3);
  camera.position.set(c.x + 0.2 * r, c.y + 0.5 * r, c.z + 1.6 * r);
  camera.near = r / 1000; camera.far = r * 100; camera.updateProjectionMatrix();
  controls.target.copy(c);
  controls.update();
}

function showFrame(f) {
  state.frame = f;
  for (const it of state.items) {
    const m = it.meta, k = f % m.n_frames, n = 3 * m.n_vertices;  // shorter sequences loop
    const attr = it.geometry.getAttribute('position');
    attr.array.set(it.positions.subarray(k * n, (k + 1) * n));
    attr.needsUpdate = true;
    it.geometry.computeVertexNormals();
    it.material.color.copy($('hues').checked ? it.hue : (m.synthetic[k] ? RED : GREEN));
  }
  const first = state.items[0].meta, k = f % first.n_frames;
  $('counter').textContent = `frame ${f} / ${state.frames - 1} (${first.synthetic[k] ? 'synthetic' : 'original'})`;
  $('scrub').value = String(f);
}

$('play').addEventListener('click', () => {
  state.playing = !state.playing;
  $('play').textContent = state.playing ? 'Pause' : 'Play';
});
$('scrub').addEventListener('input', () => {
  state.playing = false;
  $('play').textContent = 'Play';
  state.time = Number($('scrub').value) / state.fps;
  showFrame(Number($('scrub').value));
});
$('side').addEventListener('change', () => { layout(); frameCamera(); });
$('hues').addEventListener('change', () => showFrame(state.frame));

// For tests and scripting: the current frame and a way to jump.
window.surfcapViewer = {
  get frame() { return state.frame; },
  get frames() { return state.frames; },
  get playing() { return state.playing; },
  setFrame(f) { state.time = f / state.fps; showFrame(Math.max(0, Math.min(state.frames - 1, f))); },
  ready: false,
};

let last = performance.now();
function tick(now) {
  const dt = (now - last) / 1000;
  last = now;
  if (state.items.length) {
    if (state.playing) {
      state.time += dt;
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
