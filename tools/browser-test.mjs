// End-to-end check of `surfcap view` in headless Chromium (Debian's /usr/bin/chromium, driven
// by playwright-core). Usage: node browser-test.mjs URL SCREENSHOT.png
// Checks what holds for any input: no console error, playback advances, the timeline and the
// arrow keys seek, the speed control sets the speed, the legend lists exactly what is drawn
// (from /api/items), and every vertex of every frame projects inside the view and clear of the
// info panel; a frame set's item draws each frame's own vertex and triangle counts; a textured
// item binds each frame's own texture. Prints one JSON line of what it saw, including the colours counted on the canvas
// and the timeline at an original and a synthetic frame (the caller asserts on those, since
// which must appear depends on the input); exits 1 with a message when a check fails.
import { launchChromium } from './headless-chromium.mjs';

const [url, shot] = process.argv.slice(2);
const fail = (msg) => { console.error(`browser test: ${msg}`); process.exit(1); };
if (!url || !shot) fail('usage: node browser-test.mjs URL SCREENSHOT.png');

// Counts pixels by colour class on a canvas (WebGL canvases need preserveDrawingBuffer).
function countColours(selector) {
  const c = document.querySelector(selector);
  const d = document.createElement('canvas');
  d.width = c.width; d.height = c.height;
  const g = d.getContext('2d');
  g.drawImage(c, 0, 0);
  const px = g.getImageData(0, 0, d.width, d.height).data;
  const n = { painted: 0, green: 0, red: 0, blue: 0, orange: 0, grey: 0 };
  for (let i = 0; i < px.length; i += 4) {
    const [r, gr, b, a] = [px[i], px[i + 1], px[i + 2], px[i + 3]];
    if (a < 128 || Math.abs(r - 0xf4) + Math.abs(gr - 0xf4) + Math.abs(b - 0xf2) <= 30) continue;
    n.painted++;
    const hi = Math.max(r, gr, b), lo = Math.min(r, gr, b), mean = (r + gr + b) / 3;
    if (gr > r + 40 && gr > b + 30) n.green++;
    else if (r > gr + 60 && Math.abs(gr - b) < 40) n.red++;
    else if (r > gr + 30 && gr > b + 50) n.orange++;
    else if (b > r + 50 && b > gr + 20) n.blue++;
    else if (hi - lo < 12 && mean > 120 && mean < 225) n.grey++;
  }
  n.pixels = px.length / 4;
  return n;
}

