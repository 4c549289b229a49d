#!/usr/bin/env node
// Print the Khronos glTF validator's JSON report for one .glb/.gltf file.
// Usage: node tools/gltf-validator/validate.js FILE
// Install the validator first: npm install --prefix tools/gltf-validator
// Exit codes: 0 report printed (errors, if any, are in the report), 2 bad usage or unreadable file.
"use strict";
const fs = require("fs");
const path = require("path");
const validator = require("gltf-validator");

const file = process.argv[2];
if (!file) {
  console.error("usage: node validate.js FILE.glb");
  process.exit(2);
}
let bytes;
try {
  bytes = fs.readFileSync(file);
} catch (err) {
  console.error(`${file}: ${err.message}`);
  process.exit(2);
}
validator
  .validateBytes(new Uint8Array(bytes), {
    uri: path.basename(file),
    maxIssues: 0, // 0: report every issue
    externalResourceFunction: (uri) =>
      fs.promises.readFile(path.resolve(path.dirname(file), decodeURIComponent(uri))),
  })
  .then((report) => console.log(JSON.stringify(report, null, 1)))
  .catch((err) => {
    console.error(`${file}: the validator could not read it: ${err}`);
    process.exit(2);
  });
