// Hand-made posing fixtures (issue 28), written with glTF-Transform (pinned in package-lock.json):
//
//   node make_pose_fixtures.mjs OUT_DIR
//
// - morph-sparse.gltf: a 4×4 vertex grid with two morph targets, one sparse (three vertices
//   move, float) and one dense of normalized shorts (KHR_mesh_quantization); drawn by two nodes,
//   one with the mesh's weights [0.5, 0.25], one overriding them with node.weights [1, -0.5].
// - skins-shared.gltf: a joint chain J0 → J1 → J2 with non-uniform scales and rotations, two
//   skins sharing J1 (one without inverseBindMatrices), skinned mesh nodes with transforms of
//   their own (which the specification says to ignore), float and normalized ubyte weights.
// - morph-animated.gltf: morph-sparse with its weights animated, CUBICSPLINE on one node and
//   STEP on the other, and a CUBICSPLINE translation (one animation).
// - skins-animated.gltf: skins-shared with its joints animated (J0 rotation CUBICSPLINE, J1
//   scale STEP, J2 translation LINEAR) and, in a second animation, the rig's rotation LINEAR.
//   The skinned mesh nodes are not animated: three.js binds a skinned mesh to the node's
//   transform at load time, where the specification ignores that transform.
import { Document, NodeIO } from '@gltf-transform/core';
import { KHRMeshQuantization } from '@gltf-transform/extensions';
import { mkdirSync } from 'node:fs';
import { join } from 'node:path';

const out = process.argv[2];
if (!out) {
  console.error('usage: node make_pose_fixtures.mjs OUT_DIR');
  process.exit(2);
}
mkdirSync(out, { recursive: true });
const io = new NodeIO().registerExtensions([KHRMeshQuantization]);

// A grid of n × n vertices in the z = 0 plane, (x, y) in [0, size]², two triangles a cell.
function grid(n, size) {
  const positions = [];
  const indices = [];
  for (let j = 0; j < n; j++) for (let i = 0; i < n; i++) positions.push((i * size) / (n - 1), (j * size) / (n - 1), 0);
  for (let j = 0; j + 1 < n; j++)
    for (let i = 0; i + 1 < n; i++) {
      const a = j * n + i;
      indices.push(a, a + 1, a + n + 1, a, a + n + 1, a + n);
    }
  return { positions: new Float32Array(positions), indices: new Uint16Array(indices) };
}

function morphSparse() {
  const doc = new Document();
  const buffer = doc.createBuffer();
  doc.createExtension(KHRMeshQuantization).setRequired(true);
  const { positions, indices } = grid(4, 3);
  const n = positions.length / 3;
  const acc = (type, array) => doc.createAccessor().setType(type).setArray(array).setBuffer(buffer);
  const sparseDeltas = new Float32Array(n * 3);
  sparseDeltas.set([0.25, 0.5, 1.5], 5 * 3);
  sparseDeltas.set([-0.75, 0.125, 0.375], 6 * 3);
  sparseDeltas.set([0, 0, -2.5], 15 * 3);
  const dense = new Int16Array(n * 3);
  for (let v = 0; v < n; v++) dense.set([(v * 1237) % 32767 - 16000, (v * 4111) % 30000 - 15000, (v * 977) % 32767], v * 3);
  const prim = doc
    .createPrimitive()
    .setAttribute('POSITION', acc('VEC3', positions))
    .setIndices(acc('SCALAR', indices))
    .addTarget(doc.createPrimitiveTarget().setAttribute('POSITION', acc('VEC3', sparseDeltas).setSparse(true)))
    .addTarget(doc.createPrimitiveTarget().setAttribute('POSITION', acc('VEC3', dense).setNormalized(true)));
  const mesh = doc.createMesh('morphed').addPrimitive(prim).setWeights([0.5, 0.25]);
  const a = doc.createNode('mesh_weights').setMesh(mesh).setTranslation([-4, 0, 0]);
  const b = doc.createNode('node_weights').setMesh(mesh).setTranslation([1, 0.5, 0]).setRotation([0, 0.3826834323650898, 0, 0.9238795325112867]).setWeights([1, -0.5]);
  doc.createScene('scene').addChild(a).addChild(b);
  return doc;
}

