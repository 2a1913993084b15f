// Decodes the EXT_meshopt_compression buffer views of a .glb with meshoptimizer's reference
// decoder (npm package meshoptimizer) and writes the decoded fallback buffer to OUTPUT: the
// bytes a viewer would see. Prints the count of decoded views.
// Usage: NODE_PATH=<folder>/node_modules node decode_meshopt.js FILE.glb OUTPUT.bin
"use strict";
const fs = require("fs");
const { MeshoptDecoder } = require("meshoptimizer");

const [file, output] = process.argv.slice(2);
const glb = fs.readFileSync(file);
if (glb.readUInt32LE(0) !== 0x46546c67) throw new Error(`${file}: not a GLB file`);
const jsonLength = glb.readUInt32LE(12);
const json = JSON.parse(glb.subarray(20, 20 + jsonLength).toString("utf8"));
const binStart = 20 + jsonLength + 8;
const bin = glb.subarray(binStart, binStart + glb.readUInt32LE(20 + jsonLength));

MeshoptDecoder.ready.then(() => {
  const fallback = json.buffers.findIndex(
    (b) => b.extensions && b.extensions.EXT_meshopt_compression &&
      b.extensions.EXT_meshopt_compression.fallback);
  if (fallback < 0) throw new Error(`${file}: no meshopt fallback buffer`);
  const decoded = new Uint8Array(json.buffers[fallback].byteLength);
  let views = 0;
  for (const view of json.bufferViews) {
    const ext = view.extensions && view.extensions.EXT_meshopt_compression;
    if (!ext) continue;
    if (ext.buffer !== 0) throw new Error("compressed data outside the BIN chunk");
    const source = new Uint8Array(bin.buffer, bin.byteOffset + (ext.byteOffset || 0), ext.byteLength);
    const target = new Uint8Array(ext.count * ext.byteStride);
    MeshoptDecoder.decodeGltfBuffer(target, ext.count, ext.byteStride, source, ext.mode,
      ext.filter || "NONE");
    decoded.set(target, view.byteOffset || 0);
    views += 1;
  }
  fs.writeFileSync(output, decoded);
  console.log(JSON.stringify({ views, bytes: decoded.length }));
}).catch((error) => {
  console.error(`${file}: ${error}`);
  process.exit(1);
});
