// The dynahand viewer page: draws what `dynahand serve` (or `dynahand play`) streams over
// its WebSocket (docs/formats/viewer-stream.md). Bundled with three.js by the CMake build.
import * as THREE from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
import { ConvexGeometry } from 'three/examples/jsm/geometries/ConvexGeometry.js';

const COLORS = {
  hand: 0xe39a6f,
  candidate: 0x8fb8ff,
  truth: 0x66cc88,
  keypoint: 0xffe14d,
  truthKeypoint: 0x2e7d4f,
  cloud: 0x7d8a99,
  samples: 0x4fc3f7,
  scene: 0xb0bec5,
};
// MediaPipe's 21-keypoint skeleton.
const BONES = [
  [0, 1], [1, 2], [2, 3], [3, 4], [0, 5], [5, 6], [6, 7], [7, 8], [5, 9], [9, 10], [10, 11],
  [11, 12], [9, 13], [13, 14], [14, 15], [15, 16], [13, 17], [0, 17], [17, 18], [18, 19], [19, 20],
];
const TRUTH_BESIDE_M = 0.16;  // how far to the right the ground truth is drawn when "beside"

// ---- Scene setup ----
const canvas = document.getElementById('view');
// preserveDrawingBuffer: screenshots and pixel checks read what was last drawn.
const renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0x1d2126);
const camera = new THREE.PerspectiveCamera(45, 1, 0.01, 20);
camera.position.set(0.1, 0.12, 0.05);
const controls = new OrbitControls(camera, canvas);
controls.target.set(0, 0, -0.45);
controls.update();
scene.add(new THREE.HemisphereLight(0xffffff, 0x404850, 1.2));
const sun = new THREE.DirectionalLight(0xffffff, 1.0);
sun.position.set(0.5, 1.0, 0.8);
scene.add(sun);
// A headlight: whatever side of the hand the orbit camera looks at is lit.
const headlight = new THREE.DirectionalLight(0xffffff, 1.4);
headlight.position.set(0, 0, 0);
headlight.target.position.set(0, 0, -1);
camera.add(headlight, headlight.target);
scene.add(camera);

// The depth camera's frame (x right, y down, z forward) turned to three's y up, -z forward.
const world = new THREE.Group();
world.rotation.x = Math.PI;
scene.add(world);

const layers = {};
function addLayer(name, label, visible = true, parent = world) {
  const group = new THREE.Group();
  group.visible = visible;
  parent.add(group);
  layers[name] = { group, label };
  return group;
}
addLayer('cloud', 'depth cloud');
addLayer('samples', 'samples');
addLayer('model', 'hand model');
addLayer('candidates', 'simulations');
addLayer('keypoints', 'keypoints');
addLayer('truth', 'ground truth');
const sceneRoot = new THREE.Group();  // playground bodies, oriented by the scene's "up"
scene.add(sceneRoot);
addLayer('scene', 'scene', true, sceneRoot);

function makePoints(color, size) {
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.Float32BufferAttribute(new Float32Array(3), 3));
  const points = new THREE.Points(geometry, new THREE.PointsMaterial({ color, size }));
  points.frustumCulled = false;
  return points;
}
const cloudPoints = makePoints(COLORS.cloud, 0.0035);
layers.cloud.group.add(cloudPoints);
const samplePoints = makePoints(COLORS.samples, 0.004);
layers.samples.group.add(samplePoints);

function setPoints(points, flat) {
  const geometry = points.geometry;
  let attr = geometry.getAttribute('position');
  if (attr.array.length < flat.length) {
    attr = new THREE.Float32BufferAttribute(new Float32Array(flat.length * 2), 3);
    geometry.setAttribute('position', attr);
  }
  attr.array.set(flat);
  attr.needsUpdate = true;
  geometry.setDrawRange(0, flat.length / 3);
}

// ---- Convex bodies ----
function hullGeometry(body) {
  if (!body.faces) {
    return new ConvexGeometry(body.vertices.map((v) => new THREE.Vector3(v[0], v[1], v[2])));
  }
  const positions = [];
  for (const face of body.faces) {  // polygons, counter-clockwise seen from outside
    for (let k = 1; k + 1 < face.length; ++k) {
      for (const i of [face[0], face[k], face[k + 1]]) positions.push(...body.vertices[i]);
    }
  }
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute('position', new THREE.Float32BufferAttribute(positions, 3));
  geometry.computeVertexNormals();
  return geometry;
}

