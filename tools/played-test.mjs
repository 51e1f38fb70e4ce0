// `surfcap view` playing a file the page decodes itself (a compact stream or a skinned rig), in
// headless Chromium (Debian's /usr/bin/chromium, driven by playwright-core).
// Usage: node tools/played-test.mjs URL ITEM FRAMES OUT.json   (FRAMES: comma-separated)
// Waits for the page, records what the played items had decoded when their first frame was
// drawn, checks that playback advances and that a click on the timeline seeks, waits until item
// ITEM is fully decoded, then at each frame of FRAMES (set through the viewer's setFrame, which
// for a rig poses the skeleton with the animation mixer) reads back the vertices drawn, in the
// item's own coordinates (a rig's skinned by three.js: SkinnedMesh.applyBoneTransform), and
// counts the pixels the figure covers (the scene drawn with it, then without). Writes OUT.json:
// { played, frames: [{ frame, shown, vertices: [x, y, z, ...] as float32 }], figurePixels, errors };
// the caller compares the vertices with the source. Exits 1 on a console error or failed check.
import { launchChromium } from './headless-chromium.mjs';
import { writeFile } from 'node:fs/promises';

const [url, itemArg, framesArg, out] = process.argv.slice(2);
const fail = (msg) => { console.error(`played test: ${msg}`); process.exit(1); };
if (!out) fail('usage: node tools/played-test.mjs URL ITEM FRAMES OUT.json');
const item = Number(itemArg);
const wanted = framesArg.split(',').map(Number);

const browser = await launchChromium();
const errors = [];
try {
  const page = await browser.newPage({ viewport: { width: 800, height: 560 } });
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  page.on('pageerror', (e) => errors.push(String(e)));
  page.on('requestfailed', (r) => errors.push(`request failed: ${r.url()}`));
  await page.goto(url, { waitUntil: 'load' });
  await page.waitForFunction(() => window.surfcapViewer && window.surfcapViewer.ready, null, { timeout: 240000 });
  const played = await page.evaluate(() => (window.surfcapPlayed || []).map((p) => p && ({
    kind: p.kind, total: p.total, decoded: p.decoded, decodedWhenShown: p.decodedWhenShown, bones: p.bones,
  })));
  if (!played[item]) fail(`item ${item} is not played by the page: ${JSON.stringify(played)}`);
  // Playing: the frame counter advances.
  const f0 = await page.evaluate(() => window.surfcapViewer.frame);
  await page.waitForFunction((f) => window.surfcapViewer.frame !== f, f0, { timeout: 60000 });
  // The timeline (the frame slider): a click seeks to the frame under the pointer.
  await page.click('#play');
  const total = await page.evaluate(() => window.surfcapViewer.frames);
  const want = Math.floor(total / 3);
  const track = await page.locator('#track').boundingBox();
  await page.mouse.click(track.x + (track.width * (want + 0.5)) / total, track.y + track.height / 2);
  const clicked = await page.evaluate(() => window.surfcapViewer.frame);
  if (clicked !== want) fail(`clicked the timeline at frame ${want}, the page shows ${clicked}`);
  // Every frame decoded before reading frames back.
  await page.waitForFunction((k) => window.surfcapPlayed[k].decoded === window.surfcapPlayed[k].total, item, { timeout: 240000 });
  const frames = [];
  for (const f of wanted) {
    const got = await page.evaluate(([k, f]) => {
      window.surfcapViewer.setFrame(f);
      // As float32 (what is drawn); each a JSON number that reads back to the same bits.
      const v = Array.from(Float32Array.from(window.surfcapPlayed[k].vertices()));
      return { shown: window.surfcapViewer.frame, vertices: v };
    }, [item, f]);
    frames.push({ frame: f, ...got });
  }
  // The figure's pixels: the canvas drawn with the played mesh, then without it.
  const figurePixels = await page.evaluate((k) => {
    const v = window.surfcapViewer, mesh = window.surfcapPlayed[k].mesh;
    const painted = () => {
      v.renderer.render(v.scene, v.camera);
      const c = v.renderer.domElement, d = document.createElement('canvas');
      d.width = c.width; d.height = c.height;
      const g = d.getContext('2d');
      g.drawImage(c, 0, 0);
      const px = g.getImageData(0, 0, d.width, d.height).data;
      let n = 0;
      for (let i = 0; i < px.length; i += 4) if (Math.abs(px[i] - 0xf4) + Math.abs(px[i + 1] - 0xf4) + Math.abs(px[i + 2] - 0xf2) > 30) n++;
      return n;
    };
    const withFigure = painted();
    mesh.visible = false;
    const without = painted();
    mesh.visible = true;
    v.renderer.render(v.scene, v.camera);
    return withFigure - without;
  }, item);
  await writeFile(out, JSON.stringify({ played, clicked, frames, figurePixels, errors }));
  if (errors.length) fail(`console errors: ${errors.join(' | ')}`);
} finally {
  await browser.close();
}
