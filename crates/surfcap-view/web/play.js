// surfcap play: steer a captured character live (the server side and the design:
// crates/surfcap-view/src/play.rs). This page
// - reads the captured frames as a compact stream (.scstream) progressively and decodes it key
//   frame block by key frame block (each block starts with a key frame, so decodes on its own),
//   the start frame's block first, then any block a due frame needs, then the rest in order;
// - every animation frame, sends one step (the asked direction in the subject's ground axes, run
//   or not, the seconds since the last step) and shows the frames that fell due, each captured
//   frame or blended transition frame placed by the rigid ground motion the step gives;
// - fetches each transition's blended frames (streams of their own, piece by piece as the
//   server makes them) as soon as the step says the controller chose it; a blended frame due
//   before its exact mesh is here is drawn as its stand-in (the two captured frames Blend mixes,
//   placed as the step says, linearly interpolated: eq. 2.23) and counted as such; a frame
//   whose meshes are not decoded at all is shown as the last mesh moved along the centre track,
//   and counted as late;
// - draws the ground grid, the desired and the predicted trajectories, the centre track, the
//   clip and transition, what cannot be followed, and a frame-time graph.
// window.surfcapPlay exposes the state for scripts and tests.

import * as THREE from 'three';
import { decodeTriangles, frameDecoder, parseStream, decodeFrames } from './stream_decode.js';

const t0 = performance.now();
const $ = (id) => document.getElementById(id);
const state = {
  ready: false,
  error: null,
  firstFrameMs: null,
  allDecodedMs: null,
  framesShown: 0,
  decoded: 0,
  totalFrames: 0,
  centre: null,
  heading: null,
  speed: 0,
  commandHeading: null,
  commandSpeed: 0,
  fps: 0,
  frameMs: { p50: null, p99: null },
  rttMs: { p50: null, p99: null },
  bytes: { stream: 0, blends: 0, steps: 0 },
  streamComplete: false,
  late: { blend: 0, captured: 0 },
  // Blended frames shown exact (Blend's, from the server) and as stand-ins.
  blendsShown: 0,
  standIns: 0,
  transitions: 0,
  decisions: 0,
  cannotFollow: [],
  clip: null,
  steps: 0,
};
window.surfcapPlay = state;

function fail(e) {
  const msg = e && e.stack ? e.stack : String(e);
  state.error = msg;
  $('error').textContent = msg;
  console.error(msg);
}

// Rotation that turns the subject's up axis onto three.js's +Y (as the viewer does).
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

// ---- the captured stream, read progressively ----

class CapturedStream {
  constructor(info) {
    this.info = info;
    this.frames = new Array(info.frames);
    this.buf = null;
    this.got = 0;
    this.head = null; // { header, topology, chunkStart[], chunkEnd[] }
    this.blocks = []; // { first, count, end, done, decoding }
    this.wanted = new Set();
    this.waiting = [];
  }

  // Wakes whoever waits for more bytes or a wanted frame.
  poke() {
    const w = this.waiting;
    this.waiting = [];
    for (const f of w) f();
  }

  wait() {
    return new Promise((r) => this.waiting.push(r));
  }

  async fetch() {
    const r = await fetch('/api/play/stream');
    if (!r.ok) throw new Error(`/api/play/stream: HTTP ${r.status}`);
    const length = Number(r.headers.get('content-length'));
    this.buf = new Uint8Array(length > 0 ? length : this.info.stream.bytes);
    await r.body.pipeTo(new WritableStream({
      write: (value) => {
        if (this.got + value.length > this.buf.length) {
          const bigger = new Uint8Array(Math.max(this.buf.length * 2, this.got + value.length));
          bigger.set(this.buf.subarray(0, this.got));
          this.buf = bigger;
        }
        this.buf.set(value, this.got);
        this.got += value.length;
        state.bytes.stream = this.got;
        if (!this.head) this.parseHead();
        this.poke();
      },
    }));
    if (!this.head) throw new Error('the captured stream ended before its frame table');
    if (this.got !== this.head.end) throw new Error(`the captured stream has ${this.got} bytes, its table says ${this.head.end}`);
    state.streamComplete = true;
  }

