// semrec's scene viewer. USD scenes are composed and read by Pixar's OpenUSD compiled to
// WebAssembly (three-usdz-loader's emHdBindings: a Hydra scene delegate that calls the render
// delegate below); .glb scenes by three's GLTFLoader. Our render delegate draws Mesh and Points
// prims (the stock one draws only meshes), and the viewer honours the stage's upAxis and the
// people's time-sampled visibility, which the stock loader ignores.
//
// For headless use, window.semrecLoaded is a promise of a result object (what OpenUSD read), and
// window.semrecSetView({camera, time}) frames the scene and renders it.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';

const kStructureClasses = new Set(['wall', 'floor', 'ceiling']);

// Fixed, well-separated colours for common indoor classes (so they read the same in every
// scene); any other class gets a stable colour from a hash of its name.
const kClassColors = {
  wall: '#b4b4a0', floor: '#8c6e50', ceiling: '#d2d2e6', person: '#e6194b', chair: '#3cb44b',
  table: '#ffe119', sofa: '#4363d8', bed: '#f58231', cabinet: '#911eb4', shelf: '#46f0f0',
  door: '#f032e6', windowpane: '#bcf60c', window: '#bcf60c', plant: '#008080',
  curtain: '#e6beff', desk: '#9a6324', lamp: '#fffac8', monitor: '#800000', tv: '#800000',
  box: '#aaffc3', book: '#808000', picture: '#ffd8b1', pillow: '#000075', bottle: '#a9a9a9',
  cup: '#ff7f50', building: '#9aa5b1', rug: '#c71585', counter: '#5f9ea0', sink: '#4682b4',
  refrigerator: '#2f4f4f', toilet: '#dda0dd', bathtub: '#87ceeb', mirror: '#708090',
};
function ClassColor(label) {
  if (kClassColors[label]) return new THREE.Color(kClassColors[label]);
  let h = 2166136261;
  for (const c of label) h = Math.imul(h ^ c.charCodeAt(0), 16777619) >>> 0;
  return new THREE.Color().setHSL((h % 360) / 360, 0.65, 0.5);
}

// ---------------------------------------------------------------------------------------------
// Render delegate: OpenUSD's Hydra calls these while syncing the stage.
class HydraPrim {
  constructor(typeId, path, root) {
    this.typeId = typeId;
    this.path = path;
    this.geometry = new THREE.BufferGeometry();
    this.points = null;
    this.indices = null;
    this.normals = null;
    this.colors = null;
    this.constantColor = new THREE.Color(0.8, 0.8, 0.8);
    if (typeId === 'points') {
      this.material = new THREE.PointsMaterial({ size: 0.04, sizeAttenuation: true });
      this.object = new THREE.Points(this.geometry, this.material);
    } else {
      this.material = new THREE.MeshStandardMaterial({
        side: THREE.DoubleSide, roughness: 0.85, metalness: 0.0,
      });
      this.object = new THREE.Mesh(this.geometry, this.material);
    }
    this.object.matrixAutoUpdate = false;
    this.object.userData.prim = this;
    root.add(this.object);
  }
  updatePoints(points) {
    this.points = Float32Array.from(points);
    this.geometry.setAttribute('position', new THREE.BufferAttribute(this.points, 3));
    this.refreshColors();
    this.geometry.computeBoundingBox();
    this.geometry.computeBoundingSphere();
  }
  updateIndices(indices) {
    this.indices = Uint32Array.from(indices);
    this.geometry.setIndex(new THREE.BufferAttribute(this.indices, 1));
    if (!this.normals) this.geometry.computeVertexNormals();
  }
  updateNormals(normals) {
    if (this.points && normals.length === this.points.length) {
      this.normals = Float32Array.from(normals);
      this.geometry.setAttribute('normal', new THREE.BufferAttribute(this.normals, 3));
    }
  }
  updatePrimvar(name, data, dimension, interpolation) {
    if (name !== 'displayColor') return;
    if (interpolation === 'constant' || data.length === 3) {
      this.constantColor = new THREE.Color(data[0], data[1], data[2]);
      this.colors = null;
    } else if (interpolation === 'vertex' || interpolation === 'varying') {
      this.colors = Float32Array.from(data);
    }
    this.refreshColors();
  }
  refreshColors() {
    if (this.colors && this.points && this.colors.length === this.points.length) {
      this.geometry.setAttribute('color', new THREE.BufferAttribute(this.colors, 3));
    } else {
      this.geometry.deleteAttribute('color');
    }
    Viewer.applyColor(this);
  }
  setTransform(matrix) {
    this.object.matrix.fromArray(matrix);  // USD matrices are row-vector: three's column-major
    this.object.matrixWorldNeedsUpdate = true;
  }
  setMaterial() {}
  commit() {}
}

