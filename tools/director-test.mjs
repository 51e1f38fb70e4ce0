// End-to-end check of directing from the viewer (`surfcap view SUBJECT --direct`) in headless
// Chromium (Debian's /usr/bin/chromium, driven by playwright-core).
// Usage: node director-test.mjs URL OUT_DIR
// Through the page as a user would: draws a path on the ground with the mouse (the walk
// follows it and plays, its curve where it was drawn), clicks a transition arc of the graph's
// timeline (the blended transition plays), asks for a distance in a time, places two key poses
// on the timeline and drags one to a new time, and downloads the result as glb, abc and usda.
// Screenshots go to OUT_DIR (start.png, path.png, transition.png, reach.png, keyposes.png) and
// the downloads beside them. Prints one JSON line of what it saw (times measured by the page
// from each request to the first frame of its result drawn); exits 1 when a check fails.
import { chromium } from 'playwright-core';
import { readFileSync, statSync } from 'node:fs';
import { join } from 'node:path';

const [url, out] = process.argv.slice(2);
const fail = (msg) => { console.error(`director test: ${msg}`); process.exit(1); };
if (!url || !out) fail('usage: node director-test.mjs URL OUT_DIR');

const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
  args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'],
});
const errors = [];
const seen = {};
try {
  const page = await browser.newPage({ viewport: { width: 1280, height: 860 }, acceptDownloads: true });
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  page.on('pageerror', (e) => errors.push(String(e)));
  await page.goto(url, { waitUntil: 'load' });
  await page.waitForFunction(() => window.surfcapDirector && window.surfcapViewer && window.surfcapViewer.ready, null, { timeout: 120000 });
  const ev = (f, a) => page.evaluate(f, a);
  const graph = await ev(() => window.surfcapDirector.graph);
  if (!graph.sequences.length || !graph.transitions.length) fail(`the graph has no sequences or no transitions: ${JSON.stringify(graph).slice(0, 300)}`);
  seen.graph = { sequences: graph.sequences.length, transitions: graph.transitions.length, text: graph.graph };
  // The timeline draws a row per sequence and every arc inside its canvas.
  const box = await page.locator('#graph-timeline').boundingBox();
  if (!box || box.height < graph.sequences.length * 18) fail(`the graph's timeline is missing or too small: ${JSON.stringify(box)}`);
  seen.timeline_box = box;
  await page.screenshot({ path: join(out, 'start.png') });

  // Waits for the answer to request number `n` and returns what the page measured.
  const answer = async (n, what) => {
    await page.waitForFunction((k) => window.surfcapDirector.status.requests >= k && !window.surfcapDirector.status.busy, n, { timeout: 120000 });
    const st = await ev(() => window.surfcapDirector.status);
    if (st.error || !st.last) fail(`${what}: ${st.error || 'no result'}`);
    return st.last;
  };
  const items = async () => (await (await page.request.get(new URL('/api/items', url).href)).json()).items;
  const playing = async (what) => {
    const f0 = await ev(() => window.surfcapViewer.frame);
    await page.waitForFunction((f) => window.surfcapViewer.frame !== f, f0, { timeout: 20000 }).catch(() => fail(`${what}: the result does not play`));
  };

  // 1. A path drawn with the mouse across the ground, along the longer side of what is shown.
  const stroke = await ev(() => {
    const v = window.surfcapViewer, THREE = v.camera.position.constructor;
    const b = { min: new THREE(Infinity, Infinity, Infinity), max: new THREE(-Infinity, -Infinity, -Infinity) };
    v.scene.traverse((o) => {
      if (!o.isMesh) return;
      o.geometry.computeBoundingBox();
      const bb = o.geometry.boundingBox.clone().applyMatrix4(o.matrixWorld);
      b.min.min(bb.min); b.max.max(bb.max);
    });
    const c = b.min.clone().add(b.max).multiplyScalar(0.5);
    const canvas = v.renderer.domElement, rect = canvas.getBoundingClientRect();
    const toScreen = (p) => {
      const q = p.clone().project(v.camera);
      return { x: rect.left + ((q.x + 1) / 2) * rect.width, y: rect.top + ((1 - q.y) / 2) * rect.height };
    };
    // From the figure, 2.5 units along a ground axis then bending 1 unit aside: the first of
    // the four directions whose every point lies on the 3D view (not under a panel).
    for (const [ax, az] of [[1, 0], [-1, 0], [0, 1], [0, -1]]) {
      const world = [];
      for (let k = 0; k <= 20; k++) {
        const t = k / 20, along = 2.5 * t, aside = 1.0 * t * t;
        world.push(new THREE(c.x + ax * along - az * aside, v.groundY, c.z + az * along + ax * aside));
      }
      const screen = world.map(toScreen);
      if (screen.every((p) => document.elementFromPoint(p.x, p.y) === canvas)) {
        return { first: v.toItem(world[0]).toArray(), screen };
      }
    }
    return null;
  });
  if (!stroke) fail('no 2.5-unit stroke from the figure fits on the 3D view');
  await page.click('#director-draw');
  await page.mouse.move(stroke.screen[0].x, stroke.screen[0].y);
  await page.mouse.down();
  for (const p of stroke.screen.slice(1)) await page.mouse.move(p.x, p.y, { steps: 3 });
  await page.mouse.up();
  const path = await answer(1, 'the drawn path');
  await playing('the drawn path');
  let it = (await items())[0];
  if (!it.overlay || !it.overlay.curve || it.overlay.centres.length !== it.n_frames) fail(`the path's result has no curve or centre track: ${JSON.stringify(it.overlay).slice(0, 200)}`);
  // The curve the server followed starts where the stroke started (the subject's own axes; its
  // height is the ground's projection, so only the two ground axes are compared).
  const c0 = it.overlay.curve[0], ground = [0, 1, 2].filter((a) => a !== 1);
  const off = Math.hypot(...ground.map((a) => c0[a] - stroke.first[a]));
  if (off > 0.05) fail(`the followed curve starts ${off} from where the stroke started (${c0} vs ${stroke.first})`);
  if (!(await ev(() => window.surfcapViewer.overlays[0].curve))) fail('the page draws no requested path after the result');
  seen.path = { ...path, n_frames: it.n_frames, curve_start_offset: off, points: stroke.screen.length };
  await page.screenshot({ path: join(out, 'path.png') });

  // 2. A click on a transition arc of the timeline plays that transition.
  const k = Math.floor(graph.transitions.length / 2), arc = graph.transitions[k];
  const at = await ev((i) => window.surfcapDirector.timeline.arcCentre(i), k);
  await page.mouse.move(at.x, at.y);
  const hot = await ev(() => document.getElementById('graph-timeline').title);
  await page.mouse.click(at.x, at.y);
  const tr = await answer(2, `the transition ${arc.from_frame} -> ${arc.to_frame}`);
  await playing('the transition');
  it = (await items())[0];
  if (tr.kind !== 'transition' || it.n_frames !== tr.frames) fail(`the transition did not play: ${JSON.stringify(tr)}`);
  if (!it.synthetic.some((s) => s)) fail('the transition shows no blended (synthetic) frame');
  seen.transition = { ...tr, arc, hover_title: hot };
  await page.screenshot({ path: join(out, 'transition.png') });

  // 3. A distance in a time, between the frames the panel proposes.
  await page.fill('#reach-distance', '2');
  await page.fill('#reach-seconds', '3');
  await page.click('#director-reach');
  const reach = await answer(3, 'reach');
  await playing('reach');
  seen.reach = reach;
  await page.screenshot({ path: join(out, 'reach.png') });

  // 4. Two key poses placed on the rows of the timeline, the second dragged to a new time.
  // Two frames of the first sequence, Shift-clicked on its row (arcs may pass over it).
  const q = graph.sequences[0];
  const picks = [];
  for (const g of [q.first + 2, q.first + Math.floor(q.frames / 2)]) {
    const p = await ev((x) => window.surfcapDirector.timeline.framePoint(x), g);
    const h = await ev(([x, y]) => window.surfcapDirector.timeline.hitAt(x, y, true), [p.x, p.y]);
    if (h.kind !== 'row' || h.global !== g) fail(`Shift at frame ${g} of the timeline finds ${JSON.stringify(h)}`);
    picks.push(p);
  }
  await page.keyboard.down('Shift');
  for (const p of picks) await page.mouse.click(p.x, p.y);
  await page.keyboard.up('Shift');
  const k1 = await ev(() => window.surfcapDirector.timeline.keyPoint(1));
  const target = await ev(() => window.surfcapDirector.timeline.timeX(70));
  await page.mouse.move(k1.x, k1.y);
  await page.mouse.down();
  await page.mouse.move(target, k1.y, { steps: 5 });
  await page.mouse.up();
  const keys = await ev(() => window.surfcapDirector.timeline.keys);
  if (keys.length !== 2 || Math.abs(keys[1].time - 70) > 3) fail(`the keys were not placed and dragged: ${JSON.stringify(keys)}`);
  await page.click('#director-keys');
  const kp = await answer(4, 'key poses');
  await playing('key poses');
  seen.keyposes = { ...kp, keys };
  await page.screenshot({ path: join(out, 'keyposes.png') });

  // 5. The last result downloaded in each format.
  seen.exports = {};
  for (const f of ['glb', 'abc', 'usda']) {
    const [download] = await Promise.all([page.waitForEvent('download'), page.click(`#export-${f}`)]);
    const file = join(out, `keyposes.${f}`);
    await download.saveAs(file);
    const bytes = readFileSync(file);
    seen.exports[f] = { file, name: download.suggestedFilename(), bytes: statSync(file).size };
    if (f === 'glb' && (bytes.toString('latin1', 0, 4) !== 'glTF' || bytes.readUInt32LE(8) !== bytes.length)) fail('the glb download is not a glb file');
    if (f === 'usda' && !bytes.toString('utf8', 0, 8).startsWith('#usda')) fail('the usda download is not a usda file');
    if (f === 'abc' && bytes.toString('latin1', 0, 5) !== 'Ogawa') fail('the abc download is not an Ogawa Alembic file');
  }
  if (errors.length) fail(`console errors: ${errors.join(' | ')}`);
  console.log(JSON.stringify(seen));
} finally {
  await browser.close();
}
