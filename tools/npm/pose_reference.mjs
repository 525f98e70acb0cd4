// The independent reference for glTF posing (issue 28): three.js's GLTFLoader (version pinned in
// package-lock.json) loads a file in node and writes the world-space vertices of every mesh it
// draws, posed as three.js poses them without an animation playing: morph targets at their
// influences (mesh.weights or node.weights), skinned meshes by their bones' matrixWorld.
//
//   node pose_reference.mjs IN.glb|IN.gltf OUT.json [TIME [ANIMATION]]
//
// With TIME, the file's animations (all of them, or the one ANIMATION names by index) play in an
// AnimationMixer set to TIME seconds, each once and held at its ends (LoopOnce, clampWhenFinished):
// the keyframes clamp outside their range, as the glTF specification's samplers do.
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
// - Quaternion.slerpFlat, which LINEAR rotation tracks use, is replaced by the specification's
//   spherical interpolation (three's lerps and normalizes keyframes closer than acos(0.9995));
// - animation tracks hold and interpolate f64 (KeyframeTrack's ValueBufferType, Float32Array by
//   default, would round every interpolated value to f32: 1e-7 of the scene size);
// - normalized keyframe values (meshopt-compressed animations) are dequantized in f64 as the
//   specification writes it, max(c / (2^(b-1) - 1), -1) or c / (2^b - 1): three.js stores
//   c · (1 / max) in a Float32Array (3e-8 relative);
// - SkinnedMesh.normalizeSkinWeights is switched off: GLTFLoader rescales float weights whose
//   sum is not 1 "to fix malformed assets", the glTF specification uses the weights as stored.
import * as THREE from 'three';
import { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';
import { MeshoptDecoder } from 'three/examples/jsm/libs/meshopt_decoder.module.js';
import { readFileSync, writeFileSync } from 'node:fs';
import { basename, dirname, join } from 'node:path';

THREE.SkinnedMesh.prototype.normalizeSkinWeights = function () {};
THREE.KeyframeTrack.prototype.ValueBufferType = Float64Array;
// Spherical interpolation as the glTF specification defines it (three's slerpFlat lerps and
// normalizes whenever the keyframes' dot product is above 0.9995, off by up to 1e-7).
THREE.Quaternion.slerpFlat = function (dst, dstOffset, src0, offset0, src1, offset1, t) {
  const a = [0, 1, 2, 3].map((i) => src0[offset0 + i]);
  let b = [0, 1, 2, 3].map((i) => src1[offset1 + i]);
  let dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
  if (dot < 0) {
    b = b.map((x) => -x);
    dot = -dot;
  }
  let q;
  if (1 - dot > 1e-15) {
    const theta = Math.acos(Math.min(dot, 1));
    const sin = Math.sin(theta);
    const wa = Math.sin((1 - t) * theta) / sin;
    const wb = Math.sin(t * theta) / sin;
    q = a.map((x, i) => x * wa + b[i] * wb);
  } else {
    // Closer than 4e-8 radians: linear and normalized (the arc is straight to 1e-23).
    q = a.map((x, i) => x * (1 - t) + b[i] * t);
    const length = Math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    q = q.map((x) => x / length);
  }
  for (let i = 0; i < 4; i++) dst[dstOffset + i] = q[i];
};
// three's FileLoader (data: and file URIs of a .gltf, read with node's fetch) reports progress
// with the browser's ProgressEvent.
globalThis.ProgressEvent ??= class ProgressEvent extends Event {
  constructor(type, init = {}) {
    super(type);
    Object.assign(this, init);
  }
};

const [input, output, timeArg, animationArg] = process.argv.slice(2);
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
const NORMALIZED_MAX = new Map([
  [Int8Array, 127],
  [Uint8Array, 255],
  [Int16Array, 32767],
  [Uint16Array, 65535],
]);
loader.register((parser) => {
  parser._getArrayFromAccessor = (accessor) => {
    const array = accessor.array;
    if (!accessor.normalized) return array;
    const max = NORMALIZED_MAX.get(array.constructor);
    return Float64Array.from(array, (c) => Math.max(c / max, -1));
  };
  return { name: 'raycast_f64_keyframes' };
});

const gltf = await new Promise((resolve, reject) =>
  loader.parse(data, dirname(input) + '/', resolve, reject),
);
const scene = gltf.scene;
if (timeArg !== undefined) {
  const time = Number(timeArg);
  const mixer = new THREE.AnimationMixer(scene);
  const clips = animationArg === undefined ? gltf.animations : [gltf.animations[Number(animationArg)]];
  for (const clip of clips) {
    const action = mixer.clipAction(clip);
    action.setLoop(THREE.LoopOnce);
    action.clampWhenFinished = true;
    action.play();
  }
  mixer.setTime(time);
}
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
const record = { three: THREE.REVISION, file: basename(input), time: timeArg === undefined ? null : Number(timeArg) };
if (animationArg !== undefined) record.animation = Number(animationArg);
writeFileSync(output, JSON.stringify({ ...record, nodes }) + '\n');