function solidMaterial(color) {
  return new THREE.MeshStandardMaterial({ color, roughness: 0.65, metalness: 0.0 });
}
// Faint, and pushed back in depth so that where a ghost coincides with the winner's
// surface the winner shows; only where it differs does the ghost appear.
function ghostMaterial(color, opacity) {
  return new THREE.MeshStandardMaterial({
    color, transparent: true, opacity, depthWrite: false, roughness: 0.8,
    polygonOffset: true, polygonOffsetFactor: 2, polygonOffsetUnits: 8,
  });
}

// A set of meshes, one per body, posed from [{p, q}] lists.
class Rig {
  constructor(geometries, material, parent) {
    this.group = new THREE.Group();
    this.meshes = geometries.map((g) => {
      const mesh = new THREE.Mesh(g, material);
      this.group.add(mesh);
      return mesh;
    });
    this.group.visible = false;
    parent.add(this.group);
  }
  pose(bodies) {
    const n = Math.min(bodies.length, this.meshes.length);
    for (let i = 0; i < n; ++i) {
      const { p, q } = bodies[i];
      this.meshes[i].position.set(p[0], p[1], p[2]);
      this.meshes[i].quaternion.set(q[1], q[2], q[3], q[0]);
    }
    this.group.visible = n > 0;
  }
  dispose() {
    this.group.parent.remove(this.group);
  }
}

class Keypoints {
  constructor(color, parent) {
    const sphere = new THREE.SphereGeometry(0.003, 10, 8);
    // Drawn over the meshes (no depth test) so keypoints inside or behind the hand show.
    const material = new THREE.MeshBasicMaterial({ color, depthTest: false });
    this.spheres = new THREE.InstancedMesh(sphere, material, 21);
    const lineGeometry = new THREE.BufferGeometry();
    lineGeometry.setAttribute('position', new THREE.Float32BufferAttribute(BONES.length * 6, 3));
    this.lines = new THREE.LineSegments(lineGeometry,
      new THREE.LineBasicMaterial({ color, depthTest: false }));
    this.spheres.renderOrder = 2;
    this.lines.renderOrder = 2;
    this.group = new THREE.Group();
    this.group.add(this.spheres, this.lines);
    this.group.visible = false;
    this.spheres.frustumCulled = false;
    this.lines.frustumCulled = false;
    parent.add(this.group);
    this.matrix = new THREE.Matrix4();
  }
  set(points) {
    this.group.visible = Array.isArray(points);
    if (!this.group.visible) return;
    points.forEach((p, i) => {
      this.matrix.makeTranslation(p[0], p[1], p[2]);
      this.spheres.setMatrixAt(i, this.matrix);
    });
    this.spheres.instanceMatrix.needsUpdate = true;
    const attr = this.lines.geometry.getAttribute('position');
    BONES.forEach(([a, b], k) => {
      attr.array.set(points[a], k * 6);
      attr.array.set(points[b], k * 6 + 3);
    });
    attr.needsUpdate = true;
  }
}

// ---- State built from "hello" ----
let hands = [];  // per hand: {estimate, truth, candidates: Map(name -> Rig), keypoints, truthKeypoints}
let simulations = [];
let framed = false;  // the orbit camera has been pointed at the hand

function clearHands() {
  for (const h of hands) {
    h.estimate.dispose();
    h.truth.dispose();
    for (const c of h.candidates.values()) c.dispose();
    h.keypoints.group.parent.remove(h.keypoints.group);
    h.truthKeypoints.group.parent.remove(h.truthKeypoints.group);
  }
  hands = [];
}

function onHello(msg) {
  clearHands();
  simulations = msg.simulations || [];
  document.getElementById('source').textContent = msg.source || '';
  const handMaterial = solidMaterial(COLORS.hand);
  const truthMaterial = ghostMaterial(COLORS.truth, 0.55);
  const candidateMaterial = ghostMaterial(COLORS.candidate, 0.13);
  for (const model of msg.models || []) {
    const geometries = model.bodies.map(hullGeometry);
    const candidates = new Map();
    for (const name of simulations) {
      candidates.set(name, new Rig(geometries, candidateMaterial, layers.candidates.group));
    }
    hands.push({
      estimate: new Rig(geometries, handMaterial, layers.model.group),
      truth: new Rig(geometries, truthMaterial, layers.truth.group),
      candidates,
      keypoints: new Keypoints(COLORS.keypoint, layers.keypoints.group),
      truthKeypoints: new Keypoints(COLORS.truthKeypoint, layers.truth.group),
    });
  }
  layers.truth.available = !!msg.ground_truth;
  buildLayerToggles();
}