class RenderDelegate {
  constructor(root) {
    this.root = root;
    this.prims = new Map();
    this.unsupported = [];
  }
  createRPrim(typeId, path) {
    if (typeId !== 'mesh' && typeId !== 'points') {
      this.unsupported.push(`${typeId} ${path}`);
      return { updatePoints() {}, updateIndices() {}, updateNormals() {}, updatePrimvar() {},
               setTransform() {}, setMaterial() {}, commit() {} };
    }
    const prim = new HydraPrim(typeId, path, this.root);
    this.prims.set(path, prim);
    return prim;
  }
  createSPrim() { return undefined; }
  createBPrim() { return undefined; }
  CommitResources() {}
}

// ---------------------------------------------------------------------------------------------
// Reading what OpenUSD composed.

function AttributeValue(prim, name) {
  try {
    const attr = prim.GetAttribute(name);
    const value = attr.Get();
    return value === undefined || value === null ? null : value;
  } catch {
    return null;
  }
}

// The stage metadata and the People prims' visibility samples, from OpenUSD's own serialisation
// of the layers it loaded (the 0.22 bindings have no time-sampled Get and no metadata getters).
function LayerFacts(stage) {
  const root = stage.GetRootLayer().ExportToString();
  const header = root.slice(0, root.indexOf('\ndef ') >= 0 ? root.indexOf('\ndef ') : 20000);
  const facts = {
    upAxis: (/upAxis = "([YZ])"/.exec(header) || [null, 'Y'])[1],
    metersPerUnit: Number((/metersPerUnit = ([0-9.eE+-]+)/.exec(header) || [null, 1])[1]),
    visibility: new Map(),
  };
  const stack = stage.GetLayerStack(true);
  for (let i = 0; i < stack.size(); i++) {
    const text = stack.get(i).ExportToString();
    // def Xform "person_3" ( ... ) { ... token visibility.timeSamples = { 0: "inherited", ... }
    const re = /def \w+ "(\w+)"[^{]*\{\s*([^{}]*?)token visibility\.timeSamples = \{([^}]*)\}/g;
    for (let m; (m = re.exec(text));) {
      const samples = [];
      for (const s of m[3].matchAll(/([0-9.eE+-]+):\s*"(\w+)"/g)) {
        samples.push([Number(s[1]), s[2] !== 'invisible']);
      }
      samples.sort((a, b) => a[0] - b[0]);
      facts.visibility.set(m[1], samples);
    }
  }
  return facts;
}

// Held interpolation, as USD does for tokens.
function VisibleAt(samples, time) {
  if (!samples || samples.length === 0) return true;
  let visible = samples[0][1];
  for (const [t, v] of samples) {
    if (t <= time) visible = v;
  }
  return visible;
}

async function LoadScript(src) {
  await new Promise((resolve, reject) => {
    const tag = document.createElement('script');
    tag.onload = resolve;
    tag.onerror = () => reject(new Error(`cannot load ${src}`));
    tag.src = src;
    document.head.appendChild(tag);
  });
}

async function FetchBytes(url) {
  const res = await fetch(url);
  if (!res.ok) throw new Error(`cannot fetch ${url}: HTTP ${res.status}`);
  return new Uint8Array(await res.arrayBuffer());
}

// ---------------------------------------------------------------------------------------------
const Viewer = {
  classColors: false,
  items: [],  // {object, prim?, path, label, instanceId, structure, person, name}
  time: 0,
  applyColor(prim) {
    const item = prim.item;
    const useClass = Viewer.classColors && item;
    const hasVertexColors = !!prim.geometry.getAttribute('color');
    prim.material.vertexColors = !useClass && hasVertexColors;
    prim.material.color = useClass ? ClassColor(item.label)
                                   : (hasVertexColors ? new THREE.Color(1, 1, 1) : prim.constantColor);
    prim.material.needsUpdate = true;
  },
};

async function LoadUsd(config, root) {
  if (!window.crossOriginIsolated) {
    throw new Error('the page is not cross-origin isolated (OpenUSD-WASM needs SharedArrayBuffer)');
  }
  await LoadScript('/usd/emHdBindings.js');
  const usd = await window.getUsdModule(undefined, '/usd', undefined);
  await usd.ready;
  for (const name of [...config.layers, config.scene]) {
    usd.FS.createDataFile('/', name, await FetchBytes(`/scene/${encodeURIComponent(name)}`),
                          true, true, true);
  }
  const delegate = new RenderDelegate(root);
  const driver = new usd.HdWebSyncDriver(delegate, config.scene);
  driver.Draw();
  const stage = driver.GetStage();
  if (delegate.prims.size === 0) {
    throw new Error(`OpenUSD found no Mesh or Points prims in ${config.scene}` +
                    ' (not a USD scene, or an empty one)');
  }
  const facts = LayerFacts(stage);
  const items = [];
  for (const [path, prim] of delegate.prims) {
    // People: the semantics sit on the Xform above the Points prim "Cloud".
    const person = path.startsWith('/World/People/');
    const holderPath = person ? path.slice(0, path.lastIndexOf('/')) : path;
    const holder = stage.GetPrimAtPath(holderPath);
    const classes = AttributeValue(holder, 'semantics:labels:class');
    const label = (Array.isArray(classes) && classes.length ? classes[0] : null) ??
                  AttributeValue(holder, 'semrec:label') ?? holderPath.split('/').pop();
    const name = holderPath.split('/').pop();
    const item = {
      object: prim.object, prim, path: holderPath, name, label, person,
      instanceId: AttributeValue(holder, person ? 'semrec:trackId' : 'semrec:instanceId'),
      confidence: person ? null : AttributeValue(holder, 'semrec:confidence') ?? null,
      structure: path.startsWith('/World/Structure/') || kStructureClasses.has(label),
      visibility: person ? (facts.visibility.get(name) ?? []) : [],
    };
    prim.item = item;
    Viewer.applyColor(prim);
    items.push(item);
  }
  return {
    items,
    facts,
    unsupported: delegate.unsupported,
    timeRange: { start: stage.GetStartTimeCode(), end: stage.GetEndTimeCode(),
                 fps: stage.GetTimeCodesPerSecond() },
    setTime(t) {
      driver.SetTime(t);
      driver.Draw();
    },
  };
}

async function LoadGlb(config, root) {
  const gltf = await new GLTFLoader().loadAsync(`/scene/${encodeURIComponent(config.scene)}`);
  root.add(gltf.scene);
  const items = [];
  gltf.scene.traverse((node) => {
    const extras = node.userData || {};
    if (!extras.semrec_class) return;
    const person = extras.semrec_kind === 'person';
    node.traverse((child) => {
      if (!child.isMesh && !child.isPoints) return;
      // glTF points are one pixel; draw people's clouds like the USD ones.
      if (child.isPoints) child.material = new THREE.PointsMaterial({ size: 0.04, color: child.material.color });
      const item = {
        object: child, path: node.name, name: node.name, label: extras.semrec_class, person,
        instanceId: extras.semrec_instance_id ?? null,
        confidence: person ? null : extras.semrec_confidence ?? null,
        structure: extras.semrec_kind === 'structure', visibility: [],
      };
      child.userData.item = item;
      items.push(item);
    });
  });
  // glTF is Y-up by definition.
  const mixer = gltf.animations.length ? new THREE.AnimationMixer(gltf.scene) : null;
  const actions = [];
  for (const clip of gltf.animations) {
    // The timeline drives the time; past the last key the last frame holds (no wrap to 0).
    const action = mixer.clipAction(clip);
    actions.push(action);
    action.setLoop(THREE.LoopOnce);
    action.clampWhenFinished = true;
    action.play();
  }
  const duration = Math.max(0, ...gltf.animations.map((c) => c.duration));
  const fps = 10;
  return {
    items,
    facts: { upAxis: 'Y', metersPerUnit: 1, visibility: new Map() },
    unsupported: [],
    animations: gltf.animations.length,
    timeRange: { start: 0, end: duration * fps, fps },
    setTime(t) {
      // Keyframe times are float32 (0.2 is stored as 0.2000000030): a hair past the frame, so a
      // STEP key at exactly this frame applies.
      if (!mixer) return;
      for (const action of actions) action.reset();  // a finished action would stay paused
      mixer.setTime(t / fps + 1e-4);
    },
  };
}

// ---------------------------------------------------------------------------------------------
const container = document.getElementById('view');
const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio);
container.appendChild(renderer.domElement);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0x30353b);
scene.add(new THREE.HemisphereLight(0xffffff, 0x445566, 1.6));
const sun = new THREE.DirectionalLight(0xffffff, 1.4);
scene.add(sun);
const root = new THREE.Group();
scene.add(root);
const camera = new THREE.PerspectiveCamera(50, 1, 0.02, 500);
let controls = null;
let loaded = null;

