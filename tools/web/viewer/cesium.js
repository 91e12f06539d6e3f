// SPDX-License-Identifier: MIT
// citymesh in CesiumJS: streams /tiles/tileset.json in CesiumJS's Earth-centred frame (no
// globe, imagery or terrain: nothing is fetched from the internet), looks at it obliquely,
// colours every triangle by its source acquisition (feature id _FEATURE_ID_0; stitch
// triangles magenta) and names each in the legend from the tiles' property table.
// A click names the pass the triangle under the pointer comes from (name, date, index).
// The status line gives the tiles loaded and failed and where CesiumJS placed the tileset's
// centre (latitude, longitude, ellipsoidal height): tests compare it with the input's place.
// Triangles are single-sided, as glTF says by default: each is wound to face the sensor that
// saw it, so a facade seen from behind (from inside its building) is not drawn.
// URL parameters: ?error=16 (maximum screen-space error, pixels), ?color=date (oldest pass
// blue to newest yellow), ?color=none (plain grey), ?cull=0 (draw both sides, as the
// three.js page does).
import { PALETTE, STITCH, NULL_FEATURE, acquisitionColours, describePick, legendHtml } from './palette.js';

const Cesium = window.Cesium;
const params = new URLSearchParams(location.search);
const status = document.getElementById('status');
const legend = document.getElementById('legend');

const viewer = new Cesium.Viewer('globe', {
  baseLayer: false, baseLayerPicker: false, geocoder: false, homeButton: false, sceneModePicker: false,
  navigationHelpButton: false, animation: false, timeline: false, fullscreenButton: false, infoBox: false,
  selectionIndicator: false, globe: false,
  contextOptions: { webgl: { preserveDrawingBuffer: true } },  // for screenshots
});
const scene = viewer.scene;
scene.backgroundColor = Cesium.Color.fromCssColorString('#1b2330');
scene.skyBox.show = false;
scene.skyAtmosphere.show = false;
scene.sun.show = false;
scene.moon.show = false;

const vec3 = (rgb) => `vec3(${rgb.map((c) => (c / 255).toFixed(4)).join(', ')})`;

/// Colours every triangle by its feature id (`colours`, by id; stitch triangles magenta), flat
/// shaded from the screen-space derivatives of the eye position: the tiles carry no normals,
/// and a light fixed to the camera keeps the picture independent of the date.
function colourShader(colours) {
  const n = colours.length;
  const colour = params.get('color') === 'none' || n === 0 ? 'vec3(0.72, 0.74, 0.77)' : `
      id == ${NULL_FEATURE} ? ${vec3(STITCH)} : id < ${n} ? colours[id] : ${vec3(PALETTE[7])}`;
  return new Cesium.CustomShader({
    lightingModel: Cesium.LightingModel.UNLIT,
    fragmentShaderText: `
      ${n ? `const vec3 colours[${n}] = vec3[${n}](${colours.map(vec3).join(', ')});` : ''}
      void fragmentMain(FragmentInput fsInput, inout czm_modelMaterial material) {
        vec3 p = fsInput.attributes.positionEC;
        vec3 normal = normalize(cross(dFdx(p), dFdy(p)));
        float shade = 0.35 + 0.65 * abs(dot(normal, normalize(vec3(0.3, 0.5, 1.0))));
      #ifdef HAS_SELECTED_FEATURE_ID
        int id = fsInput.featureIds.featureId_0;
      #else
        int id = ${NULL_FEATURE};  // a tile without feature ids holds stitch triangles only
      #endif
        material.diffuse = (${colour}) * shade;
      }`,
  });
}

let loaded = 0;
const failures = [];
const acquisitions = [];  // [{name, date}] by feature id
let place = '';

function showStatus() {
  const failed = failures.length ? `, ${failures.length} failed (${failures[0]})` : ', 0 failed';
  status.textContent = `citymesh · CesiumJS ${Cesium.VERSION} · ${loaded} tiles loaded${failed}${place}`;
}

/// The tileset's centre on the ellipsoid, as CesiumJS placed it.
function describePlace(tileset) {
  const c = Cesium.Cartographic.fromCartesian(tileset.boundingSphere.center);
  const deg = Cesium.Math.toDegrees;
  return ` · centre lat ${deg(c.latitude).toFixed(7)} lon ${deg(c.longitude).toFixed(7)} h ${c.height.toFixed(1)} m`;
}

/// Every tile carries the run's whole acquisition table (EXT_structural_metadata): the first
/// one with features names and dates them, for the legend and the colours.
function readAcquisitions(tileset, content) {
  if (acquisitions.length || !content.featuresLength) return;
  for (let id = 0; id < content.featuresLength; id++) {
    const feature = content.getFeature(id);
    acquisitions.push({ name: String(feature.getProperty('name')), date: String(feature.getProperty('date')) });
  }
  const colours = acquisitionColours(acquisitions, params.get('color'));
  tileset.customShader = colourShader(colours);
  legend.innerHTML = legendHtml(acquisitions, colours);
}

try {
  const tileset = await Cesium.Cesium3DTileset.fromUrl('/tiles/tileset.json', {
    maximumScreenSpaceError: Number(params.get('error') ?? 16),
    backFaceCulling: params.get('cull') !== '0',
  });
  tileset.customShader = colourShader([]);
  tileset.tileLoad.addEventListener((tile) => {
    loaded++;
    readAcquisitions(tileset, tile.content);
  });
  tileset.tileFailed.addEventListener((e) => failures.push(`${e.url}: ${e.message}`));
  scene.primitives.add(tileset);
  place = describePlace(tileset);
  const radius = Math.max(tileset.boundingSphere.radius, 10);
  await viewer.zoomTo(tileset, new Cesium.HeadingPitchRange(Cesium.Math.toRadians(20), Cesium.Math.toRadians(-40),
    2.2 * radius));
  // A click names the pass the triangle under the pointer comes from.
  viewer.screenSpaceEventHandler.setInputAction((click) => {
    const picked = scene.pick(click.position);
    document.getElementById('picked').textContent = !picked ? 'nothing here'
      : describePick(acquisitions, picked instanceof Cesium.Cesium3DTileFeature ? picked.featureId : NULL_FEATURE);
  }, Cesium.ScreenSpaceEventType.LEFT_CLICK);
  // For tests and scripts: every tile the view needs is loaded and something is drawn.
  scene.postRender.addEventListener(() => {
    showStatus();
    document.body.dataset.settled = String(tileset.tilesLoaded && loaded > 0);
  });
} catch (e) {
  status.textContent = `cannot load /tiles/tileset.json: ${e.message ?? e}`;
  failures.push(String(e.message ?? e));
}
