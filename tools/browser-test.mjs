// End-to-end check of `surfcap view` in headless Chromium (Debian's /usr/bin/chromium, driven
// by playwright-core). Usage: node browser-test.mjs URL SCREENSHOT.png
// Prints one JSON line of what it saw; exits 1 with a message when a check fails.
import { chromium } from 'playwright-core';

const [url, shot] = process.argv.slice(2);
const fail = (msg) => { console.error(`browser test: ${msg}`); process.exit(1); };
if (!url || !shot) fail('usage: node browser-test.mjs URL SCREENSHOT.png');

const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
  args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'],
});
const errors = [];
try {
  const page = await browser.newPage({ viewport: { width: 960, height: 640 } });
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  page.on('pageerror', (e) => errors.push(String(e)));
  page.on('requestfailed', (r) => errors.push(`request failed: ${r.url()}`));
  await page.goto(url, { waitUntil: 'load' });
  await page.waitForFunction(() => window.surfcapViewer && window.surfcapViewer.ready, null, { timeout: 60000 });
  const counter = () => page.textContent('#counter');
  // Playing: the frame counter advances.
  const f0 = await page.evaluate(() => window.surfcapViewer.frame);
  await page.waitForFunction((f) => window.surfcapViewer.frame !== f, f0, { timeout: 20000 });
  const f1 = await page.evaluate(() => window.surfcapViewer.frame);
  const text1 = await counter();
  // Pause, then the scrubber jumps to a requested frame.
  await page.click('#play');
  const frames = await page.evaluate(() => window.surfcapViewer.frames);
  const want = Math.floor(frames / 2);
  await page.$eval('#scrub', (el, v) => { el.value = String(v); el.dispatchEvent(new Event('input')); }, want);
  const got = await page.evaluate(() => window.surfcapViewer.frame);
  const text2 = await counter();
  if (got !== want || !text2.startsWith(`frame ${want} `)) fail(`scrubbed to ${want}, page shows ${got} ("${text2}")`);
  await page.waitForTimeout(300);
  // Non-blank: the canvas has pixels other than the background.
  const painted = await page.evaluate(() => {
    const c = document.querySelector('#view canvas');
    const d = document.createElement('canvas');
    d.width = c.width; d.height = c.height;
    const g = d.getContext('2d');
    g.drawImage(c, 0, 0);
    const px = g.getImageData(0, 0, d.width, d.height).data;
    let other = 0;
    for (let i = 0; i < px.length; i += 4) {
      if (Math.abs(px[i] - 0xf4) + Math.abs(px[i + 1] - 0xf4) + Math.abs(px[i + 2] - 0xf2) > 30) other++;
    }
    return other / (px.length / 4);
  });
  await page.screenshot({ path: shot });
  if (errors.length) fail(`console errors: ${errors.join(' | ')}`);
  if (!(f1 !== f0)) fail(`the frame counter did not advance (${f0} -> ${f1})`);
  if (!(painted > 0.001)) fail(`the canvas is blank (${(100 * painted).toFixed(2)}% painted)`);
  console.log(JSON.stringify({ advanced: [f0, f1], counter: text1, scrubbed: want, painted, frames }));
} finally {
  await browser.close();
}
