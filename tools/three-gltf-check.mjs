// Loads .glb files with three.js's GLTFLoader (the three.js of the viewer, from
// crates/surfcap-view/web/node_modules) and evaluates each animation's weights track: at every key k
// (sampled), the weights must be 1 on the key's target and 0 elsewhere.
// Usage: node tools/three-gltf-check.mjs file.glb [...]
// Prints one JSON line per file; exits 1 when a file does not load or play as expected.
import { readFile } from 'node:fs/promises';

const web = new URL('../crates/surfcap-view/web/node_modules/three/', import.meta.url);
const { GLTFLoader } = await import(new URL('examples/jsm/loaders/GLTFLoader.js', web));

let failed = false;
for (const path of process.argv.slice(2)) {
  const buf = await readFile(path);
  const ab = buf.buffer.slice(buf.byteOffset, buf.byteOffset + buf.byteLength);
  const gltf = await new GLTFLoader().parseAsync(ab, '');
  const mesh = gltf.scene.getObjectByProperty('type', 'Mesh');
  const inf = mesh.morphTargetInfluences;
  const problems = [];
  let first = 0;
  for (const clip of gltf.animations) {
    const track = clip.tracks[0];
    const times = track.times;
    const at = track.createInterpolant();
    const step = Math.max(1, Math.floor(times.length / 50));
    const keys = [...Array(Math.ceil(times.length / step)).keys()].map((j) => j * step).concat([times.length - 1]);
    for (const k of keys) {
      const w = at.evaluate(times[k]);
      const on = [];
      for (let i = 0; i < w.length; i++) if (w[i] !== 0) on.push([i, w[i]]);
      if (w.length !== inf.length || on.length !== 1 || on[0][0] !== first + k || Math.abs(on[0][1] - 1) > 1e-6) {
        problems.push({ clip: clip.name, key: k, weights: w.length, nonzero: on.slice(0, 4) });
        break;
      }
    }
    first += times.length;
  }
  const report = { path, targets: inf.length, animations: gltf.animations.length, problems };
  console.log(JSON.stringify(report));
  if (problems.length > 0 || first !== inf.length) failed = true;
}
process.exit(failed ? 1 : 0);
