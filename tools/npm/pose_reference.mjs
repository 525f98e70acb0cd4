// The independent reference for glTF posing (issue 28): three.js's GLTFLoader (version pinned in
// package-lock.json) loads a file in node and writes the world-space vertices of every mesh it
// draws, posed as three.js poses them without an animation playing: morph targets at their
// influences (mesh.weights or node.weights), skinned meshes by their bones' matrixWorld.
//
//   node pose_reference.mjs IN.glb|IN.gltf OUT.json
//
// Output: {"three": REVISION, "file": name, "nodes": [{"node": glTF node index, "primitives":
// [{"primitive": index, "positions": [x, y, z, ...], "indices": [...]}]}]}; numbers are written
// as JavaScript prints doubles (shortest round trip), so nothing is rounded.
//
// Shims and deliberate departures from three.js's defaults:
// - a .gltf's external buffers are inlined as data: URIs (node's fetch reads no file paths);
// - ProgressEvent is defined for FileLoader (it exists in browsers only);
// - textures are never loaded (a plugin answers every texture with null): node has no images;
// - node rotations are normalized after loading: the specification requires unit quaternions,
//   and for a stored one that is off by rounding (AnimatedMorphCube's, by 1e-7) raycast reads
//   the rotation it stands for where three.js would also scale by its length squared;
// - SkinnedMesh.normalizeSkinWeights is switched off: GLTFLoader rescales float weights whose
//   sum is not 1 "to fix malformed assets", the glTF specification uses the weights as stored.
import * as THREE from 'three';
import { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';
import { MeshoptDecoder } from 'three/examples/jsm/libs/meshopt_decoder.module.js';
import { readFileSync, writeFileSync } from 'node:fs';
import { basename, dirname, join } from 'node:path';

THREE.SkinnedMesh.prototype.normalizeSkinWeights = function () {};
// three's FileLoader (data: and file URIs of a .gltf, read with node's fetch) reports progress
// with the browser's ProgressEvent.
globalThis.ProgressEvent ??= class ProgressEvent extends Event {
  constructor(type, init = {}) {
    super(type);
    Object.assign(this, init);
  }
};

const [input, output] = process.argv.slice(2);
if (!input || !output) {
  console.error('usage: node pose_reference.mjs IN OUT.json');
  process.exit(2);
}
// node's fetch reads no file paths: a .gltf's external buffers are inlined as data: URIs.
let bytes = readFileSync(input);
if (input.endsWith('.gltf')) {
  const json = JSON.parse(bytes.toString('utf8'));
  for (const buffer of json.buffers ?? []) {
    if (buffer.uri && !buffer.uri.startsWith('data:')) {
      const file = readFileSync(join(dirname(input), decodeURIComponent(buffer.uri)));
      buffer.uri = 'data:application/octet-stream;base64,' + file.toString('base64');
    }
  }
  bytes = Buffer.from(JSON.stringify(json));
}
const data = bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength);

const loader = new GLTFLoader();
loader.setMeshoptDecoder(MeshoptDecoder);
loader.register(() => ({ name: 'raycast_no_textures', loadTexture: () => Promise.resolve(null) }));

const gltf = await new Promise((resolve, reject) =>
  loader.parse(data, dirname(input) + '/', resolve, reject),
);
const scene = gltf.scene;
scene.traverse((object) => object.quaternion.normalize());
scene.updateMatrixWorld(true);
const associations = gltf.parser.associations;

const nodeOf = (object) => {
  for (let o = object; o; o = o.parent) {
    const a = associations.get(o);
    if (a && a.nodes !== undefined) return a.nodes;
  }
  return -1;
};

const byNode = new Map();
const v = new THREE.Vector3();
scene.traverse((object) => {
  if (!object.isMesh) return;
  const node = nodeOf(object);
  const association = associations.get(object) || {};
  const geometry = object.geometry;
  const count = geometry.attributes.position.count;
  const positions = [];
  for (let i = 0; i < count; i++) {
    object.getVertexPosition(i, v);
    v.applyMatrix4(object.matrixWorld);
    positions.push(v.x, v.y, v.z);
  }
  const indices = geometry.index
    ? Array.from(geometry.index.array)
    : Array.from({ length: count }, (_, i) => i);
  if (!byNode.has(node)) byNode.set(node, []);
  byNode.get(node).push({ primitive: association.primitives ?? 0, positions, indices });
});

const nodes = [...byNode.entries()]
  .sort((a, b) => a[0] - b[0])
  .map(([node, primitives]) => ({
    node,
    primitives: primitives.sort((a, b) => a.primitive - b.primitive),
  }));
writeFileSync(output, JSON.stringify({ three: THREE.REVISION, file: basename(input), nodes }) + '\n');
