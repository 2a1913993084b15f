// Runs the Khronos glTF validator on one .glb/.gltf file and prints its report as JSON
// (counts of errors, warnings, infos, the first messages, and the asset summary).
// Usage: NODE_PATH=<folder>/node_modules node validate_gltf.js FILE
// Exit status: 0 when the validator ran (read the counts), 1 when it could not.
"use strict";
const fs = require("fs");
const validator = require("gltf-validator");

const file = process.argv[2];
if (!file) {
  console.error("usage: node validate_gltf.js FILE");
  process.exit(1);
}
validator
  .validateBytes(new Uint8Array(fs.readFileSync(file)), { maxIssues: 50 })
  .then((report) => {
    const issues = report.issues;
    console.log(JSON.stringify({
      validatorVersion: report.validatorVersion,
      errors: issues.numErrors,
      warnings: issues.numWarnings,
      infos: issues.numInfos,
      messages: issues.messages,
      info: report.info,
    }, null, 1));
  })
  .catch((error) => {
    console.error(`${file}: ${error}`);
    process.exit(1);
  });
