// Directing from the page (served with `surfcap view SUBJECT --direct`): draw a path on the
// ground, move key poses on the graph's timeline, ask for a distance in a time, or click a
// transition of the graph; the server synthesises it (POST /api/direct) and the page plays the
// result in place of what it showed. The last result downloads as glb, abc or usda.
// Relies on the viewer's contract (window.surfcapViewer: scene, camera, controls, renderer,
// groundY, unitSymbol, reload, setFrame) plus toItem(point) (world to the subject's own axes).
import * as THREE from 'three';
import { attachGraphTimeline } from './graph_timeline.js';

const DRAWN = 0x1f5fbf;

function el(tag, props = {}, ...children) {
  const e = Object.assign(document.createElement(tag), props);
  e.append(...children);
  return e;
}

export async function attachDirector(viewer) {
  // A viewer that only plays (no --direct) has no direction routes: ask nothing of them.
  const listed = await fetch('/api/items');
  if (!listed.ok || !(await listed.json()).direct) return null;
  const r = await fetch('/api/direct/graph');
  if (!r.ok) return null;
  const graph = await r.json();
  const status = { busy: false, last: null, error: null, requests: 0 };

  // The panel: the graph in words, the controls, what the last result achieved, exports.
  const css = el('style', { textContent: `
    #director { position: absolute; top: 8px; right: 8px; width: 19em; background: rgba(255,255,255,0.92);
      padding: 8px 10px; border-radius: 6px; font-size: 13px; }
    #director h2 { font-size: 14px; margin: 0 0 4px 0; }
    #director .row { margin: 4px 0; display: flex; gap: 4px; align-items: center; flex-wrap: wrap; }
    #director input[type=text] { width: 7.5em; } #director input[type=number] { width: 4.5em; }
    #director-result { color: #333; font-size: 12px; margin-top: 4px; white-space: pre-wrap; }
    #director-error { color: #b00; font-size: 12px; white-space: pre-wrap; }
    #director button.on { background: #1f5fbf; color: #fff; }
    #graph-box { position: absolute; left: 0; right: 0; bottom: 64px; background: #fff; border-top: 1px solid #ccc;
      max-height: 40vh; overflow-y: auto; }` });
  document.head.appendChild(css);
  const first = graph.sequences[0], lastSeq = graph.sequences[graph.sequences.length - 1];
  const drawBtn = el('button', { id: 'director-draw', textContent: 'Draw a path', title: 'then drag on the ground: the walk follows it when you let go' });
  const from = el('input', { type: 'text', id: 'reach-from', value: `${first.name}:0` });
  const to = el('input', { type: 'text', id: 'reach-to', value: `${lastSeq.name}:${Math.max(0, lastSeq.frames - 1)}` });
  const distance = el('input', { type: 'number', id: 'reach-distance', value: '3', step: 'any', min: '0' });
  const seconds = el('input', { type: 'number', id: 'reach-seconds', value: '4', step: 'any', min: '0.1' });
  const reachBtn = el('button', { id: 'director-reach', textContent: 'Reach' });
  const keysBtn = el('button', { id: 'director-keys', textContent: 'Time the key poses', disabled: true });
  const clearKeys = el('button', { id: 'director-clear-keys', textContent: 'Clear keys' });
  const reset = el('button', { id: 'director-reset', textContent: 'Show the captures' });
  const exports = ['glb', 'abc', 'usda'].map((f) => el('a', { href: `/api/direct/export/${f}`, download: '', id: `export-${f}`, textContent: f, title: `download the last result as .${f}` }));
  const exportRow = el('div', { className: 'row' }, 'export: ', ...exports.flatMap((a) => [a, ' ']));
  exportRow.style.visibility = 'hidden';
  const result = el('div', { id: 'director-result' });
  const error = el('div', { id: 'director-error' });
  const panel = el('div', { id: 'director' },
    el('h2', { textContent: 'Direct' }),
    el('div', { textContent: `${graph.subject}: ${graph.graph}` }),
    el('div', { className: 'row' }, drawBtn, reset),
    el('div', { className: 'row' }, 'from ', from, ' to ', to),
    el('div', { className: 'row' }, distance, ` ${graph.units} in `, seconds, ' s ', reachBtn),
    el('div', { className: 'row' }, keysBtn, clearKeys),
    result, error, exportRow);
  document.body.appendChild(panel);

  // The graph's timeline above the play bar; the 3D view gives it room.
  const box = el('div', { id: 'graph-box' });
  document.body.appendChild(box);
  let keys = [];
  const timeline = attachGraphTimeline(box, graph, {
    onTransition: (a) => send({ kind: 'transition', from: a.from_frame, to: a.to_frame }, `transition ${a.from_frame} -> ${a.to_frame}`),
    onKeysChanged: (k) => { keys = k; keysBtn.disabled = k.length < 2; },
  });
  const fit = () => {
    document.getElementById('view').style.bottom = `${64 + box.offsetHeight}px`;
    window.dispatchEvent(new Event('resize'));
  };
  fit();

  // Sends a direction; when the result comes, the page reloads its items and plays it. The time
  // from the request to the first frame of the result drawn is measured (the page's own clock).
  async function send(direction, what) {
    if (status.busy) return;
    status.busy = true;
    status.requests++;
    error.textContent = '';
    result.textContent = `synthesising ${what}...`;
    document.body.style.cursor = 'progress';
    const t0 = performance.now();
    try {
      const answer = await fetch('/api/direct', {
        method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify(direction),
      });
      const body = await answer.json();
      if (!answer.ok) throw new Error(body.error || `HTTP ${answer.status}`);
      const t1 = performance.now();
      await viewer.reload();
      viewer.setFrame(0);
      if (viewer.play) viewer.play();
      await new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r)));
      const t2 = performance.now();
      status.last = { kind: direction.kind, name: body.name, frames: body.frames, summary: body.summary,
        server_seconds: body.seconds, answer_seconds: (t1 - t0) / 1000, playing_seconds: (t2 - t0) / 1000 };
      result.textContent = `${body.summary.join('\n')}\n${body.frames} frames; synthesised in ${body.seconds.toFixed(2)} s, playing ${((t2 - t0) / 1000).toFixed(2)} s after the request`;
      exportRow.style.visibility = 'visible';
    } catch (e) {
      status.error = e.message;
      result.textContent = '';
      error.textContent = e.message;
    } finally {
      status.busy = false;
      document.body.style.cursor = '';
    }
  }

  reachBtn.addEventListener('click', () => send({
    kind: 'reach', from: from.value.trim(), to: to.value.trim(), distance: Number(distance.value), seconds: Number(seconds.value),
  }, `${distance.value} ${graph.units} in ${seconds.value} s`));
  keysBtn.addEventListener('click', () => send({ kind: 'keyposes', keys }, `${keys.length} key poses`));
  clearKeys.addEventListener('click', () => timeline.clearKeys());
  reset.addEventListener('click', async () => {
    const a = await fetch('/api/direct/reset', { method: 'POST', headers: { 'Content-Type': 'application/json' }, body: '{}' });
    if (a.ok) { await viewer.reload(); result.textContent = ''; timeline.playing = null; }
  });

  // Drawing on the ground: the pointer's ray meets the grid's plane; the stroke is shown while
  // drawn and sent, in the subject's own axes, when the pointer is let go.
  const canvas = viewer.renderer.domElement, ray = new THREE.Raycaster();
  let drawing = false, stroke = [], line = null;
  const groundPoint = (e) => {
    const rect = canvas.getBoundingClientRect();
    const ndc = new THREE.Vector2(((e.clientX - rect.left) / rect.width) * 2 - 1, -((e.clientY - rect.top) / rect.height) * 2 + 1);
    ray.setFromCamera(ndc, viewer.camera);
    const plane = new THREE.Plane(new THREE.Vector3(0, 1, 0), -viewer.groundY);
    return ray.ray.intersectPlane(plane, new THREE.Vector3());
  };
  const showStroke = () => {
    if (line) { viewer.scene.remove(line); line.geometry.dispose(); }
    line = new THREE.Line(new THREE.BufferGeometry().setFromPoints(stroke), new THREE.LineBasicMaterial({ color: DRAWN }));
    viewer.scene.add(line);
  };
  drawBtn.addEventListener('click', () => {
    drawing = !drawing;
    drawBtn.classList.toggle('on', drawing);
    drawBtn.textContent = drawing ? 'Drawing: drag on the ground' : 'Draw a path';
    viewer.controls.enabled = !drawing;
  });
  canvas.addEventListener('pointerdown', (e) => {
    if (!drawing) return;
    const p = groundPoint(e);
    if (!p) return;
    canvas.setPointerCapture(e.pointerId);
    stroke = [p];
    showStroke();
  });
  canvas.addEventListener('pointermove', (e) => {
    if (!drawing || !canvas.hasPointerCapture(e.pointerId)) return;
    const p = groundPoint(e);
    // A point every few centimetres of the view's scale is enough for the curve.
    if (p && p.distanceTo(stroke[stroke.length - 1]) > 0.01 * viewer.camera.position.distanceTo(p)) {
      stroke.push(p);
      showStroke();
    }
  });
  canvas.addEventListener('pointerup', (e) => {
    if (!drawing || !canvas.hasPointerCapture(e.pointerId)) return;
    canvas.releasePointerCapture(e.pointerId);
    drawBtn.click();  // one stroke per path; the camera orbits again
    const points = stroke.map((p) => viewer.toItem(p).toArray());
    if (line) { viewer.scene.remove(line); line.geometry.dispose(); line = null; }
    if (points.length < 2) { error.textContent = 'the drawn path needs at least two points: drag on the ground'; return; }
    send({ kind: 'path', points }, `a path of ${points.length} points`);
  });

  window.surfcapDirector = {
    graph,
    timeline,
    get status() { return { ...status }; },
    send,
    fit,
  };
  return window.surfcapDirector;
}
