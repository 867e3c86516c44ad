// Independent USD check for the tests: parses a USD file with tinyusdz (WASM) and prints JSON
// {ok, error, meshes: [{path, points, faceVertexCounts, faceVertexIndices}], layer}.
//   node validate_usd.mjs <tinyusdz package folder> <file.usda>
// tinyusdz's loader expects a browser: these two lines let it load in node.
process.type = 'renderer';
globalThis.window = globalThis;
import fs from 'fs';
import path from 'path';

const [pkg, file] = process.argv.slice(2);
const { default: init } = await import(path.resolve(pkg, 'tinyusdz.js'));
const native = await init({ wasmBinary: fs.readFileSync(path.resolve(pkg, 'tinyusdz.wasm')) });
const data = new Uint8Array(fs.readFileSync(file));
const out = { ok: false, error: '', meshes: [], layer: '' };
const stage = new native.TinyUSDZLoaderNative();
out.ok = stage.loadFromBinary(data, path.basename(file));
if (!out.ok) {
  out.error = String(stage.error());
} else {
  for (let i = 0; i < stage.numMeshes(); i++) {
    const m = stage.getMesh(i);
    out.meshes.push({
      path: m.absPath,
      points: m.points ? m.points.length / 3 : 0,
      faceVertexCounts: m.faceVertexCounts ? Array.from(m.faceVertexCounts) : [],
      faceVertexIndices: m.faceVertexIndices ? m.faceVertexIndices.length : 0,
    });
  }
  const layer = new native.TinyUSDZLoaderNative();
  if (layer.loadAsLayerFromBinary(data, path.basename(file))) out.layer = layer.layerToString();
}
process.stdout.write(JSON.stringify(out));