  // The header, topology and frame table once their bytes are in (the layout parseStream reads).
  parseHead() {
    const b = this.buf;
    const dv = new DataView(b.buffer, 0, this.got);
    if (this.got < 12) return;
    const hl = dv.getUint32(8, true);
    if (this.got < 16 + hl) return;
    const tl = dv.getUint32(12 + hl, true);
    const tablePos = 16 + hl + tl;
    if (this.got < tablePos + 4) return;
    const n = dv.getUint32(tablePos, true);
    if (this.got < tablePos + 4 + 4 * n) return;
    const header = JSON.parse(new TextDecoder().decode(b.subarray(12, 12 + hl)));
    const topology = b.slice(16 + hl, 16 + hl + tl);
    const starts = [];
    let at = tablePos + 4 + 4 * n;
    for (let k = 0; k < n; k++) {
      starts.push(at);
      at += dv.getUint32(tablePos + 4 + 4 * k, true);
    }
    starts.push(at);
    this.head = { header, topology, starts, end: at };
    if (n !== this.info.frames) throw new Error(`the captured stream has ${n} frames, the subject ${this.info.frames}`);
    let g = 0;
    for (const s of header.sequences) {
      for (let f = 0; f < s.frames; f += header.key_interval) {
        const count = Math.min(header.key_interval, s.frames - f);
        this.blocks.push({ first: g + f, count, end: starts[g + f + count], done: false });
      }
      g += s.frames;
    }
    state.totalFrames = n;
  }

  blockOf(frame) {
    return this.blocks.find((b) => frame >= b.first && frame < b.first + b.count);
  }

  want(frame) {
    if (!this.frames[frame]) {
      this.wanted.add(frame);
      this.poke();
    }
  }

  async triangles() {
    while (!this.head) await this.wait();
    return decodeTriangles({ header: this.head.header, topology: this.head.topology });
  }

  // Decodes blocks as their bytes come: wanted ones first, then in order.
  async decodeAll() {
    while (!this.head) await this.wait();
    const h = this.head;
    for (;;) {
      const left = this.blocks.filter((b) => !b.done);
      if (left.length === 0) break;
      const ready = left.filter((b) => b.end <= this.got);
      let pick = null;
      for (const f of this.wanted) {
        const b = this.blockOf(f);
        if (b && !b.done && b.end <= this.got) { pick = b; break; }
      }
      if (!pick) pick = ready[0];
      if (!pick) {
        await this.wait();
        continue;
      }
      const chunks = [];
      for (let k = pick.first; k < pick.first + pick.count; k++) chunks.push(this.buf.subarray(h.starts[k], h.starts[k + 1]));
      const s = { header: { ...h.header, sequences: [{ frames: pick.count }] }, chunks };
      const d = frameDecoder(s);
      for (let k = 0; k < pick.count; k++) {
        this.frames[pick.first + k] = await d.next();
        this.wanted.delete(pick.first + k);
        state.decoded++;
      }
      pick.done = true;
    }
    state.allDecodedMs = performance.now() - t0;
  }
}

// ---- the scene ----

const view = $('view');
const renderer = new THREE.WebGLRenderer({ antialias: true });
renderer.setPixelRatio(window.devicePixelRatio);
view.appendChild(renderer.domElement);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0xf4f4f2);
const camera = new THREE.PerspectiveCamera(40, 1, 0.01, 1000);
scene.add(new THREE.HemisphereLight(0xffffff, 0x777777, 2.2));
const sun = new THREE.DirectionalLight(0xffffff, 1.6);
sun.position.set(2, 4, 3);
scene.add(sun);

function resize() {
  const w = view.clientWidth;
  const h = view.clientHeight;
  renderer.setSize(w, h);
  camera.aspect = w / Math.max(h, 1);
  camera.updateProjectionMatrix();
}
window.addEventListener('resize', resize);
resize();

function line(colour, width) {
  const g = new THREE.BufferGeometry();
  const l = new THREE.Line(g, new THREE.LineBasicMaterial({ color: colour, linewidth: width }));
  l.frustumCulled = false;
  scene.add(l);
  return l;
}

// ---- input: keyboard and gamepad ----