function Resize() {
  const w = container.clientWidth;
  const h = container.clientHeight;
  renderer.setSize(w, h);
  camera.aspect = w / Math.max(1, h);
  camera.updateProjectionMatrix();
}

function Render() {
  root.updateMatrixWorld(true);
  renderer.render(scene, camera);
}

function UpVector() {
  return loaded && loaded.facts.upAxis === 'Z' ? new THREE.Vector3(0, 0, 1)
                                               : new THREE.Vector3(0, 1, 0);
}

function ApplyVisibility() {
  const showStructure = document.getElementById('structure').checked;
  const showCeiling = document.getElementById('ceiling').checked;
  for (const item of Viewer.items) {
    let visible = !Viewer.hiddenClasses.has(item.label);
    if (item.structure) visible &&= item.label === 'ceiling' ? showCeiling : showStructure;
    if (item.person) visible &&= VisibleAt(item.visibility, Viewer.time);
    item.object.visible = visible;
  }
}

// Shown in the picture: visible, and not scaled to nothing (how glTF hides people).
function Shown(item) {
  if (!item.object.visible) return false;
  const scale = new THREE.Vector3();
  item.object.getWorldScale(scale);
  return Math.abs(scale.x * scale.y * scale.z) > 1e-12;
}
Viewer.hiddenClasses = new Set();