function skinsShared() {
  const doc = new Document();
  const buffer = doc.createBuffer();
  const acc = (type, array) => doc.createAccessor().setType(type).setArray(array).setBuffer(buffer);
  const j0 = doc.createNode('J0').setTranslation([0.5, -1, 0.25]).setScale([2, 1, 0.5]).setRotation([0, 0, 0.19509032201612825, 0.9807852804032304]);
  const j1 = doc.createNode('J1').setTranslation([0, 1.5, 0]).setRotation([0.25881904510252074, 0, 0, 0.9659258262890683]).setScale([1, 0.75, 1.25]);
  const j2 = doc.createNode('J2').setTranslation([0.25, 1, -0.5]).setScale([0.5, 3, 1]).setRotation([0, 0.2588190451025207, 0.1, 0.96]);
  j0.addChild(j1);
  j1.addChild(j2);
  const rig = doc.createNode('rig').setTranslation([1, 2, 3]).setScale([1, 1, 2]).addChild(j0);

  const { positions, indices } = grid(5, 2);
  const n = positions.length / 3;
  // Skin A: J0, J1 with inverse bind matrices (column-major), float weights summing to 1.
  const ibmA = new Float32Array([
    1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0.5, 0.25, 0, 1,
    0.5, 0, 0, 0, 0, 2, 0, 0, 0, 0, 1, 0, 0, -1, 0.125, 1,
  ]);
  const skinA = doc.createSkin('A').addJoint(j0).addJoint(j1).setInverseBindMatrices(acc('MAT4', ibmA));
  const jointsA = new Uint16Array(n * 4);
  const weightsA = new Float32Array(n * 4);
  for (let v = 0; v < n; v++) {
    const y = positions[v * 3 + 1] / 2;
    jointsA.set([0, 1, 0, 0], v * 4);
    weightsA.set([1 - y, y, 0, 0], v * 4);
  }
  const primA = doc
    .createPrimitive()
    .setAttribute('POSITION', acc('VEC3', positions))
    .setAttribute('JOINTS_0', acc('VEC4', jointsA))
    .setAttribute('WEIGHTS_0', acc('VEC4', weightsA))
    .setIndices(acc('SCALAR', indices));
  const meshA = doc.createMesh('skinned_a').addPrimitive(primA);
  // Skin B: J2, J1, J0 without inverse bind matrices; normalized ubyte weights, ubyte joints.
  const skinB = doc.createSkin('B').addJoint(j2).addJoint(j1).addJoint(j0);
  const jointsB = new Uint8Array(n * 4);
  const weightsB = new Uint8Array(n * 4);
  for (let v = 0; v < n; v++) {
    const k = v % 3;
    const w = Math.min(Math.round((positions[v * 3] / 2) * 255), 255 - k);
    jointsB.set([0, 1, 2, 0], v * 4);
    weightsB.set([w, 255 - w - k, k, 0], v * 4);
  }
  const primB = doc
    .createPrimitive()
    .setAttribute('POSITION', acc('VEC3', positions))
    .setAttribute('JOINTS_0', acc('VEC4', jointsB))
    .setAttribute('WEIGHTS_0', acc('VEC4', weightsB).setNormalized(true))
    .setIndices(acc('SCALAR', indices));
  const meshB = doc.createMesh('skinned_b').addPrimitive(primB);

  const a = doc.createNode('skin_a').setMesh(meshA).setSkin(skinA).setTranslation([10, 0, 0]);
  const b = doc.createNode('skin_b').setMesh(meshB).setSkin(skinB).setScale([3, 3, 3]);
  const holder = doc.createNode('holder').setTranslation([0, -5, 0]).addChild(b);
  doc.createScene('scene').addChild(rig).addChild(a).addChild(holder);
  return doc;
}

