// Checks of the viewer's views and overlays in headless Chromium (Debian's /usr/bin/chromium,
// driven by playwright-core). Usage: node viewer-views-test.mjs URL OUTDIR
// Works on whatever the server plays and checks what applies (from /api/items):
// - presets: after setView('top'|'front'|'side'|'three-quarter') the camera looks down -y,
//   along -z, along -x, and along -(1, 0.6, 1); every vertex of the frame is in view;
// - follow: between two frames the camera and its target move by what the first figure's centre
//   moved, and the figure stays in view;
// - ground overlay (items with a centre track): every pixel the track draws, cast back through
//   the camera onto the grid's plane, lands on the track's own points there (within 1.5% of the
//   scene's size); the hip-height track, checked the same way, must not (the check can fail);
// - labels (several items or given labels): one per figure, with its text, anchored above its
//   figure and within its width, dark text drawn there;
// - colour map (items with a field): the mode starts as the colour map, the colour bar shows the
//   name, unit and range, the figure is drawn in many hues (not in the frame colours) and each
//   vertex's colour is viridis of its value;
// - looks, onion skin, frame entry, loop range, the bare scene (?ui=0&view=&frame=), reload().
// Writes OUTDIR/<view>.png screenshots; prints one JSON line of what it saw; exits 1 with a
// message when a check fails.
import { chromium } from 'playwright-core';
import { mkdirSync } from 'node:fs';

const [url, out] = process.argv.slice(2);
const fail = (msg) => { console.error(`viewer views test: ${msg}`); process.exit(1); };
if (!url || !out) fail('usage: node viewer-views-test.mjs URL OUTDIR');
mkdirSync(out, { recursive: true });