const held = new Set();
let stopLatched = false;
const KEYS = {
  KeyW: [0, -1], ArrowUp: [0, -1], KeyS: [0, 1], ArrowDown: [0, 1],
  KeyA: [-1, 0], ArrowLeft: [-1, 0], KeyD: [1, 0], ArrowRight: [1, 0],
};
window.addEventListener('keydown', (e) => {
  if (e.code === 'Space') {
    stopLatched = true;
    e.preventDefault();
  } else if (KEYS[e.code]) {
    held.add(e.code);
    stopLatched = false;
    e.preventDefault();
  }
});
window.addEventListener('keyup', (e) => held.delete(e.code));
window.addEventListener('blur', () => held.clear());

// The asked direction on the page's ground (x right, z towards the viewer), length 0 to 1, and
// whether to run.
function asked() {
  let x = 0;
  let z = 0;
  let run = held.has('ShiftLeft') || held.has('ShiftRight');
  for (const k of held) if (KEYS[k]) { x += KEYS[k][0]; z += KEYS[k][1]; }
  const pads = navigator.getGamepads ? navigator.getGamepads() : [];
  for (const p of pads) {
    if (!p) continue;
    const [ax, ay] = [p.axes[0] || 0, p.axes[1] || 0];
    if (Math.hypot(ax, ay) > 0.15) { x = ax; z = ay; }
    if (p.buttons[0] && p.buttons[0].pressed) run = true;
    if (p.buttons[1] && p.buttons[1].pressed) stopLatched = true;
    break;
  }
  const len = Math.hypot(x, z);
  if (stopLatched || len < 1e-3) return { x: 0, z: 0, run: false };
  const k = len > 1 ? 1 / len : 1;
  return { x: x * k, z: z * k, run };
}
window.addEventListener('keydown', (e) => { if (e.key === 'Shift') held.add(e.code); });

// ---- play ----

function percentile(v, q) {
  if (v.length === 0) return null;
  const s = [...v].sort((a, b) => a - b);
  return s[Math.min(s.length - 1, Math.floor(q * (s.length - 1) + 0.5))];
}

