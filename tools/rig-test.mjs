// Plays a skinned rig (.glb written by `surfcap rig`) with three.js (the viewer's three.js, from
// crates/surfcap-view/web/node_modules): GLTFLoader builds the SkinnedMesh and skeleton, an
// AnimationMixer plays each animation, and at sampled frames every vertex is skinned as three.js
// skins it (SkinnedMesh.applyBoneTransform, the shader's linear blend skinning on the CPU) and
// compared with the source frame (a float32 .npy of [frames, vertices, 3], one per animation, in the
// animations' order; compared in world space, the source turned by the rig's up-axis root).
// Usage: node tools/rig-test.mjs rig.glb seq1.npy [seq2.npy ...] [--max-rms X] [--max-error Y]
// Prints one JSON line: per animation the frames checked, RMS and max error, and how far the
// skinned mesh moved from its first frame; exits 1 when an error is above the limits given, or the
// mesh does not move.
import { readFile } from 'node:fs/promises';

const web = new URL('../crates/surfcap-view/web/node_modules/three/', import.meta.url);
const { GLTFLoader } = await import(new URL('examples/jsm/loaders/GLTFLoader.js', web));
const THREE = await import(new URL('build/three.module.js', web));

function readNpy(buf) {
  if (buf.toString('latin1', 1, 6) !== 'NUMPY') throw new Error('not an .npy file');
  const major = buf[6];
  const hlen = major === 1 ? buf.readUInt16LE(8) : buf.readUInt32LE(8);
  const start = (major === 1 ? 10 : 12) + hlen;
  const header = buf.toString('latin1', major === 1 ? 10 : 12, start);
  if (!header.includes("'<f4'") || header.includes("'fortran_order': True")) throw new Error(`unsupported npy header ${header}`);
  const shape = header.match(/'shape': \(([^)]*)\)/)[1].split(',').filter((s) => s.trim()).map(Number);
  const data = new Float32Array(buf.buffer.slice(buf.byteOffset + start, buf.byteOffset + buf.byteLength));
  return { shape, data };
}

const args = process.argv.slice(2);
const opt = (name) => {
  const i = args.indexOf(name);
  if (i < 0) return undefined;
  const v = Number(args[i + 1]);
  args.splice(i, 2);
  return v;
};
const maxRms = opt('--max-rms');
const maxError = opt('--max-error');
const [glbPath, ...npys] = args;

const buf = await readFile(glbPath);
const gltf = await new GLTFLoader().parseAsync(buf.buffer.slice(buf.byteOffset, buf.byteOffset + buf.byteLength), '');
let mesh = null;
gltf.scene.traverse((o) => { if (o.isSkinnedMesh) mesh = o; });
if (!mesh) throw new Error(`${glbPath}: no skinned mesh`);
if (gltf.animations.length !== npys.length) throw new Error(`${glbPath}: ${gltf.animations.length} animations, ${npys.length} .npy files`);
const fps = gltf.parser.json.extras.surfcap.fps;
const rigRoot = mesh.skeleton.bones[0].parent;
const mixer = new THREE.AnimationMixer(gltf.scene);
const pos = mesh.geometry.attributes.position;
const nv = pos.count;
const reports = [];
let failed = false;
const v = new THREE.Vector3();
const s = new THREE.Vector3();
for (const [k, clip] of gltf.animations.entries()) {
  const src = readNpy(await readFile(npys[k]));
  const [nf, snv] = src.shape;
  if (snv !== nv) throw new Error(`${npys[k]}: ${snv} vertices, the rig has ${nv}`);
  mixer.stopAllAction();
  const action = mixer.clipAction(clip);
  action.setLoop(THREE.LoopOnce);
  action.clampWhenFinished = true;
  action.play();
  const step = Math.max(1, Math.floor(nf / 12));
  const frames = [...Array(Math.ceil(nf / step)).keys()].map((j) => j * step).concat([nf - 1]);
  let sum = 0, count = 0, max = 0, moved = 0;
  let first = null;
  for (const f of frames) {
    mixer.setTime(f / fps);
    gltf.scene.updateMatrixWorld(true);
    mesh.skeleton.update();
    const world = rigRoot.matrixWorld;
    const now = new Float32Array(3 * nv);
    for (let i = 0; i < nv; i++) {
      v.fromBufferAttribute(pos, i);
      mesh.applyBoneTransform(i, v);
      v.applyMatrix4(mesh.matrixWorld);
      now.set([v.x, v.y, v.z], 3 * i);
      const o = (f * nv + i) * 3;
      s.set(src.data[o], src.data[o + 1], src.data[o + 2]).applyMatrix4(world);
      const d2 = v.distanceToSquared(s);
      sum += d2;
      count += 1;
      max = Math.max(max, Math.sqrt(d2));
    }
    if (first === null) first = now;
    else for (let i = 0; i < nv; i++) moved = Math.max(moved, Math.hypot(now[3 * i] - first[3 * i], now[3 * i + 1] - first[3 * i + 1], now[3 * i + 2] - first[3 * i + 2]));
  }
  const rms = Math.sqrt(sum / count);
  const r = { animation: clip.name, frames_checked: frames.length, rms, max, moved };
  if ((maxRms !== undefined && rms > maxRms) || (maxError !== undefined && max > maxError) || !(moved > 0)) { r.failed = true; failed = true; }
  reports.push(r);
}
console.log(JSON.stringify({ path: glbPath, bones: mesh.skeleton.bones.length, vertices: nv, animations: reports }));
process.exit(failed ? 1 : 0);
