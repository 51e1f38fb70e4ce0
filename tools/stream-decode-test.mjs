// Decodes a surfcap stream with the viewer's JavaScript decoder
// (crates/surfcap-view/web/stream_decode.js) and writes what it decoded, for
// crates/surfcap-cli/tests/stream.rs to compare with the Rust decoder bit for bit:
//   node tools/stream-decode-test.mjs in.scstream out.bin
// out.bin: the triangles' indices (u32 LE) then every frame's positions (f32 LE), sequence
// after sequence. Prints one JSON line: frames, vertices, triangles, milliseconds.
import { readFileSync, writeFileSync } from 'node:fs';
import { dirname, join } from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';

const here = dirname(fileURLToPath(import.meta.url));
const { parseStream, decodeTriangles, decodeFrames } = await import(
  pathToFileURL(join(here, '../crates/surfcap-view/web/stream_decode.js')).href
);
const [input, output] = process.argv.slice(2);
const bytes = readFileSync(input);
const t0 = performance.now();
const s = parseStream(bytes);
const tris = await decodeTriangles(s);
const frames = await decodeFrames(s);
const ms = performance.now() - t0;
const parts = [Buffer.from(tris.buffer, tris.byteOffset, tris.byteLength)];
for (const f of frames) parts.push(Buffer.from(f.buffer, f.byteOffset, f.byteLength));
writeFileSync(output, Buffer.concat(parts));
console.log(JSON.stringify({ frames: frames.length, vertices: s.header.vertices, triangles: tris.length / 3, ms }));
