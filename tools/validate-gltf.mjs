// Validates .glb files with the Khronos glTF validator (npm package gltf-validator).
// Usage: node tools/validate-gltf.mjs file.glb [...]
// Prints one JSON line per file with the issue counts; exits 1 if any file has errors or
// warnings, 2 if the validator itself could not run.
import { readFile } from 'node:fs/promises';
import validator from 'gltf-validator';

let failed = false;
for (const path of process.argv.slice(2)) {
  const bytes = new Uint8Array(await readFile(path));
  const report = await validator.validateBytes(bytes, { maxIssues: 50 });
  const { numErrors, numWarnings, numInfos, numHints, messages } = report.issues;
  const bad = messages.filter((m) => m.severity <= 1);
  console.log(JSON.stringify({ path, numErrors, numWarnings, numInfos, numHints, problems: bad }));
  if (numErrors > 0 || numWarnings > 0) failed = true;
}
process.exit(failed ? 1 : 0);
