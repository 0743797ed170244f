// Writes the foxglove.* JSON schemas telegrasp-view advertises (foxglove.SceneUpdate,
// foxglove.FrameTransforms) into OUT_DIR, from the installed npm package @foxglove/schemas.
// Run by the build (stage_web.cmake): node gen_schemas.cjs OUT_DIR
const fs = require("node:fs");
const path = require("node:path");

const out = process.argv[2];
if (!out) {
  console.error("usage: node gen_schemas.cjs OUT_DIR");
  process.exit(2);
}
const schemas = require("@foxglove/schemas/jsonschema");
fs.mkdirSync(out, { recursive: true });
for (const name of ["SceneUpdate", "FrameTransforms"]) {
  if (!schemas[name]) {
    console.error(`@foxglove/schemas has no jsonschema ${name}`);
    process.exit(1);
  }
  fs.writeFileSync(path.join(out, `foxglove.${name}.json`), JSON.stringify(schemas[name], null, 1) + "\n");
}
