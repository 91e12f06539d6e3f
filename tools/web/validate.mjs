// SPDX-License-Identifier: MIT
// Runs the Khronos glTF validator on every .glb under the given folders (recursively).
// Prints each file's error and warning counts and the errors themselves; exits 1 when any
// file has an error (or when no glb was found), 0 otherwise. Usage:
//   node tools/web/validate.mjs out/demo-sim/out/tiles
import fs from 'node:fs';
import path from 'node:path';
import validator from 'gltf-validator';

function glbFiles(dir) {
  const out = [];
  for (const entry of fs.readdirSync(dir, { withFileTypes: true })) {
    const full = path.join(dir, entry.name);
    if (entry.isDirectory()) out.push(...glbFiles(full));
    else if (entry.name.endsWith('.glb')) out.push(full);
  }
  return out.sort();
}

const folders = process.argv.slice(2);
if (folders.length === 0) {
  console.error('usage: node validate.mjs FOLDER...');
  process.exit(2);
}
let files = [];
for (const folder of folders) files.push(...glbFiles(folder));
if (files.length === 0) {
  console.error(`validate: no .glb file under ${folders.join(', ')}`);
  process.exit(1);
}
let errors = 0, warnings = 0;
for (const file of files) {
  const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)), { uri: file, maxIssues: 50 });
  const issues = report.issues;
  errors += issues.numErrors;
  warnings += issues.numWarnings;
  if (issues.numErrors > 0 || issues.numWarnings > 0) {
    console.log(`${file}: ${issues.numErrors} errors, ${issues.numWarnings} warnings`);
    for (const m of issues.messages.filter((m) => m.severity <= 1)) console.log(`  ${m.code} ${m.pointer ?? ''}: ${m.message}`);
  }
}
console.log(`glTF validator ${validator.version()}: ${files.length} glb files, ${errors} errors, ${warnings} warnings`);
process.exit(errors > 0 ? 1 : 0);