function SceneBox(includeStructure) {
  const box = new THREE.Box3();
  root.updateMatrixWorld(true);
  for (const item of Viewer.items) {
    if (!includeStructure && item.structure) continue;
    if (item.person) continue;
    box.expandByObject(item.object);
  }
  return box;
}

// Frames the camera on the scene from a named direction (in the scene's up-axis convention).
function FrameCamera(name) {
  let box = SceneBox(true);
  if (box.isEmpty()) box = new THREE.Box3().setFromObject(root);
  if (box.isEmpty()) box = new THREE.Box3(new THREE.Vector3(-1, -1, -1), new THREE.Vector3(1, 1, 1));
  const center = box.getCenter(new THREE.Vector3());
  const radius = Math.max(0.5, box.getSize(new THREE.Vector3()).length() / 2);
  const up = UpVector();
  // Horizontal axes: for Z-up, x and -y (looking "into" the room from the front); for Y-up, x and z.
  const right = new THREE.Vector3(1, 0, 0);
  const back = up.z ? new THREE.Vector3(0, -1, 0) : new THREE.Vector3(0, 0, 1);
  const dirs = {
    iso: back.clone().multiplyScalar(1.0).add(right.clone().multiplyScalar(0.6))
             .add(up.clone().multiplyScalar(0.9)),
    top: up.clone().add(back.clone().multiplyScalar(0.02)),
    front: back.clone().add(up.clone().multiplyScalar(0.15)),
    side: right.clone().add(up.clone().multiplyScalar(0.15)),
  };
  const dir = (dirs[name] || dirs.iso).normalize();
  // The bounding sphere just fits the vertical field of view; rooms are boxes, so come closer.
  const distance = radius / Math.sin(THREE.MathUtils.degToRad(camera.fov / 2)) * 0.75;
  camera.up.copy(up);
  camera.position.copy(center).addScaledVector(dir, distance);
  camera.near = distance / 100;
  camera.far = distance * 10;
  camera.lookAt(center);
  camera.updateProjectionMatrix();
  sun.position.copy(center).addScaledVector(up, radius * 3).addScaledVector(right, radius);
  if (controls) controls.dispose();
  controls = new OrbitControls(camera, renderer.domElement);
  controls.target.copy(center);
  controls.update();
  controls.addEventListener('change', Render);
}

