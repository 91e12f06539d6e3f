// SPDX-License-Identifier: MIT
// citymesh viewer: streams /tiles/tileset.json (3D Tiles 1.1, Draco glb) with three.js and
// 3d-tiles-renderer, places the street at the origin (east-north-up, y up), and colours every
// triangle by its source acquisition (feature id _FEATURE_ID_0; stitch triangles magenta),
// naming each in the legend from the tiles' property table (EXT_structural_metadata); a
// click names the pass of the triangle under the pointer.
// URL parameters: ?error=16 (screen-space error target, pixels), ?color=date (oldest pass
// blue to newest yellow), ?color=none (plain grey).
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { DRACOLoader } from 'three/addons/loaders/DRACOLoader.js';
import { TilesRenderer } from '3d-tiles-renderer';
import { GLTFExtensionsPlugin } from '3d-tiles-renderer/plugins';
import { PALETTE, STITCH, NULL_FEATURE, acquisitionColours, describePick, legendHtml } from './palette.js';

const params = new URLSearchParams(location.search);
const status = document.getElementById('status');
const legend = document.getElementById('legend');

const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio);
renderer.setSize(window.innerWidth, window.innerHeight);
renderer.setClearColor(0x1b2330);
document.body.appendChild(renderer.domElement);

const scene = new THREE.Scene();
scene.add(new THREE.HemisphereLight(0xffffff, 0x445566, 1.6));
const sun = new THREE.DirectionalLight(0xffffff, 1.6);
sun.position.set(-0.4, 1.0, 0.6);
scene.add(sun);

const camera = new THREE.PerspectiveCamera(55, window.innerWidth / window.innerHeight, 0.1, 20000);
const controls = new OrbitControls(camera, renderer.domElement);

const tiles = new TilesRenderer('/tiles/tileset.json');
const draco = new DRACOLoader().setDecoderPath('/node_modules/three/examples/jsm/libs/draco/gltf/');
tiles.registerPlugin(new GLTFExtensionsPlugin({ dracoLoader: draco }));
tiles.errorTarget = Number(params.get('error') ?? 16);
tiles.setCamera(camera);
tiles.setResolutionFromRenderer(camera, renderer);
scene.add(tiles.group);

let models = 0;
const acquisitions = [];  // [{name, date}] by feature id, from the first tile's property table
let colours = [];

// The root transform maps the tileset's east-north-up frame to ECEF: undo it, then turn z-up
// into three.js's y-up, so that the street sits at the origin.
tiles.addEventListener('load-root-tileset', ({ tileset }) => {
  const root = tileset.root;
  const enuToEcef = new THREE.Matrix4().fromArray(root.transform ?? new THREE.Matrix4().elements);
  const toView = new THREE.Matrix4().makeRotationX(-Math.PI / 2).multiply(enuToEcef.invert());
  toView.decompose(tiles.group.position, tiles.group.quaternion, tiles.group.scale);
  tiles.group.updateMatrixWorld(true);
  const b = root.boundingVolume.box;
  const centre = new THREE.Vector3(b[0], b[2], -b[1]);
  const size = Math.max(Math.hypot(b[3], b[4], b[5]), Math.hypot(b[6], b[7], b[8]), 10);
  camera.position.copy(centre).add(new THREE.Vector3(-0.35 * size, 0.9 * size, 1.1 * size));
  controls.target.copy(centre);
  controls.update();
});

function colourByAcquisition(mesh) {
  const geometry = mesh.geometry;
  const ids = geometry.getAttribute('_feature_id_0');
  if (!geometry.getAttribute('normal')) geometry.computeVertexNormals();
  const material = new THREE.MeshLambertMaterial({ side: THREE.DoubleSide, color: 0xb8bcc4 });
  if (ids && params.get('color') !== 'none') {
    const rgbs = new Float32Array(ids.count * 3);
    for (let v = 0; v < ids.count; v++) {
      const id = ids.getX(v);
      const rgb = id === NULL_FEATURE ? STITCH : colours[id] ?? PALETTE[id % PALETTE.length];
      rgbs.set(rgb.map((c) => c / 255), v * 3);
    }
    geometry.setAttribute('color', new THREE.BufferAttribute(rgbs, 3));
    material.vertexColors = true;
    material.color.set(0xffffff);
  }
  mesh.material = material;
}

/// Every tile carries the run's whole acquisition table: read it from the first one.
function readAcquisitions(model) {
  const metadata = model.userData.structuralMetadata;
  const table = metadata?.tableAccessors?.[0];
  if (acquisitions.length || !table) return;
  for (let id = 0; id < table.count; id++) acquisitions.push(metadata.getPropertyTableData(0, id));
  colours = acquisitionColours(acquisitions, params.get('color'));
  legend.innerHTML = legendHtml(acquisitions, colours);
}

tiles.addEventListener('load-model', ({ scene: model }) => {
  models++;
  readAcquisitions(model);
  model.traverse((o) => { if (o.isMesh) colourByAcquisition(o); });
});
tiles.addEventListener('load-error', ({ url, error }) => {
  status.textContent = `cannot load ${url}: ${error}`;
});

// A click names the pass the triangle under the pointer comes from (its first corner's id:
// a triangle's corners share it, vertices being split where sources meet).
const raycaster = new THREE.Raycaster();
renderer.domElement.addEventListener('click', (event) => {
  const pointer = new THREE.Vector2((event.clientX / window.innerWidth) * 2 - 1,
    -(event.clientY / window.innerHeight) * 2 + 1);
  raycaster.setFromCamera(pointer, camera);
  const hit = raycaster.intersectObject(tiles.group, true)[0];
  const ids = hit?.object.geometry.getAttribute('_feature_id_0');
  document.getElementById('picked').textContent = !hit ? 'nothing here'
    : describePick(acquisitions, ids ? ids.getX(hit.face.a) : NULL_FEATURE);
});

window.addEventListener('resize', () => {
  camera.aspect = window.innerWidth / window.innerHeight;
  camera.updateProjectionMatrix();
  renderer.setSize(window.innerWidth, window.innerHeight);
  tiles.setResolutionFromRenderer(camera, renderer);
});

let lastFrame = 0;
function tick() {
  lastFrame = performance.now();
  controls.update();
  camera.updateMatrixWorld();
  tiles.update();
  renderer.render(scene, camera);
  const visible = tiles.visibleTiles ? tiles.visibleTiles.size : 0;
  const s = tiles.stats;
  // For tests and scripts: nothing left to fetch or parse, and something on screen.
  const settled = visible > 0 && s.queued === 0 && s.downloading === 0 && s.parsing === 0;
  document.body.dataset.settled = String(settled);
  if (!status.textContent.startsWith('cannot')) status.textContent = `citymesh · ${models} tiles loaded, ${visible} drawn`;
}
renderer.setAnimationLoop(tick);
// Background tabs and headless browsers get few animation frames: keep streaming anyway.
setInterval(() => { if (performance.now() - lastFrame > 250) tick(); }, 250);
