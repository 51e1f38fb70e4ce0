// Files the viewer's page decodes and plays itself (the server's `played` items): a compact
// stream (.scstream) and a skinned rig (`surfcap rig`'s glb). The viewer (viewer.js) plays an
// item from its positions (`[frames][vertices][3]`); for these it asks `openPlayed` instead of
// fetching them, and gets an object that fills them and is told which frame is shown:
//
// - **stream**: the file's bytes are fetched once per file, the item's sequence cut out (every
//   sequence starts with a key frame) and decoded frame by frame by stream_decode.js into the
//   positions, in the background: the first frame is shown as soon as it is decoded, and until
//   a frame is decoded the last decoded one stays on screen. The camera and grid are set from
//   the stream's grid box (every frame lies inside it), known before any frame is decoded.
// - **rig**: three.js's GLTFLoader builds the skinned mesh and its skeleton and an
//   AnimationMixer plays the item's animation; the figure drawn is that skinned mesh (linear
//   blend skinning in the shader), posed at each shown frame's time (`frame / fps`). The
//   positions are the same skinning done once per frame on the CPU (each vertex moved by its
//   bones' matrices, weighted), for what the viewer measures on them: the camera's box, labels,
//   onion skin. The rig's root node, which turns the subject's up axis onto glTF's +Y, is set
//   to the identity so the rig lies in the subject's own coordinates like every other item
//   (the viewer turns items itself).
//
// For tests and scripts, `window.surfcapPlayed[k]` describes played item k: `kind`, `total`
// frames, frames `decoded` so far, `decodedWhenShown` (how many were decoded when its first
// frame was drawn) and `vertices()`, the vertices drawn now in the item's own coordinates
// (a rig's from three.js's own skinning, SkinnedMesh.applyBoneTransform). The viewer's
// `window.surfcapViewer.ready` turns true only once every played file is fully decoded.
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { parseStream, decodeTriangles, frameDecoder } from './stream_decode.js';

const files = new Map();  // url -> Promise<ArrayBuffer>: a file shared by items is fetched once
function fetchFile(url) {
  if (!files.has(url)) {
    files.set(url, fetch(url).then((r) => {
      if (!r.ok) throw new Error(`${url}: HTTP ${r.status}`);
      return r.arrayBuffer();
    }));
  }
  return files.get(url);
}

window.surfcapPlayed = window.surfcapPlayed || [];

// A status line under the item's row in the panel.
function statusLine() {
  const row = document.createElement('div');
  row.className = 'constraint played-status';
  return row;
}

// Adds the status line once the viewer has added the item's row (in the same step of `load`,
// after `attach`): at its next pause.
function placeStatus(status) {
  queueMicrotask(() => document.getElementById('items').appendChild(status));
}

/// Item `k` (`m` its /api/items entry, `m.played` its file): `{ positions, faces, box, attach,
/// frame, ... }` as described above.
export async function openPlayed(m, k) {
  const p = m.played;
  const bytes = await fetchFile(p.url);
  const played = p.kind === 'stream' ? await openStream(m, bytes) : await openRig(m, bytes);
  window.surfcapPlayed[k] = played.info;
  return played;
}

async function openStream(m, bytes) {
  const s = parseStream(bytes);
  const h = s.header, n = 3 * h.vertices, index = m.played.index;
  if (h.vertices !== m.n_vertices || !h.sequences[index] || h.sequences[index].frames !== m.n_frames) {
    throw new Error(`${m.name}: the stream's header does not match the item (${h.vertices} vertices, sequences ${h.sequences.map((q) => `${q.name} ${q.frames}`).join(', ')})`);
  }
  // The item's sequence alone: its frames' chunks, from its key frame on.
  const start = h.sequences.slice(0, index).reduce((a, q) => a + q.frames, 0);
  const own = { header: { ...h, sequences: [h.sequences[index]] }, topology: s.topology, chunks: s.chunks.slice(start, start + m.n_frames) };
  const faces = await decodeTriangles(s);
  const positions = new Float32Array(m.n_frames * n);
  const decoder = frameDecoder(own);
  positions.set(await decoder.next(), 0);
  const status = statusLine();
  const info = { kind: 'stream', total: m.n_frames, decoded: 1, decodedWhenShown: null, mesh: null, vertices: null };
  const show = () => { status.textContent = info.decoded < info.total ? `stream: decoding, ${info.decoded} of ${info.total} frames` : `stream: ${info.total} frames decoded in the page`; };
  show();
  (async () => {
    while (!decoder.done) {
      positions.set(await decoder.next(), info.decoded * n);
      info.decoded += 1;
      if (info.decoded % 10 === 0 || decoder.done) show();
    }
  })().catch((e) => {
    status.textContent = `stream: decoding stopped at frame ${m.name}:${info.decoded}: ${e.message}`;
    console.error(e);
  });
  const [lo, hi] = m.played.bounds;
  const box = new THREE.Box3(new THREE.Vector3(...lo), new THREE.Vector3(...hi));
  return {
    info, positions, faces, box: { box, largest: box.getSize(new THREE.Vector3()) },
    attach(group, mesh) {
      info.mesh = mesh;
      info.vertices = () => Array.from(mesh.geometry.getAttribute('position').array.subarray(0, n));
      placeStatus(status);
    },
    // The frame to draw for frame `k`: itself once decoded, else the last decoded one.
    frame(k) {
      if (info.decodedWhenShown === null) info.decodedWhenShown = info.decoded;
      return Math.min(k, info.decoded - 1);
    },
  };
}

