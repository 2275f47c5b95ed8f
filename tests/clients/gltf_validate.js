// Validates GLB files with the Khronos glTF validator and prints, as one
// line of JSON, each file's counts of errors and warnings and its error
// messages. Usage: node gltf_validate.js VALIDATOR_MODULE FILE...
'use strict';
const fs = require('fs');
const validator = require(process.argv[2]);

(async () => {
  const reports = {};
  for (const file of process.argv.slice(3)) {
    const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)), {
      maxIssues: 200,
    });
    reports[file] = {
      errors: report.issues.numErrors,
      warnings: report.issues.numWarnings,
      messages: report.issues.messages.filter((m) => m.severity <= 1),
    };
  }
  console.log(JSON.stringify(reports));
})().catch((e) => {
  console.error(e);
  process.exit(1);
});