// Where a world point lands in the picture, in pixels from the top-left corner.
function ScreenPoint(p) {
  const v = p.clone().project(camera);
  return { x: (v.x + 1) / 2 * renderer.domElement.width, y: (1 - v.y) / 2 * renderer.domElement.height };
}

function BuildLegend() {
  const counts = new Map();
  for (const item of Viewer.items) {
    const entry = counts.get(item.label) ?? { objects: new Set(), person: item.person };
    entry.objects.add(item.path);
    counts.set(item.label, entry);
  }
  const table = document.getElementById('legend');
  table.innerHTML = '';
  for (const [label, entry] of [...counts].sort((a, b) => a[0].localeCompare(b[0]))) {
    const row = table.insertRow();
    const swatch = row.insertCell().appendChild(document.createElement('div'));
    swatch.className = 'swatch';
    swatch.style.background = `#${ClassColor(label).getHexString()}`;
    row.insertCell().textContent = label;
    row.insertCell().textContent = String(entry.objects.size);
    row.title = 'click to hide or show';
    row.onclick = () => {
      if (Viewer.hiddenClasses.has(label)) Viewer.hiddenClasses.delete(label);
      else Viewer.hiddenClasses.add(label);
      row.classList.toggle('off');
      ApplyVisibility();
      Render();
    };
  }
  return Object.fromEntries([...counts].map(([k, v]) => [k, v.objects.size]));
}

function Describe(item) {
  const box = new THREE.Box3().setFromObject(item.object);
  const size = box.getSize(new THREE.Vector3());
  const unit = loaded.facts.metersPerUnit || 1;
  // Width × depth × height, height along the scene's up axis.
  const [w, d, h] = loaded.facts.upAxis === 'Z' ? [size.x, size.y, size.z] : [size.x, size.z, size.y];
  // How sure the class is: its share of the views' votes.
  const sure = typeof item.confidence === 'number' ? `\nconfidence ${item.confidence.toFixed(2)}` : '';
  return `${item.label}${item.instanceId !== null ? `  #${item.instanceId}` : ''}\n${item.path}\n` +
         `size ${(w * unit).toFixed(2)} × ${(d * unit).toFixed(2)} × ${(h * unit).toFixed(2)} m${sure}`;
}

function SetupPicking() {
  const raycaster = new THREE.Raycaster();
  raycaster.params.Points.threshold = 0.05;
  const info = document.getElementById('info');
  const pick = (event) => {
    const rect = renderer.domElement.getBoundingClientRect();
    const ndc = new THREE.Vector2(((event.clientX - rect.left) / rect.width) * 2 - 1,
                                  -((event.clientY - rect.top) / rect.height) * 2 + 1);
    raycaster.setFromCamera(ndc, camera);
    const hits = raycaster.intersectObjects(Viewer.items.filter((i) => i.object.visible)
                                                .map((i) => i.object), false);
    const hit = hits.find((h) => h.object.userData.item || h.object.userData.prim?.item);
    if (!hit) return;
    const item = hit.object.userData.item || hit.object.userData.prim.item;
    info.textContent = Describe(item);
  };
  renderer.domElement.addEventListener('pointermove', pick);
  renderer.domElement.addEventListener('click', pick);
}