async function openRig(m, bytes) {
  const gltf = await new GLTFLoader().parseAsync(bytes, '');
  let skinned = null;
  gltf.scene.traverse((o) => { if (o.isSkinnedMesh && !skinned) skinned = o; });
  if (!skinned) throw new Error(`${m.name}: the glb has no skinned mesh`);
  const clip = gltf.animations[m.played.index];
  if (!clip) throw new Error(`${m.name}: the glb has ${gltf.animations.length} animations, no animation ${m.played.index}`);
  // The subject's own coordinates: the up-axis root (the joints' parent) turned back.
  const root = skinned.skeleton.bones[0].parent;
  if (root && root !== gltf.scene) root.quaternion.identity();
  const mixer = new THREE.AnimationMixer(gltf.scene);
  const action = mixer.clipAction(clip);
  action.setLoop(THREE.LoopOnce);  // the last frame's time is the clip's end: held, not wrapped to 0
  action.clampWhenFinished = true;
  action.play();
  // At frame k's time; `reset` first, since a LoopOnce action that reached its end pauses
  // itself and would ignore an earlier time.
  const at = (k) => { action.reset(); mixer.setTime(k / m.fps); };
  const pose = (k) => {
    at(k);
    gltf.scene.updateMatrixWorld(true);
    skinned.skeleton.update();
  };
  // Every frame skinned on the CPU, in the scene's coordinates (the scene is not placed yet).
  const g = skinned.geometry, nv = g.getAttribute('position').count;
  if (nv !== m.n_vertices) throw new Error(`${m.name}: the skinned mesh has ${nv} vertices, the item ${m.n_vertices}`);
  if (!g.getAttribute('normal')) g.computeVertexNormals();  // the rest pose's; skinning turns them
  const rest = g.getAttribute('position'), si = g.getAttribute('skinIndex'), sw = g.getAttribute('skinWeight');
  const joints = new Uint16Array(4 * nv), weights = new Float32Array(4 * nv), base = new Float32Array(3 * nv);
  const v = new THREE.Vector3();
  for (let i = 0; i < nv; i++) {
    v.fromBufferAttribute(rest, i).applyMatrix4(skinned.bindMatrix);
    base.set([v.x, v.y, v.z], 3 * i);
    for (let c = 0; c < 4; c++) {
      joints[4 * i + c] = si.getComponent(i, c);
      weights[4 * i + c] = sw.getComponent(i, c);
    }
  }
  const positions = new Float32Array(m.n_frames * 3 * nv);
  const world = new THREE.Matrix4();
  for (let k = 0; k < m.n_frames; k++) {
    pose(k);
    // The shader's sum: bindMatrixInverse * sum_j w_j (bone_j.matrixWorld * boneInverse_j) * bindMatrix * v,
    // then the mesh's world matrix; bindMatrixInverse is the mesh's world inverse (attached mode).
    const b = skinned.skeleton.boneMatrices, out = k * 3 * nv;
    world.copy(skinned.matrixWorld).multiply(skinned.bindMatrixInverse);
    const e = world.elements;
    for (let i = 0; i < nv; i++) {
      const x = base[3 * i], y = base[3 * i + 1], z = base[3 * i + 2];
      let px = 0, py = 0, pz = 0;
      for (let c = 0; c < 4; c++) {
        const w = weights[4 * i + c];
        if (w === 0) continue;
        const o = 16 * joints[4 * i + c];
        px += w * (b[o] * x + b[o + 4] * y + b[o + 8] * z + b[o + 12]);
        py += w * (b[o + 1] * x + b[o + 5] * y + b[o + 9] * z + b[o + 13]);
        pz += w * (b[o + 2] * x + b[o + 6] * y + b[o + 10] * z + b[o + 14]);
      }
      positions[out + 3 * i] = e[0] * px + e[4] * py + e[8] * pz + e[12];
      positions[out + 3 * i + 1] = e[1] * px + e[5] * py + e[9] * pz + e[13];
      positions[out + 3 * i + 2] = e[2] * px + e[6] * py + e[10] * pz + e[14];
    }
  }
  pose(0);
  const faces = g.index ? new Uint32Array(g.index.array) : Uint32Array.from({ length: nv }, (_, i) => i);
  const status = statusLine();
  status.textContent = `skinned rig: ${skinned.skeleton.bones.length} bones, played by three.js`;
  const info = { kind: 'rig', total: m.n_frames, decoded: m.n_frames, decodedWhenShown: null, bones: skinned.skeleton.bones.length, mesh: skinned, vertices: null };
  return {
    info, positions, faces, box: null,
    // The skinned mesh is drawn in the item's group, with the look the viewer gives its own
    // mesh (which stays, hidden, for what the viewer measures).
    attach(group, mesh) {
      group.add(gltf.scene);
      skinned.frustumCulled = false;
      Object.defineProperty(skinned, 'material', { get: () => mesh.material, set: () => {}, configurable: true });
      mesh.visible = false;
      info.vertices = () => {
        // The drawn vertices, as three.js skins them, in the item's own coordinates.
        group.updateMatrixWorld(true);
        skinned.skeleton.update();
        const toItem = new THREE.Matrix4().copy(group.matrixWorld).invert().multiply(skinned.matrixWorld);
        const out = new Array(3 * nv), q = new THREE.Vector3();
        for (let i = 0; i < nv; i++) {
          q.fromBufferAttribute(rest, i);
          skinned.applyBoneTransform(i, q);
          q.applyMatrix4(toItem);
          out[3 * i] = q.x; out[3 * i + 1] = q.y; out[3 * i + 2] = q.z;
        }
        return out;
      };
      placeStatus(status);
    },
    // Poses the skeleton at frame `k`'s time.
    frame(k) {
      if (info.decodedWhenShown === null) info.decodedWhenShown = info.decoded;
      at(k);
      return k;
    },
  };
}
