// The Khronos glTF validator (npm gltf-validator) on one .glb or .gltf file, for the tests.
// Usage: node validate_gltf.cjs VALIDATOR_PACKAGE_DIR FILE
// Prints one JSON object: {"numErrors", "numWarnings", "numInfos", "numHints", "messages"}
// (messages: every issue as "SEVERITY CODE pointer: message"; severity 0 error ... 3 hint).
// Exit 0 when the validator ran (whatever it found: read numErrors), 2 when it could not.
"use strict";
const fs = require("fs");

const [packageDir, file] = process.argv.slice(2);
if (!packageDir || !file) {
  console.error("usage: node validate_gltf.cjs VALIDATOR_PACKAGE_DIR FILE");
  process.exit(2);
}
const validator = require(require("path").resolve(packageDir));
const severities = ["error", "warning", "info", "hint"];

validator
  .validateBytes(new Uint8Array(fs.readFileSync(file)), {
    uri: file,
    maxIssues: 0,
    writeTimestamp: false,
  })
  .then((report) => {
    const issues = report.issues;
    console.log(
      JSON.stringify({
        numErrors: issues.numErrors,
        numWarnings: issues.numWarnings,
        numInfos: issues.numInfos,
        numHints: issues.numHints,
        messages: issues.messages.map(
          (m) => `${severities[m.severity] || m.severity} ${m.code} ${m.pointer || ""}: ${m.message}`
        ),
      })
    );
  })
  .catch((error) => {
    console.error(`gltf-validator could not run: ${error}`);
    process.exit(2);
  });
