// Small glTF steps for tools/make_compressed_fixtures.sh that the pinned CLIs do not offer.
//
//   node gltf_helper.mjs strip IN OUT           drop textures and images (geometry untouched)
//   node gltf_helper.mjs plain IN OUT           decode Draco / meshopt with the official decoders
//                                               (draco3dgltf, meshoptimizer) and write plain
//                                               accessors: the reference decode of IN
//   node gltf_helper.mjs draco-optional IN OUT  keep Draco but no longer require it (empty
//                                               fallback accessors, as BoxDraco.gltf has)
//   node gltf_helper.mjs draco-fallback DRACO PLAIN OUT
//                                               DRACO with Draco not required and fallback
//                                               accessors filled from PLAIN (its reference decode)
//   node gltf_helper.mjs validate FILE...       run the Khronos glTF-Validator; exit 1 on errors
import { NodeIO } from '@gltf-transform/core';
import { ALL_EXTENSIONS } from '@gltf-transform/extensions';
import draco3d from 'draco3dgltf';
import { MeshoptDecoder, MeshoptEncoder } from 'meshoptimizer';
import validator from 'gltf-validator';
import { readFileSync, writeFileSync } from 'node:fs';
import { dirname, join } from 'node:path';

const COMPRESSION = ['KHR_draco_mesh_compression', 'EXT_meshopt_compression'];

async function io() {
  await MeshoptDecoder.ready;
  await MeshoptEncoder.ready;
  return new NodeIO().registerExtensions(ALL_EXTENSIONS).registerDependencies({
    'draco3d.decoder': await draco3d.createDecoderModule(),
    'draco3d.encoder': await draco3d.createEncoderModule(),
    'meshopt.decoder': MeshoptDecoder,
    'meshopt.encoder': MeshoptEncoder,
  });
}

async function strip(input, output) {
  const nodeIO = await io();
  const doc = await nodeIO.read(input);
  for (const texture of doc.getRoot().listTextures()) texture.dispose();
  await nodeIO.write(output, doc);
}

// glTF-Transform 4.5 knows the meshopt extension only by its EXT_ name. The KHR_ name is the
// same layout with more codec versions, all of which meshoptimizer's decoder reads, so the
// JSON is renamed before reading.
async function plain(input, output) {
  const nodeIO = await io();
  const jsonDoc = await nodeIO.readAsJSON(input);
  const text = JSON.stringify(jsonDoc.json).replaceAll('KHR_meshopt_compression', 'EXT_meshopt_compression');
  jsonDoc.json = JSON.parse(text);
  const doc = await nodeIO.readJSON(jsonDoc);
  for (const ext of doc.getRoot().listExtensionsUsed()) {
    if (COMPRESSION.includes(ext.extensionName)) ext.dispose();
  }
  // A GLB holds one buffer: move every accessor into the first (meshopt's fallback buffer
  // and the compressed one become one plain buffer).
  const [first, ...others] = doc.getRoot().listBuffers();
  for (const accessor of doc.getRoot().listAccessors()) accessor.setBuffer(first);
  for (const buffer of others) buffer.dispose();
  await nodeIO.write(output, doc);
}

// Edits the GLB's JSON chunk in place: reading it through glTF-Transform would decode the
// Draco data and encode it again.
async function dracoOptional(input, output) {
  const glb = readFileSync(input);
  const jsonLength = glb.readUInt32LE(12);
  const json = JSON.parse(glb.subarray(20, 20 + jsonLength).toString('utf8'));
  json.extensionsRequired = (json.extensionsRequired ?? []).filter((e) => e !== 'KHR_draco_mesh_compression');
  if (json.extensionsRequired.length === 0) delete json.extensionsRequired;
  let text = JSON.stringify(json);
  text += ' '.repeat((4 - (Buffer.byteLength(text) % 4)) % 4);
  const chunk = Buffer.from(text, 'utf8');
  const rest = glb.subarray(20 + jsonLength);
  const header = Buffer.alloc(20);
  header.write('glTF', 0);
  header.writeUInt32LE(2, 4);
  header.writeUInt32LE(20 + chunk.length + rest.length, 8);
  header.writeUInt32LE(chunk.length, 12);
  header.writeUInt32LE(0x4e4f534a, 16);
  writeFileSync(output, Buffer.concat([header, chunk, rest]));
}

