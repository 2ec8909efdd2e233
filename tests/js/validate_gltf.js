// Runs the Khronos glTF validator (npm gltf-validator) on each file named and prints its issues.
// Exit 0: no errors in any file (warnings and infos are printed, not failures); 1: an error;
// 2: a file could not be read or the validator did not run.
'use strict';
const fs = require('fs');
const validator = require('gltf-validator');

async function main(files) {
  let failed = false;
  for (const file of files) {
    const bytes = new Uint8Array(fs.readFileSync(file));
    const report = await validator.validateBytes(bytes, { uri: file, maxIssues: 200 });
    const issues = report.issues;
    console.log(`${file}: ${issues.numErrors} errors, ${issues.numWarnings} warnings, ` +
                `${issues.numInfos} infos, ${issues.numHints} hints (glTF validator ${report.validatorVersion})`);
    // Each kind of issue once, with how often it occurs and where first.
    const kinds = new Map();
    for (const m of issues.messages) {
      const kind = kinds.get(m.code);
      if (kind) kind.count++; else kinds.set(m.code, { first: m, count: 1 });
    }
    for (const [code, { first, count }] of kinds) {
      const severity = ['error', 'warning', 'info', 'hint'][first.severity] || first.severity;
      console.log(`  ${severity} ${code} (${count}x, first at ${first.pointer || first.offset || ''}): ${first.message}`);
    }
    if (issues.numErrors > 0) failed = true;
  }
  return failed ? 1 : 0;
}

if (process.argv.length < 3) {
  console.error('usage: node validate_gltf.js FILE.glb...');
  process.exit(2);
}
main(process.argv.slice(2)).then((code) => process.exit(code), (error) => {
  console.error(`glTF validator did not run: ${error}`);
  process.exit(2);
});