// ---- Frames ----
const stats = { framesReceived: 0, framesDrawn: 0, lastIndex: -1, handVisible: false };
window.dynahandViewer = stats;  // read by the browser test
let dirty = false;
let paused = false;

function onFrame(msg) {
  stats.framesReceived += 1;
  stats.lastIndex = msg.index;
  document.getElementById('frame-count').textContent = String(stats.framesReceived);
  document.getElementById('frame-index').textContent = `${msg.index} (loop ${msg.loop})`;
  document.getElementById('tracking-fps').textContent = msg.tracking_fps.toFixed(1);
  paused = !!msg.paused;
  document.getElementById('pause').textContent = paused ? 'resume' : 'pause';

  if (msg.cloud) setPoints(cloudPoints, msg.cloud);
  if (msg.samples) setPoints(samplePoints, msg.samples);
  const handResults = msg.track.hands || [];
  stats.handVisible = false;
  hands.forEach((rig, h) => {
    const r = handResults[h];
    if (r && r.tracked && r.bodies) {
      rig.estimate.pose(r.bodies);
      stats.handVisible = true;
    } else {
      rig.estimate.group.visible = false;
    }
    rig.keypoints.set(r && r.tracked ? r.keypoints21 : null);
    for (const [name, ghost] of rig.candidates) {
      const c = r && r.candidates ? r.candidates.find((x) => x.simulation === name) : null;
      if (c && c.bodies) ghost.pose(c.bodies);
      else ghost.group.visible = false;
    }
    const t = msg.truth ? msg.truth[h] : null;
    if (t && t.bodies && t.bodies.length) rig.truth.pose(t.bodies);
    else rig.truth.group.visible = false;
    rig.truthKeypoints.set(t ? t.keypoints21 : null);
  });
  showErrors(handResults[0]);
  if (!framed) frameHand(handResults[0], msg.truth ? msg.truth[0] : null);
  dirty = true;
}

function frameHand(result, truth) {
  const points = result && result.tracked ? result.keypoints21 : truth ? truth.keypoints21 : null;
  if (!points) return;
  const p = points[9];  // middle finger MCP: the middle of the hand
  const beside = truthBeside && layers.truth.available ? TRUTH_BESIDE_M / 2 : 0;
  controls.target.set(p[0] + beside, -p[1], -p[2]);
  camera.position.set(p[0] + beside + 0.03, -p[1] + 0.07, -p[2] + 0.42);
  controls.update();
  framed = true;
}

function showErrors(result) {
  const box = document.getElementById('errors');
  const rows = (result && result.candidates) || [];
  const max = Math.max(1e-6, ...rows.map((c) => c.error || 0));
  box.replaceChildren(...rows.map((c) => {
    const bar = document.createElement('div');
    bar.className = 'bar' + (c.simulation === result.simulation ? ' winner' : '');
    const fill = document.createElement('div');
    fill.className = 'fill';
    fill.style.width = `${(100 * (c.error || 0)) / max}%`;
    const label = document.createElement('span');
    label.className = 'label';
    label.textContent = `${c.simulation} ${c.error === null ? '-' : (1000 * c.error).toFixed(0)}`;
    bar.append(fill, label);
    return bar;
  }));
}

// ---- Playground scenes ----
let sceneRigs = [];
function onScene(msg) {
  for (const m of sceneRigs) layers.scene.group.remove(m);
  const up = msg.up || '-y';
  sceneRoot.rotation.set(up === '-y' ? Math.PI : up === 'z' ? -Math.PI / 2 : 0, 0, 0);
  sceneRigs = msg.bodies.map((body) => {
    const mesh = new THREE.Mesh(hullGeometry(body), solidMaterial(body.color || COLORS.scene));
    layers.scene.group.add(mesh);
    return mesh;
  });
  layers.scene.available = true;
  sceneFramed = false;
  buildLayerToggles();
}
// Points the orbit camera at the whole scene, from above and in front.
function frameScene() {
  sceneRoot.updateMatrixWorld(true);
  const bounds = new THREE.Box3().setFromObject(layers.scene.group);
  if (bounds.isEmpty()) return;
  const centre = bounds.getCenter(new THREE.Vector3());
  const size = Math.max(0.05, bounds.getSize(new THREE.Vector3()).length());
  controls.target.copy(centre);
  camera.position.set(centre.x + 0.3 * size, centre.y + 0.6 * size, centre.z + 0.9 * size);
  controls.update();
  sceneFramed = true;
}
let sceneFramed = false;
function onScenePoses(msg) {
  msg.poses.forEach(({ p, q }, i) => {
    const mesh = sceneRigs[i];
    if (!mesh) return;
    mesh.position.set(p[0], p[1], p[2]);
    mesh.quaternion.set(q[1], q[2], q[3], q[0]);
  });
  if (!sceneFramed && !hands.length) frameScene();
  stats.framesReceived += 1;
  document.getElementById('frame-count').textContent = String(stats.framesReceived);
  document.getElementById('frame-index').textContent = String(msg.step);
  dirty = true;
}

