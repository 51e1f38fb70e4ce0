// Drives `surfcap play`'s page in headless Chromium (Debian's /usr/bin/chromium, driven by
// playwright-core) with scripted key presses, and prints one JSON line of what the page's state
// (window.surfcapPlay) said. Usage:
//   node play-page.mjs URL steer [SCREENSHOT.png]   once every captured frame is decoded, walk
//                                                   right (D), then up and right (W and D:
//                                                   a left turn of 45 degrees), then stop
//                                                   (space); samples the centre track's heading
//                                                   and speed after each
//   node play-page.mjs URL measure [SECONDS]        time to the first played frame and to every
//                                                   frame decoded, bytes received (total and per
//                                                   second of play), blended frames shown exact,
//                                                   as stand-ins and late, frame rate and
//                                                   the steps' round trips over SECONDS (default
//                                                   30) of scripted walking, running and turning
// Exits 1 with a message when the page reports an error or a console error appears.
import { launchChromium } from './headless-chromium.mjs';

const [url, mode, arg] = process.argv.slice(2);
const fail = (msg) => { console.error(`play page: ${msg}`); process.exit(1); };
if (!url || !['steer', 'measure'].includes(mode)) fail('usage: node play-page.mjs URL steer|measure [PNG|SECONDS]');

const browser = await launchChromium();
const errors = [];
try {
  const page = await browser.newPage({ viewport: { width: 960, height: 640 } });
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  page.on('pageerror', (e) => errors.push(String(e)));
  // Chromium at times reports the progressive stream's request as aborted after the page has
  // read its last byte; the page checks the stream's length against its frame table itself (an
  // error there is a page error), so that request's failure counts only when bytes are missing.
  const streamFailures = [];
  page.on('requestfailed', (r) => {
    const what = `request failed: ${r.url()}: ${r.failure() ? r.failure().errorText : '?'}`;
    if (new URL(r.url()).pathname === '/api/play/stream') streamFailures.push(what);
    else errors.push(what);
  });
  const state = () => page.evaluate(() => JSON.parse(JSON.stringify(window.surfcapPlay)));
  const check = async () => {
    const s = await state();
    if (s.error) fail(`the page failed: ${s.error}`);
    if (streamFailures.length && !(s.totalFrames > 0 && s.streamComplete)) errors.push(...streamFailures.splice(0));
    if (errors.length) fail(`console errors: ${errors.join(' | ')} (page state: ${JSON.stringify(s)})`);
    return s;
  };
  await page.goto(url, { waitUntil: 'load' });
  await page.waitForFunction(() => window.surfcapPlay && (window.surfcapPlay.firstFrameMs !== null || window.surfcapPlay.error),
    null, { timeout: 120000 });
  const first = await check();
  const wait = (ms) => page.waitForTimeout(ms);
  // Holds `keys` for `ms`, then samples the state (and the centre track's heading and speed).
  const hold = async (keys, ms) => {
    for (const k of keys) await page.keyboard.down(k);
    await wait(ms);
    const s = await check();
    for (const k of keys) await page.keyboard.up(k);
    return s;
  };
  if (mode === 'steer') {
    // Every captured frame decoded (so every blended frame has its stand-in at least), let the
    // start settle, then: right, up and right (a left turn of 45 degrees), stop.
    await page.waitForFunction(() => window.surfcapPlay.allDecodedMs !== null, null, { timeout: 300000 });
    await wait(1000);
    const right = await hold(['KeyD'], 5000);
    const up = await hold(['KeyW', 'KeyD'], 5000);
    await page.keyboard.press('Space');
    await wait(3500);
    const stopped = await check();
    if (arg) await page.screenshot({ path: arg });
    const pick = (s) => ({ heading: s.heading, speed: s.speed, commandHeading: s.commandHeading, commandSpeed: s.commandSpeed,
      clip: s.clip, centre: s.centre, fps: s.fps, frameMs: s.frameMs, framesShown: s.framesShown });
    console.log(JSON.stringify({
      firstFrameMs: first.firstFrameMs, right: pick(right), up: pick(up), stopped: pick(stopped),
      late: stopped.late, bytes: stopped.bytes, rttMs: stopped.rttMs, transitions: stopped.transitions,
      decisions: stopped.decisions, blendsShown: stopped.blendsShown, standIns: stopped.standIns, cannotFollow: stopped.cannotFollow,
    }));
  } else {
    const seconds = Number(arg || 30);
    await page.waitForFunction(() => window.surfcapPlay.allDecodedMs !== null, null, { timeout: 300000 });
    const decoded = await check();
    const before = decoded.bytes;
    const script = [['KeyD'], ['KeyW'], ['ShiftLeft', 'KeyW'], ['KeyA'], ['ShiftLeft', 'KeyS'], ['KeyD', 'KeyS'], []];
    const t = Date.now();
    for (let k = 0; Date.now() - t < seconds * 1000; k++) await hold(script[k % script.length], 3000);
    const played = (Date.now() - t) / 1000;
    const end = await check();
    const info = await page.evaluate(() => fetch('/api/play/info').then((r) => r.json()));
    const during = (end.bytes.blends - before.blends) + (end.bytes.steps - before.steps);
    console.log(JSON.stringify({
      firstFrameMs: first.firstFrameMs, allDecodedMs: decoded.allDecodedMs, frames: end.totalFrames,
      streamBytes: end.bytes.stream, playedSeconds: played, blendBytes: end.bytes.blends - before.blends,
      stepBytes: end.bytes.steps - before.steps, bytesPerSecond: during / played, late: end.late,
      framesShown: end.framesShown, blendsShown: end.blendsShown, standIns: end.standIns, transitions: end.transitions,
      fps: end.fps, frameMs: end.frameMs, rttMs: end.rttMs, delayMs: end.delayMs, blendsMade: info.blends_made,
      vertices: info.vertices, subject: info.subject,
    }));
  }
} finally {
  await browser.close();
}
