// Validates one glTF or GLB file with the Khronos glTF validator (npm gltf-validator) and prints its issues as JSON.
// Usage: node gltf_validator.js VALIDATOR_MODULE_FOLDER FILE. External resources are refused: brdffit's files have none.
const fs = require("fs");
const validator = require(process.argv[2]);
const file = process.argv[3];
validator
  .validateBytes(new Uint8Array(fs.readFileSync(file)), {
    uri: file,
    externalResourceFunction: (uri) => Promise.reject(new Error(`external resource ${uri} refused`)),
  })
  .then((report) => console.log(JSON.stringify(report.issues)))
  .catch((error) => {
    console.error(String(error));
    process.exit(1);
  });
