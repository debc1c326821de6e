#!/usr/bin/env node
// Validates a .gltf or .glb file with the Khronos glTF validator (npm package gltf-validator).
// Usage: node validate_gltf.js FILE [NODE_MODULES_DIR]
// The validator is looked up in NODE_MODULES_DIR, else $LIGHTPATCH_GLTF_VALIDATOR (a
// node_modules folder), else the usual Node resolution. Prints the report as JSON and exits 0
// when it has no errors, 1 when it has errors, 2 when the file or the validator is missing.
'use strict';
const fs = require('fs');
const path = require('path');

const file = process.argv[2];
if (!file) {
  console.error('usage: validate_gltf.js FILE [NODE_MODULES_DIR]');
  process.exit(2);
}
const dirs = [process.argv[3], process.env.LIGHTPATCH_GLTF_VALIDATOR].filter(Boolean);
let validator = null;
for (const d of dirs) {
  try {
    validator = require(path.resolve(d, 'gltf-validator'));
    break;
  } catch (e) { /* try the next place */ }
}
if (!validator) {
  try {
    validator = require('gltf-validator');
  } catch (e) {
    console.error('gltf-validator not found (looked in: ' + (dirs.join(', ') || 'node path') +
                  '); install it with npm install --prefix <dir> gltf-validator');
    process.exit(2);
  }
}

let bytes;
try {
  bytes = new Uint8Array(fs.readFileSync(file));
} catch (e) {
  console.error('cannot read ' + file + ': ' + e.message);
  process.exit(2);
}
const base = path.dirname(path.resolve(file));
validator.validateBytes(bytes, {
  uri: path.basename(file),
  maxIssues: 0,
  externalResourceFunction: (uri) => new Promise((resolve, reject) => {
    fs.readFile(path.resolve(base, decodeURIComponent(uri)), (err, data) => {
      if (err) reject(err.toString()); else resolve(new Uint8Array(data));
    });
  }),
}).then((report) => {
  console.log(JSON.stringify(report, null, 1));
  const errors = report.issues.numErrors;
  console.error(file + ': ' + errors + ' errors, ' + report.issues.numWarnings + ' warnings, ' +
                report.issues.numInfos + ' infos, ' + report.issues.numHints + ' hints');
  process.exit(errors === 0 ? 0 : 1);
}, (error) => {
  console.error('validation failed: ' + error);
  process.exit(1);
});
