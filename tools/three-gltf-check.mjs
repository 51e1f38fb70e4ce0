// Loads .glb files with three.js's GLTFLoader (the three.js of the viewer, from
// crates/surfcap-view/web/node_modules) and evaluates each animation's weights track: at every key k
// (sampled), the weights must be 1 on the key's target and 0 elsewhere. A frame-set glb (a mesh per
// frame, extras.surfcap.kind "frame-set") is played instead: at every frame of every animation,
// exactly one mesh is shown (non-zero world scale), the frame's own node, with its own vertex count.
// Usage: node tools/three-gltf-check.mjs file.glb [...]
// Prints one JSON line per file; exits 1 when a file does not load or play as expected.
import { readFile } from 'node:fs/promises';

const web = new URL('../crates/surfcap-view/web/node_modules/three/', import.meta.url);
const { GLTFLoader } = await import(new URL('examples/jsm/loaders/GLTFLoader.js', web));
const THREE = await import(new URL('build/three.module.js', web));

// Plays each animation of a frame-set glb frame by frame; returns the report.
function frameSetCheck(path, gltf, meta) {
  const json = gltf.parser.json;
  const meshes = [];
  gltf.scene.traverse((o) => { if (o.isMesh || o.isPoints) meshes.push(o); });
  const mixer = new THREE.AnimationMixer(gltf.scene);
  const problems = [], vertexCounts = [];
  gltf.animations.forEach((clip, s) => {
    const seq = meta.sequences[s], n = seq.frames, nodes = json.nodes[seq.node].children;
    mixer.stopAllAction();
    const action = mixer.clipAction(clip);
    action.setLoop(THREE.LoopOnce);
    action.clampWhenFinished = true;
    action.play();
    const counts = [];
    for (let k = 0; k < n; k++) {
      mixer.setTime((k + 0.5) / seq.fps);
      gltf.scene.updateMatrixWorld(true);
      const shown = meshes.filter((o) => Math.abs(o.matrixWorld.determinant()) > 0);
      const node = shown.length === 1 ? gltf.parser.associations.get(shown[0])?.nodes : undefined;
      const want = json.accessors[json.meshes[json.nodes[nodes[k]].mesh].primitives[0].attributes.POSITION].count;
      const count = shown.length === 1 ? shown[0].geometry.attributes.position.count : -1;
      if (node !== nodes[k] || count !== want) {
        problems.push({ clip: clip.name, frame: k, shown: shown.length, node, expected: nodes[k], count, want });
        break;
      }
      counts.push(count);
    }
    vertexCounts.push(counts);
  });
  return { path, kind: 'frame-set', meshes: meshes.length, animations: gltf.animations.length,
    frames: vertexCounts.map((c) => c.length), distinct_vertex_counts: vertexCounts.map((c) => new Set(c).size), problems };
}

let failed = false;
for (const path of process.argv.slice(2)) {
  const buf = await readFile(path);
  const ab = buf.buffer.slice(buf.byteOffset, buf.byteOffset + buf.byteLength);
  const gltf = await new GLTFLoader().parseAsync(ab, '');
  const meta = gltf.parser.json.extras && gltf.parser.json.extras.surfcap;
  if (meta && meta.kind === 'frame-set') {
    const report = frameSetCheck(path, gltf, meta);
    console.log(JSON.stringify(report));
    if (report.problems.length > 0) failed = true;
    continue;
  }
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
