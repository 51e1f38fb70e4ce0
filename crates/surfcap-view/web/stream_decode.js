// Decoder of surfcap's compact stream (.scstream; layout in docs/formats.md, encoder and the
// reference decoder in crates/surfcap-formats/src/stream*.rs). Runs in the browser and in Node
// (>= 18): the entropy coder is deflate (zlib framing), decoded natively by
// DecompressionStream('deflate'); the rest is integer arithmetic that gives the Rust decoder's
// bits exactly (positions are min + q * step in doubles, rounded to f32 once).
//
//   import { parseStream, decodeFrames } from './stream_decode.js';
//   const s = parseStream(arrayBuffer);            // header, triangles (Uint32Array), frame table
//   const frames = await decodeFrames(s);          // one Float32Array [vertices * 3] per frame
//   // or frame by frame: const it = frameDecoder(s); await it.next(k) for k = 0, 1, ...

const MAGIC = [0x53, 0x43, 0x53, 0x54, 0x52, 0x4d, 0x00, 0x01]; // "SCSTRM\0\1"

function fail(what) {
  throw new Error(`surfcap stream: ${what}`);
}

async function inflate(bytes) {
  const ds = new DecompressionStream('deflate');
  const out = new Response(new Blob([bytes]).stream().pipeThrough(ds));
  return new Uint8Array(await out.arrayBuffer());
}

/// Reads the header, the (still deflated) topology and the frame table.
export function parseStream(buffer) {
  const b = new Uint8Array(buffer);
  const dv = new DataView(b.buffer, b.byteOffset, b.byteLength);
  if (b.length < 8 || MAGIC.some((m, i) => b[i] !== m)) fail('expected a surfcap stream (SCSTRM, version 1)');
  const u32 = (pos, what) => {
    if (pos + 4 > b.length) fail(`the stream ends at byte ${b.length} before ${what}`);
    return dv.getUint32(pos, true);
  };
  const hl = u32(8, "the header's length");
  if (12 + hl > b.length) fail('the header runs past the end');
  const header = JSON.parse(new TextDecoder().decode(b.subarray(12, 12 + hl)));
  let pos = 12 + hl;
  const tl = u32(pos, "the topology's length");
  const topology = b.subarray(pos + 4, pos + 4 + tl);
  pos += 4 + tl;
  const n = u32(pos, 'the frame count');
  pos += 4;
  const chunks = [];
  let at = pos + 4 * n;
  for (let k = 0; k < n; k++) {
    const len = u32(pos + 4 * k, 'the frame table');
    if (len === 0 || at + len > b.length) fail(`frame ${k}: chunk of ${len} bytes past the end`);
    chunks.push(b.subarray(at, at + len));
    at += len;
  }
  if (at !== b.length) fail(`${b.length - at} bytes after the last frame`);
  return { header, topology, chunks };
}

/// The triangles' vertex indices (Uint32Array, three per triangle).
export async function decodeTriangles(s) {
  const raw = await inflate(s.topology);
  if (raw.length !== s.header.triangles * 12) fail(`the topology has ${raw.length} bytes`);
  return new Uint32Array(raw.buffer, raw.byteOffset, raw.length / 4).slice();
}

// Prediction of vertex i's coordinate a (the stream_predict.rs rules): 0 key (the previous vertex
// of this frame), 1 the same vertex one frame back, 2 extrapolated from two frames back.
function residualsToGrid(kind, raw, n, bits, prev) {
  const q = new Uint32Array(n * 3);
  const top = 2 ** bits - 1;
  let pos = 0;
  for (let a = 0; a < 3; a++) {
    for (let i = 0; i < n; i++) {
      // LEB128 varint, read with arithmetic (values may pass 2^32).
      let z = 0;
      let scale = 1;
      for (;;) {
        if (pos >= raw.length) fail(`the residuals end inside vertex ${i}'s coordinate ${a}`);
        const byte = raw[pos++];
        z += (byte & 0x7f) * scale;
        scale *= 128;
        if ((byte & 0x80) === 0) break;
      }
      const r = z % 2 === 0 ? z / 2 : -(z + 1) / 2;
      const j = 3 * i + a;
      let p;
      if (kind === 0) p = i === 0 ? 0 : q[j - 3];
      else if (kind === 1) p = prev[0][j];
      else p = 2 * prev[0][j] - prev[1][j];
      const v = p + r;
      if (v < 0 || v > top) fail(`vertex ${i} coordinate ${a}: ${v} is off the ${bits}-bit grid`);
      q[j] = v;
    }
  }
  if (pos !== raw.length) fail(`${raw.length - pos} bytes after the last residual`);
  return q;
}

/// A decoder that yields frames in order: `await next()` gives the next frame's positions
/// (Float32Array [vertices * 3]) and `done` says when every frame was given.
export function frameDecoder(s) {
  const h = s.header;
  const n = h.vertices;
  const starts = new Set();
  let total = 0;
  for (const q of h.sequences) {
    starts.add(total);
    total += q.frames;
  }
  let k = 0;
  let history = [];
  let sinceStart = 0;
  return {
    get done() {
      return k >= total;
    },
    async next() {
      if (k >= total) fail('no frame left');
      if (starts.has(k)) {
        history = [];
        sinceStart = 0;
      }
      const chunk = s.chunks[k];
      const kind = chunk[0];
      if (kind > 2) fail(`frame ${k}: prediction ${kind}: expected 0 (key), 1 or 2`);
      if (kind > Math.min(history.length, sinceStart % h.key_interval)) fail(`frame ${k}: prediction ${kind} needs earlier frames`);
      const raw = await inflate(chunk.subarray(1));
      const grid = residualsToGrid(kind, raw, n, h.bits, [history[history.length - 1], history[history.length - 2]]);
      const out = new Float32Array(n * 3);
      for (let i = 0; i < n; i++) {
        for (let a = 0; a < 3; a++) out[3 * i + a] = Math.fround(h.min[a] + grid[3 * i + a] * h.step[a]);
      }
      history.push(grid);
      if (history.length > 2) history.shift();
      sinceStart++;
      k++;
      return out;
    },
  };
}

/// Every frame, sequence after sequence.
export async function decodeFrames(s) {
  const d = frameDecoder(s);
  const frames = [];
  while (!d.done) frames.push(await d.next());
  return frames;
}