// Adds to `animation` a sampler over float keyframe `times` and `values` (of accessor `type`)
// driving `path` of `node`.
function animate(doc, animation, node, path, interpolation, times, values, type) {
  const buffer = doc.getRoot().listBuffers()[0];
  const acc = (t, array) => doc.createAccessor().setType(t).setArray(new Float32Array(array)).setBuffer(buffer);
  const sampler = doc
    .createAnimationSampler()
    .setInput(acc('SCALAR', times))
    .setOutput(acc(type, values))
    .setInterpolation(interpolation);
  const channel = doc.createAnimationChannel().setTargetNode(node).setTargetPath(path).setSampler(sampler);
  animation.addSampler(sampler).addChannel(channel);
}

const nodeNamed = (doc, name) => doc.getRoot().listNodes().find((n) => n.getName() === name);

function morphAnimated() {
  const doc = morphSparse();
  const animation = doc.createAnimation('Morph');
  // CUBICSPLINE weights: per keyframe the in-tangents, the values, the out-tangents (2 targets).
  animate(doc, animation, nodeNamed(doc, 'node_weights'), 'weights', 'CUBICSPLINE', [0, 0.5, 1], [
    0, 0, 1, -0.5, 0.5, -1,
    2, 0.25, 0.2, 0.8, -1.5, 0.75,
    0.25, 1, -0.3, 1.2, 0, 0,
  ], 'SCALAR');
  animate(doc, animation, nodeNamed(doc, 'mesh_weights'), 'weights', 'STEP', [0.25, 0.6], [0, 1, 0.75, -0.25], 'SCALAR');
  animate(doc, animation, nodeNamed(doc, 'mesh_weights'), 'translation', 'CUBICSPLINE', [0.1, 0.9], [
    0, 0, 0, -4, 0, 0, 1, 2, -1,
    -2, 0.5, 3, -3.5, 1, 0.5, 0, 0, 0,
  ], 'VEC3');
  return doc;
}

function skinsAnimated() {
  const doc = skinsShared();
  const joints = doc.createAnimation('Joints');
  const s = Math.SQRT1_2;
  // CUBICSPLINE rotation: in-tangent, unit value, out-tangent per keyframe (the result is
  // normalized, as the specification says).
  animate(doc, joints, nodeNamed(doc, 'J0'), 'rotation', 'CUBICSPLINE', [0, 0.4, 1.2], [
    0, 0, 0, 0, 0, 0, 0.19509032201612825, 0.9807852804032304, 0.5, -0.25, 0, 0.1,
    0.3, 0, -0.2, 0.1, 0, s, 0, s, -0.4, 0.2, 0.6, 0,
    0, 0.1, 0, -0.1, 0.5, 0.5, 0.5, 0.5, 0, 0, 0, 0,
  ], 'VEC4');
  animate(doc, joints, nodeNamed(doc, 'J1'), 'scale', 'STEP', [0.2, 0.5], [1, 0.75, 1.25, 0.5, 2, 1.5], 'VEC3');
  animate(doc, joints, nodeNamed(doc, 'J2'), 'translation', 'LINEAR', [0, 1], [0.25, 1, -0.5, -0.75, 2, 0.5], 'VEC3');
  const rig = doc.createAnimation('Rig');
  animate(doc, rig, nodeNamed(doc, 'rig'), 'rotation', 'LINEAR', [0, 0.8], [0, 0, 0, 1, 0, 0.9238795325112867, 0, 0.3826834323650898], 'VEC4');
  return doc;
}

await io.write(join(out, 'morph-sparse.gltf'), morphSparse());
await io.write(join(out, 'skins-shared.gltf'), skinsShared());
await io.write(join(out, 'morph-animated.gltf'), morphAnimated());
await io.write(join(out, 'skins-animated.gltf'), skinsAnimated());