async function main() {
  // A new page starts a new walk from the start frame.
  const restarted = await fetch('/api/play/restart', { method: 'POST', headers: { 'Content-Type': 'application/json' }, body: '{}' });
  if (!restarted.ok) throw new Error(`/api/play/restart: HTTP ${restarted.status}: ${await restarted.text()}`);
  const info = await (await fetch('/api/play/info')).json();
  $('subject').textContent = `${info.subject} (${info.frames} frames of ${info.vertices} vertices, ${info.fps} fps)`;
  const [iu, iv] = info.ground_axes;
  const upAxis = 3 - iu - iv;
  const rot = upRotation(info.up);
  const quat = new THREE.Quaternion().setFromEuler(rot);
  const inverse = quat.clone().invert();
  const world = new THREE.Group();
  world.quaternion.copy(quat);
  scene.add(world);
  const toPage = (p) => new THREE.Vector3(p[0], p[1], p[2]).applyQuaternion(quat);

  const captured = new CapturedStream(info);
  const loading = captured.fetch();
  loading.catch(fail);
  const decoding = captured.decodeAll();
  decoding.catch(fail);
  captured.want(info.start.frame);

  const triangles = await captured.triangles();
  const n = info.vertices;
  const geometry = new THREE.BufferGeometry();
  const position = new THREE.BufferAttribute(new Float32Array(n * 3), 3);
  position.setUsage(THREE.DynamicDrawUsage);
  geometry.setAttribute('position', position);
  geometry.setIndex(new THREE.BufferAttribute(triangles, 1));
  const mesh = new THREE.Mesh(geometry, new THREE.MeshStandardMaterial({ color: 0x4caf50, roughness: 0.7, side: THREE.DoubleSide }));
  mesh.frustumCulled = false;
  world.add(mesh);

  // Wait for the start frame, then set the ground, grid and camera from it.
  while (!captured.frames[info.start.frame]) await new Promise((r) => setTimeout(r, 5));
  const start = captured.frames[info.start.frame];
  let groundY = Infinity;
  const v = new THREE.Vector3();
  for (let i = 0; i < n; i++) {
    v.set(start[3 * i], start[3 * i + 1], start[3 * i + 2]).applyQuaternion(quat);
    groundY = Math.min(groundY, v.y);
  }
  const h = info.height;
  const unitsPerMetre = info.metres_per_unit ? 1 / info.metres_per_unit : null;
  const cell = unitsPerMetre ? 0.5 * unitsPerMetre : h / 4;
  const grid = new THREE.GridHelper(cell * 80, 80, 0x999999, 0xcccccc);
  grid.position.y = groundY;
  scene.add(grid);
  $('grid-legend').textContent = `grid: 1 square = ${unitsPerMetre ? '0.5 m' : `${cell.toPrecision(2)} ${info.units}`}`;
  const desiredLine = line(0x2060d0, 2);
  const predictedLine = line(0xe07000, 2);
  const trackLine = line(0x777777, 1);
  const onGround = (p) => {
    const q = toPage(p);
    q.y = groundY + 0.002 * h;
    return q;
  };
  // A line's points replaced (a new geometry: a buffer keeps the size it was made with).
  const setPoints = (l, points) => {
    l.geometry.dispose();
    l.geometry = new THREE.BufferGeometry().setFromPoints(points);
  };
  const setLine = (l, points) => setPoints(l, points.map(onGround));

  // What is shown: the last mesh's positions (subject coordinates, placed) and centre.
  let shownCentre = null;
  const track = []; // centres of the frames shown, page ground coordinates {x, z}
  const showPositions = (src, theta, t) => {
    const out = position.array;
    const c = Math.cos(theta);
    const s = Math.sin(theta);
    for (let i = 0; i < n; i++) {
      const u = src[3 * i + iu];
      const w = src[3 * i + iv];
      out[3 * i + iu] = u * c + w * s + t[0];
      out[3 * i + iv] = -u * s + w * c + t[1];
      out[3 * i + upAxis] = src[3 * i + upAxis];
    }
    position.needsUpdate = true;
  };
  const moveShown = (from, to) => {
    const out = position.array;
    const d = [to[0] - from[0], to[1] - from[1], to[2] - from[2]];
    for (let i = 0; i < n; i++) {
      out[3 * i + iu] += d[iu];
      out[3 * i + iv] += d[iv];
    }
    position.needsUpdate = true;
  };

  const blends = new Map(); // id -> Float32Array[] of the frames decoded so far
  const requested = new Set();
  // A transition's frames, piece by piece: each answer holds the frames made so far from the
  // first one not here yet, and says how many the transition has.
  const fetchBlend = async (id) => {
    const got = [];
    blends.set(id, got);
    for (let total = Infinity; got.length < total;) {
      const url = `/api/play/blend/${id}/from/${got.length}`;
      const r = await fetch(url);
      if (!r.ok) throw new Error(`${url}: HTTP ${r.status}: ${await r.text()}`);
      total = Number(r.headers.get('x-blend-frames'));
      const b = await r.arrayBuffer();
      state.bytes.blends += b.byteLength;
      const frames = await decodeFrames(parseStream(b));
      if (!frames.length || !(total > 0)) throw new Error(`${url}: no frames (of ${total})`);
      got.push(...frames);
    }
  };
  // A blended frame's stand-in: the two captured frames placed and mixed (null when either is
  // not decoded yet).
  const standIn = (m) => {
    const a = captured.frames[m.a];
    const b = captured.frames[m.b];
    if (!a || !b) return null;
    const out = new Float32Array(3 * n);
    const [ta, ua, va] = m.ga;
    const [tb, ub, vb] = m.gb;
    const ca = Math.cos(ta), sa = Math.sin(ta), cb = Math.cos(tb), sb = Math.sin(tb);
    const l = m.lambda;
    for (let i = 0; i < n; i++) {
      const [x, y] = [a[3 * i + iu], a[3 * i + iv]];
      const [p, q] = [b[3 * i + iu], b[3 * i + iv]];
      out[3 * i + iu] = (1 - l) * (x * ca + y * sa + ua) + l * (p * cb + q * sb + ub);
      out[3 * i + iv] = (1 - l) * (-x * sa + y * ca + va) + l * (-p * sb + q * cb + vb);
      out[3 * i + upAxis] = (1 - l) * a[3 * i + upAxis] + l * b[3 * i + upAxis];
    }
    return out;
  };

  const show = (f) => {
    let src = null;
    if (f.frame !== undefined) {
      src = captured.frames[f.frame];
      if (!src) {
        captured.want(f.frame);
        state.late.captured++;
      }
    } else {
      const b = blends.get(f.blend);
      src = b ? b[f.k] : null;
      if (src) state.blendsShown++;
      else if (f.stand_in && (src = standIn(f.stand_in))) state.standIns++;
      else {
        if (f.stand_in) { captured.want(f.stand_in.a); captured.want(f.stand_in.b); }
        state.late.blend++;
      }
    }
    if (src) showPositions(src, f.theta, f.t);
    else if (shownCentre) moveShown(shownCentre, f.centre);
    shownCentre = f.centre;
    const p = toPage(f.centre);
    track.push({ x: p.x, z: p.z });
    if (track.length > 600) track.shift();
    state.framesShown++;
    state.clip = f.label;
    $('clip').textContent = f.label;
    $('transition').textContent = f.transition ? `${f.transition[0]} → ${f.transition[1]}` : '-';
    if (state.firstFrameMs === null && src) state.firstFrameMs = performance.now() - t0;
  };

  // Heading (degrees, from the page's +x towards -z: right is 0, up the screen 90) and speed of
  // the centre track over the last half second of frames.
  const motion = () => {
    const k = Math.max(1, Math.round(info.fps / 2));
    if (track.length <= k) return;
    const a = track[track.length - 1 - k];
    const b = track[track.length - 1];
    const dx = b.x - a.x;
    const dz = b.z - a.z;
    state.speed = Math.hypot(dx, dz) / (k / info.fps);
    state.heading = state.speed > 0.05 * h ? (Math.atan2(-dz, dx) * 180) / Math.PI : state.heading;
    state.centre = [b.x, b.z];
  };

  // Frames are shown `delay` ms after their step's answer (?delay=ms, default 100): the time a
  // transition's blend has to arrive before its first frame is due.
  const delay = Number(new URLSearchParams(location.search).get('delay') ?? 100);
  state.delayMs = delay;
  const pending = [];
  const rtts = [];
  const frameTimes = [];
  let lastStep = null;
  let inFlight = false;
  let lastFrameAt = null;
  const graph = $('graph').getContext('2d');
  const drawGraph = () => {
    const W = 300;
    const H = 60;
    graph.clearRect(0, 0, W, H);
    const scale = H / 50; // 50 ms tall
    graph.strokeStyle = '#c33';
    graph.beginPath();
    graph.moveTo(0, H - 16.7 * scale);
    graph.lineTo(W, H - 16.7 * scale);
    graph.stroke();
    graph.strokeStyle = '#333';
    graph.beginPath();
    frameTimes.slice(-W / 2).forEach((ms, i) => {
      const y = H - Math.min(ms, 50) * scale;
      if (i === 0) graph.moveTo(2 * i, y);
      else graph.lineTo(2 * i, y);
    });
    graph.stroke();
  };

  const step = async (now) => {
    inFlight = true;
    const a = asked();
    const d = new THREE.Vector3(a.x, 0, a.z).applyQuaternion(inverse);
    const direction = [d.getComponent(iu), d.getComponent(iv)];
    const dt = lastStep === null ? 0 : Math.min((now - lastStep) / 1000, 0.25);
    lastStep = now;
    state.commandSpeed = Math.hypot(a.x, a.z) * (a.run ? info.run_speed : info.walk_speed);
    state.commandHeading = state.commandSpeed > 0 ? (Math.atan2(-a.z, a.x) * 180) / Math.PI : null;
    const body = JSON.stringify({ direction, run: a.run, dt });
    const sent = performance.now();
    const r = await fetch('/api/play/step', { method: 'POST', headers: { 'Content-Type': 'application/json' }, body });
    const text = await r.text();
    rtts.push(performance.now() - sent);
    if (rtts.length > 600) rtts.shift();
    state.bytes.steps += text.length;
    if (!r.ok) throw new Error(`/api/play/step: HTTP ${r.status}: ${text}`);
    const s = JSON.parse(text);
    state.steps++;
    for (const b of s.blends) {
      if (requested.has(b.id)) continue;
      requested.add(b.id);
      fetchBlend(b.id).catch(fail);
    }
    const due = performance.now() + delay;
    for (const f of s.frames) pending.push({ f, due });
    state.decisions += s.decisions.length;
    state.transitions = s.transitions;
    if (s.decisions.length) {
      const last = s.decisions[s.decisions.length - 1];
      const chosen = last.chosen === 'continue' ? 'continue the clip' : `${last.chosen.from} → ${last.chosen.to}`;
      $('decisions').textContent = `${state.decisions} (last: ${chosen}, ${last.candidates} moves in ${last.ms.toFixed(3)} ms); ${s.transitions} transitions`;
    }
    if (s.cannot_follow !== null) {
      state.cannotFollow = s.cannot_follow;
      $('cannot').textContent = s.cannot_follow.map((c) => `cannot follow: ${c}`).join('\n');
    }
    setLine(desiredLine, s.desired);
    setLine(predictedLine, s.predicted);
    const speedText = (x) => `${x.toFixed(2)} ${info.units}/s`;
    $('asked').textContent = state.commandSpeed > 0
      ? `${a.run ? 'run' : 'walk'} ${speedText(state.commandSpeed)} heading ${state.commandHeading.toFixed(0)}°` : 'stop';
    $('moving').textContent = `${speedText(state.speed)}${state.heading !== null ? ` heading ${state.heading.toFixed(0)}°` : ''}`;
    inFlight = false;
  };

  $('loading').textContent = '';
  state.ready = true;
  document.dispatchEvent(new Event('surfcap-play-ready'));
  let fpsCount = 0;
  let fpsSince = performance.now();
  const frame = (now) => {
    requestAnimationFrame(frame);
    if (lastFrameAt !== null) {
      frameTimes.push(now - lastFrameAt);
      if (frameTimes.length > 600) frameTimes.shift();
    }
    lastFrameAt = now;
    fpsCount++;
    if (now - fpsSince >= 1000) {
      state.fps = (1000 * fpsCount) / (now - fpsSince);
      fpsCount = 0;
      fpsSince = now;
      state.frameMs = { p50: percentile(frameTimes, 0.5), p99: percentile(frameTimes, 0.99) };
      state.rttMs = { p50: percentile(rtts, 0.5), p99: percentile(rtts, 0.99) };
      $('fps').textContent = `${state.fps.toFixed(1)} page frames/s (p99 ${state.frameMs.p99?.toFixed(1)} ms)`;
      $('rtt').textContent = rtts.length ? `p50 ${state.rttMs.p50.toFixed(1)} ms, p99 ${state.rttMs.p99.toFixed(1)} ms` : '-';
      const kb = (x) => `${(x / 1e6).toFixed(2)} MB`;
      $('bytes').textContent = `stream ${kb(state.bytes.stream)} (${state.decoded}/${state.totalFrames} frames decoded), blends ${kb(state.bytes.blends)}, steps ${kb(state.bytes.steps)}`;
      $('late').textContent = `${state.late.blend + state.late.captured} (blended ${state.late.blend}, captured ${state.late.captured}); blended frames shown exact ${state.blendsShown}, as stand-ins ${state.standIns}`;
    }
    if (!inFlight) step(now).catch((e) => { inFlight = false; fail(e); });
    let shown = false;
    while (pending.length && pending[0].due <= performance.now()) {
      show(pending.shift().f);
      shown = true;
    }
    if (shown) motion();
    if (shownCentre) {
      const c = toPage(shownCentre);
      camera.position.set(c.x, groundY + 1.1 * h, c.z + 3.2 * h);
      camera.lookAt(c.x, groundY + 0.45 * h, c.z);
    }
    if (track.length > 1 && shown) setPoints(trackLine, track.map((p) => new THREE.Vector3(p.x, groundY + 0.001 * h, p.z)));
    drawGraph();
    renderer.render(scene, camera);
  };
  requestAnimationFrame(frame);
}

main().catch(fail);
