// The Khronos glTF-Validator's verdict on each file named, one JSON line per file, for the
// Python tools (raycast_tools.corpus, raycast_tools.check_scale):
//
//   node validate_codes.mjs FILE...
//
// {"file", "version", "errors", "warnings", "codes": {CODE: severity}} where severity is the
// validator's (0 error, 1 warning, 2 info, 3 hint), the most severe one seen for the code; or
// {"file", "exception"} when the validator throws (not glTF at all). External buffers and
// images are read beside the file (the URI percent-decoded), as a viewer would.
import validator from 'gltf-validator';
import { readFileSync } from 'node:fs';
import { dirname, join } from 'node:path';

async function verdict(file) {
  const externalResourceFunction = async (uri) =>
    new Uint8Array(readFileSync(join(dirname(file), decodeURIComponent(uri))));
  const report = await validator.validateBytes(new Uint8Array(readFileSync(file)), {
    uri: file,
    externalResourceFunction,
    maxIssues: 0,
  });
  const codes = {};
  for (const m of report.issues.messages) {
    codes[m.code] = Math.min(codes[m.code] ?? 3, m.severity);
  }
  return {
    file,
    version: report.validatorVersion,
    errors: report.issues.numErrors,
    warnings: report.issues.numWarnings,
    codes,
  };
}

for (const file of process.argv.slice(2)) {
  try {
    console.log(JSON.stringify(await verdict(file)));
  } catch (e) {
    console.log(JSON.stringify({ file, exception: String(e) }));
  }
}
