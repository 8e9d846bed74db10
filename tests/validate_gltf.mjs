// Validate a .glb with the Khronos glTF validator; print its report's issue summary as JSON.
// Usage: node tests/validate_gltf.mjs FILE.glb (run from the repository root, where
// node_modules/gltf-validator is installed by `make test` from package.json).
import { readFile } from "node:fs/promises";
import { createRequire } from "node:module";
import path from "node:path";

const require = createRequire(path.join(process.cwd(), "package.json"));
const validator = require("gltf-validator");
const file = process.argv[2];
const bytes = new Uint8Array(await readFile(file));
const report = await validator.validateBytes(bytes, { maxIssues: 0 });
const { numErrors, numWarnings, numInfos, numHints, messages } = report.issues;
console.log(JSON.stringify({ numErrors, numWarnings, numInfos, numHints, validatorVersion: report.validatorVersion,
  messages: messages.map((m) => `${m.code} ${m.severity} ${m.pointer ?? ""} ${m.message}`) }));