function SetupTimeline() {
  const range = loaded.timeRange;
  if (!(range.end > range.start) || !Viewer.items.some((i) => i.person) && !loaded.animations) return;
  document.getElementById('timeline').hidden = false;
  const slider = document.getElementById('time');
  slider.min = range.start;
  slider.max = range.end;
  const label = document.getElementById('timeLabel');
  const setTime = (t) => {
    Viewer.time = t;
    slider.value = t;
    loaded.setTime(t);
    label.textContent = `frame ${t}`;
    ApplyVisibility();
    Render();
  };
  slider.oninput = () => setTime(Number(slider.value));
  let timer = null;
  document.getElementById('play').onclick = (e) => {
    if (timer) {
      clearInterval(timer);
      timer = null;
      e.target.textContent = '▶';
      return;
    }
    e.target.textContent = '❚❚';
    timer = setInterval(() => {
      const next = Viewer.time + 1 > range.end ? range.start : Viewer.time + 1;
      setTime(next);
    }, 1000 / (range.fps || 10));
  };
  setTime(range.start);
}

async function Load() {
  const config = await (await fetch('/config.json')).json();
  document.getElementById('title').textContent = config.scene;
  document.title = `semrec: ${config.scene}`;
  loaded = config.kind === 'glb' ? await LoadGlb(config, root) : await LoadUsd(config, root);
  Viewer.items = loaded.items;
  Resize();
  window.addEventListener('resize', () => { Resize(); Render(); });
  const legend = BuildLegend();
  document.getElementById('classColors').onchange = (e) => {
    Viewer.classColors = e.target.checked;
    for (const item of Viewer.items) {
      if (item.prim) Viewer.applyColor(item.prim);
      else if (item.object.material) {
        item.object.material.color = Viewer.classColors ? ClassColor(item.label) : new THREE.Color(1, 1, 1);
      }
    }
    Render();
  };
  for (const id of ['structure', 'ceiling']) {
    document.getElementById(id).onchange = () => { ApplyVisibility(); Render(); };
  }
  ApplyVisibility();
  FrameCamera('iso');
  SetupPicking();
  SetupTimeline();
  Render();
  const objects = Viewer.items.filter((i) => !i.person);
  const people = Viewer.items.filter((i) => i.person);
  document.getElementById('status').textContent =
      `${objects.length} objects, ${people.length} people · up axis ${loaded.facts.upAxis}` +
      (config.kind === 'usd' ? ' · read by OpenUSD' : ' · glTF');
  return {
    ok: true,
    error: '',
    reader: config.kind === 'usd' ? 'OpenUSD (WASM)' : 'three.js GLTFLoader',
    scene: config.scene,
    upAxis: loaded.facts.upAxis,
    metersPerUnit: loaded.facts.metersPerUnit,
    timeRange: loaded.timeRange,
    animations: loaded.animations ?? 0,
    classes: legend,
    classColors: Object.fromEntries(Object.keys(legend).map((c) => [c, `#${ClassColor(c).getHexString()}`])),
    unsupported: loaded.unsupported,
    objects: objects.map((i) => ({
      path: i.path, name: i.name, class: i.label, instanceId: i.instanceId, structure: i.structure,
      confidence: i.confidence,
      vertices: i.object.geometry.getAttribute('position')?.count ?? 0,
      triangles: i.object.geometry.index ? i.object.geometry.index.count / 3 : 0,
      vertexColors: !!i.object.geometry.getAttribute('color'),
    })),
    people: people.map((i) => ({
      path: i.path, name: i.name, class: i.label, trackId: i.instanceId,
      points: i.object.geometry.getAttribute('position')?.count ?? 0,
      visibilitySamples: i.visibility.length,
    })),
  };
}

