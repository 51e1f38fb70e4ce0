// Plays a frame-set glb with a texture per frame (crates/surfcap-formats/src/glb_frame_set.rs)
// in headless Chromium with three.js's GLTFLoader (the viewer's three.js), since decoding the
// embedded PNGs needs a browser. At every frame of every animation: exactly one mesh is shown,
// the frame's own node, its material's `map` is the glTF texture that frame's material names,
// decoded (non-zero size), with UVs; the mean colour of each bound texture's image is measured
// on a canvas. Usage: node tools/three-gltf-textures.mjs file.glb
// Prints one JSON line; exits 1 when a frame shows the wrong mesh or texture.
import { readFile } from 'node:fs/promises';
import { chromium } from 'playwright-core';

const [file] = process.argv.slice(2);
const fail = (msg) => { console.error(`three-gltf-textures: ${msg}`); process.exit(1); };
if (!file) fail('usage: node tools/three-gltf-textures.mjs file.glb');
const three = new URL('../crates/surfcap-view/web/node_modules/three/', import.meta.url);
const glb = await readFile(file);
const ORIGIN = 'http://surfcap.test';
const page_html = `<!doctype html><html><head><script type="importmap">
{ "imports": { "three": "/three/build/three.module.js", "three/addons/": "/three/examples/jsm/" } }
</script></head><body></body></html>`;

// In the page: load the glb and play it frame by frame.
async function check() {
  const THREE = await import('three');
  const { GLTFLoader } = await import('three/addons/loaders/GLTFLoader.js');
  const ab = await (await fetch('/file.glb')).arrayBuffer();
  const gltf = await new GLTFLoader().parseAsync(ab, '');
  const json = gltf.parser.json, meta = json.extras.surfcap;
  const meshes = [];
  gltf.scene.traverse((o) => { if (o.isMesh) meshes.push(o); });
  const canvas = document.createElement('canvas');
  canvas.width = canvas.height = 16;
  const g = canvas.getContext('2d', { willReadFrequently: true });
  const meanColour = (image) => {
    g.clearRect(0, 0, 16, 16);
    g.drawImage(image, 0, 0, 16, 16);
    const d = g.getImageData(0, 0, 16, 16).data, m = [0, 0, 0];
    for (let i = 0; i < d.length; i += 4) for (let c = 0; c < 3; c++) m[c] += d[i + c] / 256;
    return m.map((x) => Math.round(x));
  };
  const mixer = new THREE.AnimationMixer(gltf.scene);
  const problems = [], frames = [], means = {};
  gltf.animations.forEach((clip, s) => {
    const seq = meta.sequences[s], nodes = json.nodes[seq.node].children;
    mixer.stopAllAction();
    const action = mixer.clipAction(clip);
    action.setLoop(THREE.LoopOnce);
    action.clampWhenFinished = true;
    action.play();
    const bound = [];
    for (let k = 0; k < seq.frames; k++) {
      mixer.setTime((k + 0.5) / seq.fps);
      gltf.scene.updateMatrixWorld(true);
      const shown = meshes.filter((o) => Math.abs(o.matrixWorld.determinant()) > 0);
      const node = shown.length === 1 ? gltf.parser.associations.get(shown[0])?.nodes : undefined;
      const prim = json.meshes[json.nodes[nodes[k]].mesh].primitives[0];
      const want = json.materials[prim.material].pbrMetallicRoughness.baseColorTexture.index;
      const map = shown.length === 1 ? shown[0].material.map : null;
      const got = map ? gltf.parser.associations.get(map)?.textures : undefined;
      const ok = node === nodes[k] && got === want && map.image && map.image.width > 0 && !!shown[0].geometry.attributes.uv;
      if (!ok) {
        problems.push({ clip: clip.name, frame: k, shown: shown.length, node, expected: nodes[k], texture: got, want });
        break;
      }
      if (!(got in means)) means[got] = { size: [map.image.width, map.image.height], mean: meanColour(map.image), flipY: map.flipY };
      bound.push(got);
    }
    frames.push(bound);
  });
  return { animations: gltf.animations.length, meshes: meshes.length, textures: (json.textures || []).length,
    materials: (json.materials || []).length, frames, means, problems };
}

const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
  args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader'],
});
try {
  const page = await browser.newPage();
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  await page.route(`${ORIGIN}/**`, async (route) => {
    const path = new URL(route.request().url()).pathname;
    if (path === '/') return route.fulfill({ contentType: 'text/html', body: page_html });
    if (path === '/file.glb') return route.fulfill({ contentType: 'model/gltf-binary', body: glb });
    if (path.startsWith('/three/') && !path.includes('..')) {
      try {
        const body = await readFile(new URL(path.slice('/three/'.length), three));
        return route.fulfill({ contentType: 'text/javascript', body });
      } catch { /* 404 below */ }
    }
    return route.fulfill({ status: 404, body: 'not found' });
  });
  await page.goto(`${ORIGIN}/`);
  const report = await page.evaluate(`(${check.toString()})()`);
  report.path = file;
  console.log(JSON.stringify(report));
  if (errors.length) fail(`page errors: ${errors.join(' | ')}`);
  if (report.problems.length) process.exitCode = 1;
} finally {
  await browser.close();
}