const browser = await launchChromium();
const errors = [];
try {
  const page = await browser.newPage({ viewport: { width: 960, height: 640 } });
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  page.on('pageerror', (e) => errors.push(String(e)));
  page.on('requestfailed', (r) => errors.push(`request failed: ${r.url()}`));
  await page.goto(url, { waitUntil: 'load' });
  await page.waitForFunction(() => window.surfcapViewer && window.surfcapViewer.ready, null, { timeout: 60000 });
  const viewer = (expr, arg) => page.evaluate(expr, arg);
  const counter = () => page.textContent('#counter');
  const rendered = () => page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
  // Playing: the frame counter advances.
  const f0 = await viewer(() => window.surfcapViewer.frame);
  // The frame it advanced to, read when it changed: a short sequence playing under load can wrap
  // round to f0 again before a second read.
  const advanced = await page.waitForFunction((f) => {
    const x = window.surfcapViewer.frame;
    return x !== f && { frame: x };
  }, f0, { timeout: 20000 });
  const f1 = (await advanced.jsonValue()).frame;
  const text1 = await counter();
  // Pause, then a click on the timeline jumps to the frame under the pointer.
  await page.click('#play');
  const frames = await viewer(() => window.surfcapViewer.frames);
  const want = Math.floor(frames / 2);
  const track = await page.locator('#track').boundingBox();
  await page.mouse.click(track.x + (track.width * (want + 0.5)) / frames, track.y + track.height / 2);
  const got = await viewer(() => window.surfcapViewer.frame);
  const text2 = await counter();
  if (got !== want || !text2.startsWith(`frame ${want} `)) fail(`clicked the timeline at ${want}, page shows ${got} ("${text2}")`);
  // Arrow keys step one frame (ten with Shift), paused.
  const keys = [];
  for (const [key, delta] of [['ArrowRight', 1], ['ArrowLeft', -1], ['ArrowLeft', -1], ['Shift+ArrowRight', 10]]) {
    const before = await viewer(() => window.surfcapViewer.frame);
    await page.keyboard.press(key);
    const after = await viewer(() => window.surfcapViewer.frame);
    keys.push([key, before, after]);
    // Stepping wraps around the ends (a short sequence wraps within the ten frames of Shift).
    const expected = (((before + delta) % frames) + frames) % frames;
    if (after !== expected) fail(`${key} went from frame ${before} to ${after}, not ${expected}`);
  }
  if (await viewer(() => window.surfcapViewer.playing)) fail('stepping with the arrow keys left the animation playing');
  // Speed.
  await page.selectOption('#speed', '0.25');
  const speed = await viewer(() => window.surfcapViewer.speed);
  if (speed !== 0.25) fail(`speed 0.25 selected, viewer plays at ${speed}`);
  const beforeKey = await viewer(() => window.surfcapViewer.frame);
  await page.keyboard.press('ArrowRight');
  const afterKey = await viewer(() => window.surfcapViewer.frame);
  if (afterKey !== (beforeKey + 1) % frames) fail(`after choosing a speed, ArrowRight went from ${beforeKey} to ${afterKey}`);
  // The legend lists exactly what is drawn.
  const meta = await (await page.request.get(new URL('/api/items', url).href)).json();
  const legend = await viewer(() => window.surfcapViewer.legend);
  // Items with per-vertex colours (body parts) show their own legend rows instead of frame kinds.
  const colourRows = meta.items.flatMap((m) => (m.colour_legend || []).map((r) => r[1]));
  // Items with a texture per frame draw it instead of the frame kinds.
  const texturedRow = meta.items.some((m) => m.frame_textures) ? ['texture per frame'] : [];
  const plain = meta.items.filter((m) => !m.has_colours && !m.frame_textures);
  const labels = plain.flatMap((m) => m.synthetic);
  const expected = [
    ...colourRows,
    ...texturedRow,
    labels.some((s) => !s) && 'original frame',
    labels.some((s) => s) && 'synthetic frame',
    meta.items.some((m) => m.overlay && m.overlay.curve) && 'requested path (on the ground)',
    meta.items.some((m) => m.overlay) && 'achieved centre of mass (on the ground)',
    meta.items.some((m) => m.overlay && m.overlay.transitions.length) && 'transition (timeline)',
  ].filter(Boolean);
  const grid = await viewer(() => window.surfcapViewer.grid);
  if (!grid || !grid.text.includes(meta.items[0].units)) fail(`the grid is not labelled in ${meta.items[0].units}: ${JSON.stringify(grid)}`);
  expected.push(`grid: ${grid.text}`);
  const legendText = await page.textContent('#legend');
  if (JSON.stringify(legend) !== JSON.stringify(expected) || !expected.every((e) => legendText.includes(e))) {
    fail(`legend ${JSON.stringify(legend)} ("${legendText}"), expected ${JSON.stringify(expected)}`);
  }
  // One colour per sequence: the legend names the sequences instead of the frame kinds.
  await page.check('#hues');
  const hued = await viewer(() => window.surfcapViewer.legend);
  const huedWant = [...colourRows, ...texturedRow, ...plain.map((m) => m.name)];
  if (JSON.stringify(hued.slice(0, huedWant.length)) !== JSON.stringify(huedWant) || hued.includes('original frame')) {
    fail(`legend with one colour per sequence: ${JSON.stringify(hued)}`);
  }
  await page.uncheck('#hues');
  // Every frame: every vertex inside the view and clear of the info panel.
  const framing = await viewer(() => {
    const v = window.surfcapViewer, out = { worst: null, outside: [] };
    let margin = Infinity;
    for (let f = 0; f < v.frames; f++) {
      v.setFrame(f);
      const { subject: s, view, panel } = v.screenBounds();
      const m = Math.min(s.left, s.top, view.width - s.right, view.height - s.bottom);
      const clear = s.left >= panel.right || s.top >= panel.bottom;
      if (m < 0 || !clear) out.outside.push({ frame: f, subject: s, panel });
      if (m < margin) { margin = m; out.worst = { frame: f, margin: m, subject: s, view, panel }; }
    }
    return out;
  });
  // A frame set (every frame its own mesh): each frame draws its own vertex and triangle
  // counts, and they change from frame to frame.
  const frameSets = [];
  for (const [k, m] of meta.items.entries()) {
    if (!m.frame_vertices) continue;
    const seen = await viewer(({ k, n }) => {
      const v = window.surfcapViewer, out = [];
      for (let f = 0; f < n; f++) { v.setFrame(f); out.push([v.vertexCounts[k], v.triangleCounts[k]]); }
      return out;
    }, { k, n: m.n_frames });
    const wrong = seen.findIndex(([nv, nt], f) => nv !== m.frame_vertices[f] || nt !== m.frame_triangles[f]);
    if (wrong >= 0) fail(`${m.name} frame ${wrong} draws ${JSON.stringify(seen[wrong])} vertices/triangles, expected ${m.frame_vertices[wrong]}/${m.frame_triangles[wrong]}`);
    const distinct = new Set(seen.map(([nv]) => nv)).size;
    frameSets.push({ item: k, frames: seen.length, distinct_vertex_counts: distinct, first: seen.slice(0, 3) });
  }
  // A texture per frame: at every frame the item's map is the frame's texture; the canvas's
  // colours are counted at the first frame showing each texture.
  const textured = [];
  for (const [k, m] of meta.items.entries()) {
    if (!m.frame_textures) continue;
    const bound = await viewer(({ k, n }) => {
      const v = window.surfcapViewer, out = [];
      for (let f = 0; f < n; f++) { v.setFrame(f); out.push(v.boundTextures[k]); }
      return out;
    }, { k, n: m.n_frames });
    const wrong = bound.findIndex((t, f) => t !== m.frame_textures[f]);
    if (wrong >= 0) fail(`${m.name} frame ${wrong} binds texture ${bound[wrong]}, expected ${m.frame_textures[wrong]}`);
    const seenAt = [];
    for (let t = 0; t < m.n_textures; t++) {
      const f = m.frame_textures.indexOf(t);
      if (f < 0) continue;
      await viewer((f) => window.surfcapViewer.setFrame(f), f);
      await rendered();
      seenAt.push({ texture: t, frame: f, colours: await page.evaluate(`(${countColours.toString()})("#view canvas")`) });
    }
    textured.push({ item: k, bound, seen: seenAt });
  }
  if (framing.outside.length) fail(`${framing.outside.length} frames leave the view or pass under the panel, first ${JSON.stringify(framing.outside[0])}`);
  // Colours at an original and a synthetic frame (when the sequence has them): canvas and timeline.
  const spans = await viewer(() => window.surfcapViewer.spans[0]);
  const colours = {};
  for (const kind of ['original', 'synthetic']) {
    const span = spans.find((s) => s.synthetic === (kind === 'synthetic'));
    if (!span) continue;
    await viewer((f) => window.surfcapViewer.setFrame(f), Math.floor((span.from + span.to - 1) / 2));
    await rendered();
    colours[kind] = await page.evaluate(`(${countColours.toString()})("#view canvas")`);
  }
  const timeline = await page.evaluate(`(${countColours.toString()})("#track")`);
  await page.screenshot({ path: shot });
  if (errors.length) fail(`console errors: ${errors.join(' | ')}`);
  if (!(f1 !== f0)) fail(`the frame counter did not advance (${f0} -> ${f1})`);
  const painted = (colours.original || colours.synthetic).painted / (colours.original || colours.synthetic).pixels;
  if (!(painted > 0.001)) fail(`the canvas is blank (${(100 * painted).toFixed(2)}% painted)`);
  console.log(JSON.stringify({ advanced: [f0, f1], counter: text1, seeked: want, keys, speed, legend, grid,
    framing: framing.worst, colours, timeline, painted, frames, frame_sets: frameSets, textured }));
} finally {
  await browser.close();
}