window.semrecLoaded = Load().catch((e) => {
  const status = document.getElementById('status');
  status.className = 'error';
  status.textContent = `Could not load the scene: ${e.message ?? e}`;
  return { ok: false, error: String(e.message ?? e), objects: [], people: [] };
});

// Headless: frames the camera, sets the time, renders, and reports where things landed.
window.semrecSetView = async ({ camera: view = 'iso', time = null, classColors = false,
                                panel = true } = {}) => {
  await window.semrecLoaded;
  // Who is shown at every frame (up to 1000), for checks against the writer.
  const visibleByFrame = [];
  const range = loaded.timeRange;
  if (Viewer.items.some((i) => i.person) && range.end > range.start) {
    for (let t = Math.ceil(range.start); t <= range.end + 1e-6 && visibleByFrame.length < 1000; t++) {
      Viewer.time = t;
      loaded.setTime(t);
      ApplyVisibility();
      root.updateMatrixWorld(true);
      visibleByFrame.push(Viewer.items.filter((i) => i.person && Shown(i)).map((i) => i.name));
    }
    Viewer.time = range.start;
    loaded.setTime(range.start);
  }
  document.getElementById('panel').hidden = !panel;
  container.style.right = panel ? '' : '0';
  Resize();
  if (classColors !== Viewer.classColors) {
    const box = document.getElementById('classColors');
    box.checked = classColors;
    box.onchange({ target: box });
  }
  if (time !== null && loaded.timeRange.end >= loaded.timeRange.start) {
    Viewer.time = Math.min(Math.max(time, loaded.timeRange.start), loaded.timeRange.end);
    loaded.setTime(Viewer.time);
    document.getElementById('time').value = Viewer.time;
    document.getElementById('timeLabel').textContent = `frame ${Viewer.time}`;
  }
  ApplyVisibility();
  FrameCamera(view);
  Render();
  await new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r)));
  const centerOf = (items) => {
    const box = new THREE.Box3();
    for (const i of items) box.expandByObject(i.object);
    return box.isEmpty() ? null : ScreenPoint(box.getCenter(new THREE.Vector3()));
  };
  // Click on each object in the picture (real click events, as a user would: at up to 16 of its
  // vertices, until the info box names it; others may hide it) and record what the box says.
  const clicks = [];
  const rect = renderer.domElement.getBoundingClientRect();
  for (const item of Viewer.items.filter((i) => !i.structure && !i.person && Shown(i))) {
    const positions = item.object.geometry.getAttribute('position');
    if (!positions || positions.count === 0) continue;
    let info = '';
    let tries = 0;
    for (let k = 0; k < 16; k++) {
      const v = new THREE.Vector3().fromBufferAttribute(
          positions, Math.floor((k + 0.5) * positions.count / 16) % positions.count);
      const p = ScreenPoint(v.applyMatrix4(item.object.matrixWorld));
      if (p.x < 0 || p.y < 0 || p.x >= rect.width || p.y >= rect.height) continue;
      tries++;
      document.getElementById('info').textContent = '';
      renderer.domElement.dispatchEvent(new MouseEvent('click', {
        clientX: rect.left + p.x, clientY: rect.top + p.y, bubbles: true,
      }));
      info = document.getElementById('info').textContent;
      if (info.includes(item.path)) break;
    }
    clicks.push({ path: item.path, info, tries });
  }
  return {
    visibleByFrame,
    clicks,
    camera: view,
    time: Viewer.time,
    width: renderer.domElement.width,
    height: renderer.domElement.height,
    floorScreen: centerOf(Viewer.items.filter((i) => i.label === 'floor')),
    ceilingScreen: centerOf(Viewer.items.filter((i) => i.label === 'ceiling')),
    objectsScreen: centerOf(Viewer.items.filter((i) => !i.structure && !i.person)),
    visiblePeople: Viewer.items.filter((i) => i.person && Shown(i)).map((i) => i.name),
  };
};