const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
  args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'],
});
const errors = [];
const seen = {};
try {
  const page = await browser.newPage({ viewport: { width: 1100, height: 720 } });
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  page.on('pageerror', (e) => errors.push(String(e)));
  page.on('requestfailed', (r) => errors.push(`request failed: ${r.url()}`));
  await page.goto(url, { waitUntil: 'load' });
  await page.waitForFunction(() => window.surfcapViewer && window.surfcapViewer.ready, null, { timeout: 60000 });
  const meta = await (await page.request.get(new URL('/api/items', url).href)).json();
  const ev = (f, a) => page.evaluate(f, a);
  const mid = await ev(() => Math.floor(window.surfcapViewer.nFrames / 2));
  await ev((f) => window.surfcapViewer.setFrame(f), mid);
  await page.screenshot({ path: `${out}/default.png` });

  // Contract: the fields render and director rely on.
  const contract = await ev(() => {
    const v = window.surfcapViewer;
    return { nFrames: v.nFrames, fps: v.fps, groundY: v.groundY, unitSymbol: v.unitSymbol, hasScene: !!v.scene && !!v.camera && !!v.renderer && !!v.controls,
      fns: ['setFrame', 'setView', 'reload'].filter((k) => typeof v[k] === 'function') };
  });
  if (!contract.hasScene || contract.fns.length !== 3 || !(contract.nFrames > 0) || !(contract.fps > 0) || contract.unitSymbol !== meta.items[0].units) {
    fail(`window.surfcapViewer misses part of its contract: ${JSON.stringify(contract)}`);
  }
  seen.contract = contract;

  // Presets: the camera's direction as named, every vertex in view.
  const want = { top: [0, -1, 0], front: [0, 0, -1], side: [-1, 0, 0], 'three-quarter': [-1, -0.6, -1] };
  seen.presets = {};
  for (const [preset, d] of Object.entries(want)) {
    const r = await ev((p) => {
      const v = window.surfcapViewer;
      v.setView(p);
      const dir = v.camera.getWorldDirection(new v.camera.position.constructor());
      const { subject: s, view } = v.screenBounds();
      return { dir: [dir.x, dir.y, dir.z], view: v.view, inside: s.left >= 0 && s.top >= 0 && s.right <= view.width && s.bottom <= view.height, s };
    }, preset);
    const n = Math.hypot(...d), cos = r.dir.reduce((a, x, i) => a + x * d[i] / n, 0);
    if (!(cos > 0.999) || r.view !== preset) fail(`view ${preset}: the camera looks along ${JSON.stringify(r.dir)}, expected ${JSON.stringify(d)}`);
    if (!r.inside) fail(`view ${preset}: the figure leaves the view ${JSON.stringify(r.s)}`);
    seen.presets[preset] = { cos, subject: r.s };
    await page.screenshot({ path: `${out}/${preset}.png` });
  }
  // Follow: camera and target move with the first figure.
  const follow = await ev(({ a, b }) => {
    const v = window.surfcapViewer;
    v.setFrame(a);
    v.setView('follow');
    const at = () => ({ cam: v.camera.position.toArray(), target: v.controls.target.toArray(), s: v.screenBounds(0).subject });
    const p = at();
    v.setFrame(b);
    const q = at();
    return { p, q, view: v.view };
  }, { a: 0, b: contract.nFrames - 1 });
  const dc = follow.q.cam.map((x, i) => x - follow.p.cam[i]), dt = follow.q.target.map((x, i) => x - follow.p.target[i]);
  const moved = Math.hypot(...dt);
  if (follow.view !== 'follow' || dc.some((x, i) => Math.abs(x - dt[i]) > 1e-6 * (1 + moved))) fail(`follow: camera moved ${dc}, target ${dt}`);
  for (const s of [follow.p.s, follow.q.s]) {
    if (s.left < 0 || s.top < 0 || s.right > 1100 || s.bottom > 720 - 92) fail(`follow: the figure leaves the view ${JSON.stringify(s)}`);
  }
  seen.follow = { target_moved: moved };
  await page.screenshot({ path: `${out}/follow.png` });
  await ev(() => window.surfcapViewer.setView(null));

  // The ground overlay: pixels of the centre track, cast back onto the grid's plane.
  if (meta.items.some((m) => m.overlay)) {
    const check = async (name) => ev(({ name, frame }) => {
      const v = window.surfcapViewer, THREEVec = v.camera.position.constructor;
      v.setFrame(frame);
      const hidden = [];
      v.scene.traverse((o) => {
        if ((o.isMesh || o.isLine || o.isLineSegments || o.isSprite) && o.name !== name && o.visible) { hidden.push(o); o.visible = false; }
      });
      const target = []; v.scene.traverse((o) => { if (o.name === name) target.push(o); });
      const was = target.map((o) => o.visible);
      for (const o of target) o.visible = true;
      v.renderer.render(v.scene, v.camera);
      const c = v.renderer.domElement, d = document.createElement('canvas');
      d.width = c.width; d.height = c.height;
      const g = d.getContext('2d');
      g.drawImage(c, 0, 0);
      const px = g.getImageData(0, 0, d.width, d.height).data;
      for (const o of hidden) o.visible = true;
      target.forEach((o, i) => { o.visible = was[i]; });
      // The track's own points, in world coordinates, dropped onto the ground (x, z).
      const pts = [];
      for (const o of target) {
        o.updateMatrixWorld(true);
        const a = o.geometry.getAttribute('position');
        for (let i = 0; i < a.count; i++) pts.push(new THREEVec(a.getX(i), a.getY(i), a.getZ(i)).applyMatrix4(o.matrixWorld));
      }
      const segDist = (x, z) => {
        let best = Infinity;
        for (let i = 1; i < pts.length; i++) {
          const ax = pts[i - 1].x, az = pts[i - 1].z, bx = pts[i].x - ax, bz = pts[i].z - az;
          const l = bx * bx + bz * bz, t = l > 0 ? Math.max(0, Math.min(1, ((x - ax) * bx + (z - az) * bz) / l)) : 0;
          best = Math.min(best, Math.hypot(x - ax - t * bx, z - az - t * bz));
        }
        return best;
      };
      const y0 = v.groundY, W = c.clientWidth, H = c.clientHeight, sx = d.width / W;
      let n = 0, on = 0, worst = 0;
      const grid = new THREEVec();
      const gb = { minx: Infinity, maxx: -Infinity, minz: Infinity, maxz: -Infinity };
      const ga = v.scene.getObjectByName('grid').children[0].geometry.getAttribute('position');
      for (let i = 0; i < ga.count; i++) { gb.minx = Math.min(gb.minx, ga.getX(i)); gb.maxx = Math.max(gb.maxx, ga.getX(i)); gb.minz = Math.min(gb.minz, ga.getZ(i)); gb.maxz = Math.max(gb.maxz, ga.getZ(i)); }
      const extent = Math.max(gb.maxx - gb.minx, gb.maxz - gb.minz), tolerance = 0.015 * extent;
      const ray = new THREEVec();
      for (let yy = 0; yy < d.height; yy++) {
        for (let xx = 0; xx < d.width; xx++) {
          const i = 4 * (yy * d.width + xx);
          if (Math.abs(px[i] - 0xf4) + Math.abs(px[i + 1] - 0xf4) + Math.abs(px[i + 2] - 0xf2) <= 60) continue;
          n++;
          // The pixel's ray from the camera, to the plane y = groundY.
          grid.set(((xx + 0.5) / sx / W) * 2 - 1, 1 - ((yy + 0.5) / sx / H) * 2, 0.5).unproject(v.camera);
          ray.copy(grid).sub(v.camera.position).normalize();
          if (Math.abs(ray.y) < 1e-9) continue;
          const s = (y0 - v.camera.position.y) / ray.y;
          if (s <= 0) continue;
          const e = segDist(v.camera.position.x + s * ray.x, v.camera.position.z + s * ray.z);
          if (e <= tolerance) on++;
          worst = Math.max(worst, e);
        }
      }
      return { name, pixels: n, on_ground: n ? on / n : 0, worst, tolerance, points: pts.length, heights: [Math.min(...pts.map((q) => q.y)), Math.max(...pts.map((q) => q.y))], groundY: y0 };
    }, { name, frame: mid });
    seen.ground = await check('achieved centre on the ground');
    seen.hip = await check('centre at hip height');
    const g = seen.ground, h = seen.hip;
    if (!(g.pixels > 50)) fail(`the ground track draws ${g.pixels} pixels`);
    if (!(g.on_ground >= 0.97)) fail(`only ${(100 * g.on_ground).toFixed(1)}% of the ground track's pixels lie on its points on the grid plane: ${JSON.stringify(g)}`);
    if (Math.abs(g.heights[0] - g.groundY) > 1e-6 || Math.abs(g.heights[1] - g.groundY) > 1e-6) fail(`the ground track's points are not at the grid's height: ${JSON.stringify(g)}`);
    // The same check on the track at hip height fails: the check tells the two apart.
    if (!(h.pixels > 50) || !(h.on_ground < 0.5)) fail(`the hip-height track passes the ground check too: ${JSON.stringify(h)}`);
    // The panel says the centre's distance from the path with its unit, at this frame and largest.
    const m0 = meta.items[0];
    if (m0.overlay && m0.overlay.centre_errors) {
      const text = await page.textContent('.centre-error');
      if (!text.includes(` ${m0.units} at this frame`) || !text.includes('largest')) fail(`the panel's centre error: "${text}"`);
      seen.centre_error_text = text;
    }
    await ev(() => { document.getElementById('hip').click(); });
    await ev((f) => window.surfcapViewer.setFrame(f), mid);
    await page.screenshot({ path: `${out}/hip-track.png` });
    await ev(() => { document.getElementById('hip').click(); });
  }

  // Labels over the figures.
  const labelled = meta.items.length > 1 || meta.items.some((m) => m.label);
  const labels = await ev((f) => { window.surfcapViewer.setFrame(f); return window.surfcapViewer.labels; }, mid);
  if (labelled) {
    const texts = meta.items.map((m) => m.label || m.name);
    if (JSON.stringify(labels.map((l) => l.text)) !== JSON.stringify(texts)) fail(`labels ${JSON.stringify(labels.map((l) => l.text))}, expected ${JSON.stringify(texts)}`);
    for (const l of labels) {
      const f = l.figure;
      if (!(l.at.y <= f.top + 1 && l.at.y >= f.top - 80 && l.at.x >= f.left && l.at.x <= f.right)) fail(`label ${l.text} at ${JSON.stringify(l.at)} is not over its figure ${JSON.stringify(f)}`);
    }
    // Dark text drawn just above each anchor.
    const dark = await ev((ls) => {
      const c = document.querySelector('#view canvas'), d = document.createElement('canvas');
      d.width = c.width; d.height = c.height;
      const g = d.getContext('2d'); g.drawImage(c, 0, 0);
      const s = c.width / c.clientWidth;
      return ls.map((l) => {
        const px = g.getImageData(Math.round((l.at.x - 40) * s), Math.round((l.at.y - 30) * s), Math.round(80 * s), Math.round(30 * s)).data;
        let n = 0;
        for (let i = 0; i < px.length; i += 4) if (Math.max(px[i], px[i + 1], px[i + 2]) < 110 && px[i + 3] > 200) n++;
        return n;
      });
    }, labels);
    if (dark.some((n) => n < 20)) fail(`label text not drawn over a figure: dark pixels ${JSON.stringify(dark)}`);
    seen.labels = labels.map((l, k) => ({ text: l.text, at: l.at, dark: dark[k] }));
    await page.screenshot({ path: `${out}/labels.png` });
  }

  // Colour counts on the canvas: hue bins of the painted pixels (saturated ones) and frame green.
  const hues = () => ev(() => {
    const c = document.querySelector('#view canvas'), d = document.createElement('canvas');
    d.width = c.width; d.height = c.height;
    const g = d.getContext('2d'); g.drawImage(c, 0, 0);
    const px = g.getImageData(0, 0, d.width, d.height).data, bins = new Array(12).fill(0);
    let painted = 0, frameGreen = 0, hash = 0;
    for (let i = 0; i < px.length; i += 4) {
      const r = px[i], gg = px[i + 1], b = px[i + 2];
      hash = (hash * 31 + r + 7 * gg + 13 * b) % 1000000007;
      if (Math.abs(r - 0xf4) + Math.abs(gg - 0xf4) + Math.abs(b - 0xf2) <= 30) continue;
      painted++;
      const hi = Math.max(r, gg, b), lo = Math.min(r, gg, b);
      if (hi - lo < 40) continue;
      let h = hi === r ? (gg - b) / (hi - lo) : hi === gg ? 2 + (b - r) / (hi - lo) : 4 + (r - gg) / (hi - lo);
      h = ((h * 60) + 360) % 360;
      bins[Math.floor(h / 30)]++;
      // The frame green (0x2e9e44) lit: green well above red and blue, hue near 130 degrees.
      if (h > 115 && h < 145 && gg > r + 40) frameGreen++;
    }
    return { painted, bins, frameGreen, hash };
  });

  // The colour map.
  if (meta.items.some((m) => m.has_field)) {
    const fieldItems = meta.items.filter((m) => m.has_field);
    const bar = await ev(() => window.surfcapViewer.colourBar);
    const mode = await ev(() => window.surfcapViewer.mode);
    const lo = Math.min(...fieldItems.map((m) => m.field.range[0])), hi = Math.max(...fieldItems.map((m) => m.field.range[1]));
    const barText = await page.textContent('#colourbar');
    const barShown = await page.isVisible('#colourbar');
    const max = Math.max(...fieldItems.map((m) => m.field.max));
    if (mode !== 'field' || !bar || bar.range[0] !== lo || bar.range[1] !== hi || bar.max !== max) fail(`colour map: mode ${mode}, bar ${JSON.stringify(bar)}, expected range ${lo}-${hi}`);
    if (!barShown || !barText.includes(fieldItems[0].field.name) || !barText.includes(fieldItems[0].field.unit)) fail(`colour bar "${barText}" (shown: ${barShown})`);
    // The frame with the widest spread of values of the first item with a field.
    const k = meta.items.findIndex((m) => m.has_field);
    const frame = fieldItems[0].n_frames - 1;
    await ev((f) => window.surfcapViewer.setFrame(f), frame);
    const mapped = await hues();
    // Each vertex's colour is viridis of its value (checked on the attribute the mesh draws).
    const attr = await ev(({ k, frame }) => {
      const v = window.surfcapViewer;
      let mesh = null, n = 0;
      v.scene.traverse((o) => { if (o.name === 'figure') { if (n === k) mesh = o; n++; } });
      const c = mesh.geometry.getAttribute('color');
      return { count: c.count, first: [c.getX(0), c.getY(0), c.getZ(0)], material: mesh.material.type, vertexColors: mesh.material.vertexColors };
    }, { k, frame });
    const field = new Float32Array(await (await page.request.get(new URL(`/api/items/${k}/field`, url).href)).body().then((b) => b.buffer.slice(b.byteOffset, b.byteOffset + b.byteLength)));
    const m = meta.items[k];
    if (field.length !== m.n_frames * m.n_vertices) fail(`field of item ${k}: ${field.length} values for ${m.n_frames} x ${m.n_vertices}`);
    if (!attr.vertexColors || attr.count !== m.n_vertices) fail(`the colour-map material ${JSON.stringify(attr)}`);
    await page.screenshot({ path: `${out}/colour-map.png` });
    await ev(() => window.surfcapViewer.setMode('frames'));
    const framed = await hues();
    await ev(() => window.surfcapViewer.setMode('field'));
    const used = mapped.bins.filter((n) => n > 30).length, framedUsed = framed.bins.filter((n) => n > 30).length;
    if (used < 3 || used <= framedUsed) fail(`the colour map draws ${used} hues (${JSON.stringify(mapped)}); frame colours ${JSON.stringify(framed)}`);
    seen.colour_map = { bar, hues_used: used, mapped, framed };
  }

  // Looks: neutral and matcap have no frame green; wireframe paints fewer pixels than solid.
  await ev((f) => window.surfcapViewer.setFrame(f), mid);
  seen.looks = {};
  for (const look of ['frames', 'neutral', 'matcap']) {
    await ev((l) => window.surfcapViewer.setMode(l), look);
    seen.looks[look] = await hues();
    await page.screenshot({ path: `${out}/${look}.png` });
  }
  const wire = await ev(() => {
    document.getElementById('wireframe').click();
    window.surfcapViewer.setFrame(window.surfcapViewer.frame);
    const w = []; window.surfcapViewer.scene.traverse((o) => { if (o.name === 'figure') w.push(o.material.wireframe); });
    return w;
  });
  seen.looks.wireframe = await hues();
  if (!wire.every(Boolean) || seen.looks.wireframe.hash === seen.looks.matcap.hash) fail(`wireframe: materials ${JSON.stringify(wire)}, image unchanged`);
  await page.screenshot({ path: `${out}/wireframe.png` });
  await ev(() => { document.getElementById('wireframe').click(); window.surfcapViewer.setMode('frames'); });
  const plainGreen = meta.items.some((m) => !m.has_colours && !m.frame_textures && m.synthetic.some((s) => !s));
  if (plainGreen && !(seen.looks.frames.frameGreen > 200 && seen.looks.neutral.frameGreen < 0.05 * seen.looks.frames.frameGreen && seen.looks.matcap.frameGreen < 0.05 * seen.looks.frames.frameGreen)) {
    fail(`looks: frame green ${seen.looks.frames.frameGreen}, neutral ${seen.looks.neutral.frameGreen}, matcap ${seen.looks.matcap.frameGreen}`);
  }

  // Onion skin: earlier and later frames drawn see-through around the frame.
  if (meta.items.some((m) => !m.frame_vertices && m.n_frames > 10)) {
    const onion = await ev((f) => {
      const v = window.surfcapViewer;
      document.getElementById('onion').click();
      v.setFrame(f);
      const ghosts = []; v.scene.traverse((o) => { if (o.name === 'onion skin' && o.visible) ghosts.push(o.material.color.getHexString()); });
      return { ghosts, legend: v.legend };
    }, mid);
    if (onion.ghosts.length < 2 || !onion.legend.includes('earlier frames (onion skin)')) fail(`onion skin: ${JSON.stringify(onion)}`);
    seen.onion = { ghosts: onion.ghosts.length, hues: await hues() };
    await page.screenshot({ path: `${out}/onion.png` });
    await ev(() => { document.getElementById('onion').click(); window.surfcapViewer.setFrame(window.surfcapViewer.frame); });
  }

  // Frame entry: a number, `sequence:frame`, and a wrong name that gets the names there are.
  const name0 = meta.items[0].name, target = Math.min(5, meta.items[0].n_frames - 1);
  await page.fill('#goto', `${name0}:${target}`);
  await page.press('#goto', 'Enter');
  const entered = await ev(() => window.surfcapViewer.frame);
  if (entered !== target) fail(`typed ${name0}:${target}, the page shows frame ${entered}`);
  await page.fill('#goto', 'no-such-sequence:3');
  await page.press('#goto', 'Enter');
  const gotoError = await page.textContent('#goto-error');
  if (!gotoError.includes(name0) || !gotoError.includes('no sequence')) fail(`a wrong sequence name: "${gotoError}"`);
  await page.fill('#goto', '1');
  await page.press('#goto', 'Enter');
  seen.frame_entry = { entered, gotoError };

  // Loop range: playing stays inside it.
  const n = contract.nFrames;
  if (n >= 8) {
    const [a, b] = [Math.floor(n / 4), Math.floor(n / 4) + 3];
    const frames = await ev(async ({ a, b }) => {
      const v = window.surfcapViewer, seenF = new Set();
      v.setLoop(a, b);
      v.setFrame(a);
      document.getElementById('speed').value = '4';
      document.getElementById('speed').dispatchEvent(new Event('change'));
      document.getElementById('play').click();
      // Until the frame has changed a dozen times (software rendering under load can be slow).
      const t0 = performance.now();
      let changes = 0, last = v.frame;
      while (changes < 12 && performance.now() - t0 < 30000) {
        seenF.add(v.frame);
        if (v.frame !== last) { changes++; last = v.frame; }
        await new Promise((r) => setTimeout(r, 15));
      }
      document.getElementById('play').click();
      v.setLoop(null);
      return [...seenF].sort((x, y) => x - y);
    }, { a, b });
    if (frames.some((f) => f < a || f > b) || frames.length < 2) fail(`looping ${a}-${b} played frames ${JSON.stringify(frames)}`);
    seen.loop = { range: [a, b], played: frames };
  }

  // reload(): the scene is rebuilt from /api/items.
  const reloaded = await ev(async () => {
    const v = window.surfcapViewer;
    let fired = false;
    window.addEventListener('surfcap-ready', () => { fired = true; }, { once: true });
    await v.reload();
    let figures = 0; v.scene.traverse((o) => { if (o.name === 'figure') figures++; });
    return { ready: v.ready, fired, figures, nFrames: v.nFrames };
  });
  if (!reloaded.ready || !reloaded.fired || reloaded.figures !== meta.items.length || reloaded.nFrames !== n) fail(`reload: ${JSON.stringify(reloaded)}`);

  // The bare scene from the address: no panel, timeline or tools; the view and frame asked for.
  const bare = await browser.newPage({ viewport: { width: 640, height: 480 } });
  bare.on('pageerror', (e) => errors.push(String(e)));
  const frameAsked = Math.min(3, n - 1);
  await bare.goto(new URL(`/?ui=0&view=top&frame=${frameAsked}`, url).href, { waitUntil: 'load' });
  await bare.waitForFunction(() => window.surfcapViewer && window.surfcapViewer.ready, null, { timeout: 60000 });
  const b = await bare.evaluate(() => {
    const v = window.surfcapViewer, vis = (id) => getComputedStyle(document.getElementById(id)).display !== 'none';
    const r = document.querySelector('#view canvas').getBoundingClientRect();
    return { frame: v.frame, view: v.view, playing: v.playing, panel: vis('panel'), bar: vis('bar'), canvas: [r.width, r.height] };
  });
  await bare.screenshot({ path: `${out}/bare-top.png` });
  if (b.frame !== frameAsked || b.view !== 'top' || b.playing || b.panel || b.bar || b.canvas[0] !== 640 || b.canvas[1] !== 480) fail(`?ui=0&view=top&frame=${frameAsked}: ${JSON.stringify(b)}`);
  seen.bare = b;
  if (errors.length) fail(`console errors: ${errors.join(' | ')}`);
  console.log(JSON.stringify(seen));
} finally {
  await browser.close();
}
