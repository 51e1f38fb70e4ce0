// The motion graph as a timeline: one row per sequence (its frames left to right), an arc per
// transition edge from a frame of one row to a frame of another (or the same) row, and below
// them a lane of key poses on the output's time axis. A click on an arc plays that transition;
// a click on a row (Shift-click where arcs pass over it) adds the frame under the pointer as a
// key pose; keys are dragged along the
// lane to new times (thesis 3.5.2). Drawn on a canvas; everything is in CSS pixels.

const ROW = 18, GAP = 6, LABEL = 120, LANE = 34, PAD = 8;
const ARC = '#7b2cbf', ARC_HOT = '#e0007a', ROW_FILL = '#2e9e44', KEY = '#1f5fbf';

export function attachGraphTimeline(container, graph, { onTransition, onKeysChanged }) {
  const canvas = document.createElement('canvas');
  canvas.id = 'graph-timeline';
  canvas.title = 'the motion graph: rows are sequences, arcs its transitions (click one to play it); ' +
    'click a row (Shift-click where arcs cross it) to add a key pose, drag keys along the lowest lane to new times';
  canvas.style.cssText = 'width: 100%; display: block; cursor: pointer; touch-action: none;';
  container.appendChild(canvas);
  const n = graph.sequences.length;
  const height = PAD + n * (ROW + GAP) + LANE + PAD;
  canvas.style.height = `${height}px`;
  const longest = Math.max(...graph.sequences.map((q) => q.frames));
  const state = { keys: [], hot: -1, drag: -1, span: 0, playing: null };

  const width = () => canvas.clientWidth;
  const xOfFrame = (f) => LABEL + ((f + 0.5) / longest) * (width() - LABEL - PAD);
  const rowY = (r) => PAD + r * (ROW + GAP);
  // Row and frame within it of a global frame.
  const locate = (g) => {
    const r = graph.sequences.findIndex((q) => g >= q.first && g < q.first + q.frames);
    return { r, f: g - graph.sequences[r].first };
  };
  const point = (g) => { const { r, f } = locate(g); return { x: xOfFrame(f), y: rowY(r) + ROW / 2 }; };
  // An arc from one frame to another: a quadratic curve bulging right of its chord.
  const arcPoints = (a) => {
    const p = point(a.from), q = point(a.to), pts = [];
    const mx = (p.x + q.x) / 2, my = (p.y + q.y) / 2, dx = q.x - p.x, dy = q.y - p.y;
    const len = Math.hypot(dx, dy) || 1, bulge = Math.min(40, 0.3 * len + 8);
    const cx = mx - (dy / len) * bulge, cy = my + (dx / len) * bulge;
    for (let k = 0; k <= 16; k++) {
      const t = k / 16, u = 1 - t;
      pts.push({ x: u * u * p.x + 2 * u * t * cx + t * t * q.x, y: u * u * p.y + 2 * u * t * cy + t * t * q.y });
    }
    return pts;
  };
  // The arcs' points for the current width, computed once per width.
  let cached = { width: -1, arcs: [] };
  const arcsNow = () => {
    if (cached.width !== width()) cached = { width: width(), arcs: graph.transitions.map(arcPoints) };
    return cached.arcs;
  };
  const laneY = () => PAD + n * (ROW + GAP) + 4;
  const span = () => Math.max(120, ...state.keys.map((k) => k.time + 60));
  const xOfTime = (t) => LABEL + (t / state.span) * (width() - LABEL - PAD);
  const timeOfX = (x) => Math.max(0, Math.round(((x - LABEL) / (width() - LABEL - PAD)) * state.span));

  // The rows and every arc, rasterised once per size into a picture of their own that each draw
  // copies: a dense graph has thousands of arcs, and stroking them on every hover or click kept
  // the browser's rasteriser busy for seconds (a software-rendered page stalled its next WebGL
  // frame behind it, 9-16 s after a click on a graph of 10,220 transitions).
  let base = { key: '', canvas: null };
  function baseLayer(dpr) {
    const key = `${width()}x${height}@${dpr}`;
    if (base.key === key) return base.canvas;
    const c = document.createElement('canvas');
    c.width = Math.round(width() * dpr);
    c.height = Math.round(height * dpr);
    const g = c.getContext('2d');
    g.setTransform(dpr, 0, 0, dpr, 0, 0);
    g.font = '12px system-ui, sans-serif';
    g.textBaseline = 'middle';
    graph.sequences.forEach((q, r) => {
      g.fillStyle = '#333';
      g.fillText(q.name.length > 16 ? `${q.name.slice(0, 15)}…` : q.name, 4, rowY(r) + ROW / 2);
      g.fillStyle = ROW_FILL;
      g.globalAlpha = 0.35;
      g.fillRect(xOfFrame(0) - 1, rowY(r) + 4, xOfFrame(q.frames - 1) - xOfFrame(0) + 2, ROW - 8);
      g.globalAlpha = 1;
    });
    // Every arc in one stroke, fainter the more there are.
    const arcs = arcsNow();
    g.strokeStyle = ARC;
    g.lineWidth = 1;
    g.globalAlpha = Math.min(0.55, 6 / Math.sqrt(arcs.length || 1));
    g.beginPath();
    arcs.forEach((pts) => pts.forEach((p, i) => (i ? g.lineTo(p.x, p.y) : g.moveTo(p.x, p.y))));
    g.stroke();
    base = { key, canvas: c };
    return c;
  }

  function draw() {
    const dpr = window.devicePixelRatio || 1;
    const w = Math.round(width() * dpr), h = Math.round(height * dpr);
    if (canvas.width !== w) canvas.width = w;
    if (canvas.height !== h) canvas.height = h;
    const g = canvas.getContext('2d');
    g.setTransform(1, 0, 0, 1, 0, 0);
    g.clearRect(0, 0, w, h);
    g.drawImage(baseLayer(dpr), 0, 0);
    g.setTransform(dpr, 0, 0, dpr, 0, 0);
    g.font = '12px system-ui, sans-serif';
    g.textBaseline = 'middle';
    // The arc pointed at or playing, on top.
    const arcs = arcsNow();
    const trace = (pts) => pts.forEach((p, i) => (i ? g.lineTo(p.x, p.y) : g.moveTo(p.x, p.y)));
    for (const k of new Set([state.hot, state.playing])) {
      if (k === null || k < 0 || !arcs[k]) continue;
      g.strokeStyle = ARC_HOT;
      g.lineWidth = 2.5;
      g.beginPath();
      trace(arcs[k]);
      g.stroke();
    }
    // The key lane: output time axis and the keys on it, each also marked on its row.
    const y = laneY();
    g.fillStyle = '#333';
    g.fillText('key poses', 4, y + 12);
    g.strokeStyle = '#999';
    g.lineWidth = 1;
    g.beginPath(); g.moveTo(LABEL, y + 12); g.lineTo(width() - PAD, y + 12); g.stroke();
    g.fillStyle = '#777';
    for (let t = 0; t <= state.span; t += 30) g.fillRect(xOfTime(t), y + 9, 1, 6);
    state.keys.forEach((k, i) => {
      const x = xOfTime(k.time);
      g.fillStyle = KEY;
      g.beginPath(); g.moveTo(x, y + 4); g.lineTo(x + 6, y + 12); g.lineTo(x, y + 20); g.lineTo(x - 6, y + 12); g.fill();
      g.fillStyle = '#222';
      g.fillText(`${i + 1}: ${k.frame} @ ${k.time}`, x + 8, y + 24);
      const p = point(k.global);
      g.fillStyle = KEY;
      g.fillRect(p.x - 2, p.y - ROW / 2, 4, ROW);
    });
  }

  // What lies under page point (clientX, clientY): a key on the lane, an arc (away from its
  // ends, which sit on the rows), or a frame of a row.
  function hit(e) {
    const r = canvas.getBoundingClientRect(), x = e.clientX - r.left, y = e.clientY - r.top;
    if (y >= laneY() - 2) {
      const k = state.keys.findIndex((key) => Math.abs(xOfTime(key.time) - x) < 8);
      return { kind: 'lane', key: k, x };
    }
    let best = -1, bestD = 6;
    // Shift: the row under the pointer, whatever arc passes there.
    if (!e.shiftKey) arcsNow().forEach((pts, k) => {
      for (let i = 3; i < 14; i++) {
        const p = pts[i];
        const d = Math.hypot(p.x - x, p.y - y);
        if (d < bestD) { bestD = d; best = k; }
      }
    });
    if (best >= 0) return { kind: 'arc', arc: best };
    const row = Math.floor((y - PAD) / (ROW + GAP));
    if (row >= 0 && row < n && x >= LABEL) {
      const q = graph.sequences[row];
      const f = Math.max(0, Math.min(q.frames - 1, Math.round(((x - LABEL) / (width() - LABEL - PAD)) * longest - 0.5)));
      return { kind: 'row', global: q.first + f, frame: `${q.name}:${f}` };
    }
    return { kind: 'none' };
  }

  const keysChanged = () => { state.keys.sort((a, b) => a.time - b.time); onKeysChanged(state.keys.map((k) => ({ frame: k.frame, time: k.time }))); };
  canvas.addEventListener('pointermove', (e) => {
    if (state.drag >= 0) {
      const r = canvas.getBoundingClientRect();
      state.keys[state.drag].time = timeOfX(e.clientX - r.left);
      draw();
      return;
    }
    const h = hit(e), hot = h.kind === 'arc' ? h.arc : -1;
    if (hot !== state.hot) {
      state.hot = hot;
      const a = graph.transitions[hot];
      canvas.title = a ? `transition ${a.from_frame} -> ${a.to_frame} (weight ${a.weight.toFixed(3)}): click to play it` : '';
      draw();
    }
  });
  canvas.addEventListener('pointerdown', (e) => {
    const h = hit(e);
    if (h.kind === 'lane' && h.key >= 0) {
      state.drag = h.key;
      canvas.setPointerCapture(e.pointerId);
    } else if (h.kind === 'arc') {
      state.playing = h.arc;
      draw();
      onTransition(graph.transitions[h.arc]);
    } else if (h.kind === 'row') {
      const last = state.keys.length ? state.keys[state.keys.length - 1].time : -30;
      state.keys.push({ frame: h.frame, global: h.global, time: last + 30 });
      state.span = span();
      draw();
      keysChanged();
    }
  });
  canvas.addEventListener('pointerup', () => {
    if (state.drag >= 0) {
      state.drag = -1;
      state.span = span();
      draw();
      keysChanged();
    }
  });
  window.addEventListener('resize', draw);
  state.span = span();
  draw();
  return {
    canvas,
    draw,
    // For tests and scripting: where an arc or a frame is drawn, in page pixels.
    arcCentre(k) {
      const r = canvas.getBoundingClientRect(), p = arcsNow()[k][8];
      return { x: r.left + p.x, y: r.top + p.y };
    },
    framePoint(g) { const r = canvas.getBoundingClientRect(), p = point(g); return { x: r.left + p.x, y: r.top + p.y }; },
    keyPoint(i) { const r = canvas.getBoundingClientRect(); return { x: r.left + xOfTime(state.keys[i].time), y: r.top + laneY() + 12 }; },
    hitAt(x, y, shiftKey = false) { return hit({ clientX: x, clientY: y, shiftKey }); },
    timeX(t) { return canvas.getBoundingClientRect().left + xOfTime(t); },
    get keys() { return state.keys.map((k) => ({ frame: k.frame, time: k.time })); },
    clearKeys() { state.keys = []; state.span = span(); draw(); keysChanged(); },
    set playing(k) { state.playing = k; draw(); },
  };
}