// ---- Controls ----
let truthBeside = true;
function buildLayerToggles() {
  const box = document.getElementById('layers');
  const toggles = Object.entries(layers)
    .filter(([name, layer]) => (['truth', 'scene'].includes(name) ? layer.available
      : hands.length > 0))
    .map(([name, layer]) => checkbox(layer.label, layer.group.visible, (on) => {
      layer.group.visible = on;
    }, `layer-${name}`));
  if (layers.truth.available) {
    toggles.push(checkbox('truth beside', truthBeside, (on) => {
      truthBeside = on;
      placeTruth();
    }, 'layer-truth-beside'));
  }
  box.replaceChildren(...toggles);
  placeTruth();
}
function placeTruth() {
  layers.truth.group.position.x = truthBeside ? TRUTH_BESIDE_M : 0;
}
function checkbox(text, checked, onChange, id) {
  const label = document.createElement('label');
  const input = document.createElement('input');
  input.type = 'checkbox';
  input.checked = checked;
  input.id = id;
  input.addEventListener('change', () => onChange(input.checked));
  label.append(input, ` ${text}`);
  return label;
}

let socket = null;
function send(action) {
  if (socket && socket.readyState === WebSocket.OPEN) {
    socket.send(JSON.stringify({ type: 'control', action }));
  }
}
document.getElementById('pause').addEventListener('click', () => {
  paused = !paused;
  document.getElementById('pause').textContent = paused ? 'resume' : 'pause';
  send(paused ? 'pause' : 'resume');
});
document.getElementById('step').addEventListener('click', () => send('step'));

// ---- Connection ----
function setStatus(text, error = false) {
  const status = document.getElementById('status');
  status.textContent = text;
  status.className = error ? 'error' : '';
}
// The run's token, when the page's address carries it (dynahand prints the page's address
// as http://HOST:PORT/?token=...). The server lets the page's own origin in without it; a
// page opened at any other address needs it (docs/commands.md, "dynahand serve").
const token = new URLSearchParams(location.search).get('token');
let everConnected = false;
function connect() {
  const query = token ? `?token=${encodeURIComponent(token)}` : '';
  socket = new WebSocket(`ws://${location.host}/${query}`);
  socket.onopen = () => {
    everConnected = true;
    setStatus('connected');
  };
  socket.onclose = () => {
    setStatus(everConnected ? 'disconnected; retrying…'
      : 'cannot connect (is dynahand still running? from this address the page needs the ' +
        '?token= dynahand printed); retrying…', true);
    setTimeout(connect, 1000);
  };
  socket.onmessage = (event) => {
    const msg = JSON.parse(event.data);
    if (msg.type === 'hello') onHello(msg);
    else if (msg.type === 'frame') onFrame(msg);
    else if (msg.type === 'scene') onScene(msg);
    else if (msg.type === 'scene_poses') onScenePoses(msg);
    else if (msg.type === 'error') setStatus(`server: ${msg.message}`, true);
  };
}
connect();
buildLayerToggles();

// ---- Drawing ----
let viewFrames = 0;
let viewSince = performance.now();
function resize() {
  const w = canvas.clientWidth;
  const h = canvas.clientHeight;
  if (canvas.width !== Math.floor(w * renderer.getPixelRatio()) ||
      canvas.height !== Math.floor(h * renderer.getPixelRatio())) {
    renderer.setSize(w, h, false);
    camera.aspect = w / Math.max(1, h);
    camera.updateProjectionMatrix();
  }
}
function animate() {
  resize();
  controls.update();
  renderer.render(scene, camera);
  if (dirty) {
    stats.framesDrawn += 1;
    dirty = false;
  }
  viewFrames += 1;
  const now = performance.now();
  if (now - viewSince > 1000) {
    document.getElementById('view-fps').textContent = ((1000 * viewFrames) / (now - viewSince)).toFixed(0);
    viewFrames = 0;
    viewSince = now;
  }
  requestAnimationFrame(animate);
}
requestAnimationFrame(animate);