function readGlb(file) {
  const glb = readFileSync(file);
  const jsonLength = glb.readUInt32LE(12);
  const json = JSON.parse(glb.subarray(20, 20 + jsonLength).toString('utf8'));
  const bin = glb.subarray(20 + jsonLength + 8);
  return { json, bin };
}

function writeGlb(file, json, bin) {
  let text = JSON.stringify(json);
  text += ' '.repeat((4 - (Buffer.byteLength(text) % 4)) % 4);
  const chunk = Buffer.from(text, 'utf8');
  const header = Buffer.alloc(20);
  header.write('glTF', 0);
  header.writeUInt32LE(2, 4);
  header.writeUInt32LE(20 + chunk.length + 8 + bin.length, 8);
  header.writeUInt32LE(chunk.length, 12);
  header.writeUInt32LE(0x4e4f534a, 16);
  const binHeader = Buffer.alloc(8);
  binHeader.writeUInt32LE(bin.length, 0);
  binHeader.writeUInt32LE(0x004e4942, 4);
  writeFileSync(file, Buffer.concat([header, chunk, binHeader, bin]));
}

// The Draco file's own JSON and streams, plus the plain file's bytes appended to its BIN
// chunk; each Draco primitive's accessors then point at the plain accessors' data.
async function dracoFallback(dracoFile, plainFile, output) {
  const draco = readGlb(dracoFile);
  const plain = readGlb(plainFile);
  const json = draco.json;
  const base = draco.bin.length;
  json.meshes.forEach((mesh, m) => {
    mesh.primitives.forEach((prim, p) => {
      if (!prim.extensions?.KHR_draco_mesh_compression) return;
      const other = plain.json.meshes[m].primitives[p];
      const pairs = Object.entries(prim.attributes).map(([k, a]) => [a, other.attributes[k]]);
      if (prim.indices !== undefined) pairs.push([prim.indices, other.indices]);
      for (const [ours, theirs] of pairs) {
        const source = plain.json.accessors[theirs];
        const view = { ...plain.json.bufferViews[source.bufferView], buffer: 0 };
        view.byteOffset = (view.byteOffset ?? 0) + base;
        json.bufferViews.push(view);
        Object.assign(json.accessors[ours], {
          bufferView: json.bufferViews.length - 1,
          byteOffset: source.byteOffset ?? 0,
          componentType: source.componentType,
        });
        // The decoded (quantized) values' bounds, not the source's.
        for (const key of ['min', 'max']) {
          if (source[key]) json.accessors[ours][key] = source[key];
        }
      }
    });
  });
  json.extensionsRequired = (json.extensionsRequired ?? []).filter((e) => e !== 'KHR_draco_mesh_compression');
  if (json.extensionsRequired.length === 0) delete json.extensionsRequired;
  json.buffers[0].byteLength = base + plain.bin.length;
  writeGlb(output, json, Buffer.concat([draco.bin, plain.bin]));
}

async function validate(files) {
  let failed = false;
  for (const file of files) {
    const externalResourceFunction = async (uri) =>
      new Uint8Array(readFileSync(join(dirname(file), decodeURIComponent(uri))));
    const report = await validator.validateBytes(new Uint8Array(readFileSync(file)), { externalResourceFunction });
    const { numErrors, numWarnings } = report.issues;
    console.log(`${file}: ${numErrors} errors, ${numWarnings} warnings (glTF-Validator ${report.validatorVersion})`);
    if (numErrors > 0) {
      failed = true;
      for (const m of report.issues.messages.filter((m) => m.severity === 0)) {
        console.log(`  ${m.code} ${m.pointer ?? ''}: ${m.message}`);
      }
    }
  }
  if (failed) process.exit(1);
}

const [command, ...args] = process.argv.slice(2);
const commands = { strip, plain, 'draco-optional': dracoOptional };
if (command === 'validate') {
  await validate(args);
} else if (command === 'draco-fallback' && args.length === 3) {
  await dracoFallback(...args);
} else if (commands[command] && args.length === 2) {
  await commands[command](args[0], args[1]);
} else {
  console.error('usage: node gltf_helper.mjs strip|plain|draco-optional IN OUT | validate FILE...');
  process.exit(2);
}
