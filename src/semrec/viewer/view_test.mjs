// End-to-end test of `semrec view` and `--glb`: scenes written by semrec are opened by Pixar's
// OpenUSD (WASM) and by three's GLTFLoader in headless Chromium, and what they read is checked
// against what semrec wrote (our own reader via `semrec query`, report.json).
//   node view_test.mjs <semrec binary>
// Exit 0 pass, 1 fail, 77 skipped (a failure under SEMREC_REQUIRE_ALL=1).
import { spawnSync } from 'node:child_process';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import zlib from 'node:zlib';

const semrec = path.resolve(process.argv[2]);
const tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'semrec-view-test-'));
let failures = 0;

function Check(ok, what) {
  if (!ok) {
    failures++;
    console.log(`FAIL: ${what}`);
  }
}

function Skip(why) {
  if (process.env.SEMREC_REQUIRE_ALL === '1') {
    console.log(`FAIL: ${why} [a skip is a failure under SEMREC_REQUIRE_ALL=1]`);
    process.exit(1);
  }
  console.log(`SKIP: ${why}`);
  process.exit(77);
}

function Run(args, expectCode = 0) {
  const r = spawnSync(semrec, args, { encoding: 'utf8', cwd: tmp });
  if (r.status !== expectCode) {
    console.log(`FAIL: semrec ${args.join(' ')}: exit ${r.status}, expected ${expectCode}\n` +
                `${r.stdout}\n${r.stderr}`);
    process.exit(1);
  }
  return r;
}

// What the viewer read, at a time, from a camera; optionally with a screenshot.
function Probe(scene, { time = 0, camera = 'front', screenshot = '' } = {}) {
  const out = path.join(tmp, `probe-${path.basename(path.dirname(scene))}-${path.basename(scene)}-${time}.json`);
  const args = ['view', scene, '--probe', out, '--time', String(time), '--camera', camera,
                '--size', '960x600'];
  if (screenshot) args.push('--screenshot', screenshot);
  Run(args);
  return JSON.parse(fs.readFileSync(out, 'utf8'));
}

// Decodes an 8-bit RGB/RGBA, non-interlaced PNG (what Chromium writes): {width, height, rgb}.
function ReadPng(file) {
  const data = fs.readFileSync(file);
  let pos = 8;
  let width = 0, height = 0, channels = 0;
  const idat = [];
  while (pos < data.length) {
    const len = data.readUInt32BE(pos);
    const type = data.toString('ascii', pos + 4, pos + 8);
    const body = data.subarray(pos + 8, pos + 8 + len);
    if (type === 'IHDR') {
      width = body.readUInt32BE(0);
      height = body.readUInt32BE(4);
      if (body[8] !== 8 || body[12] !== 0) throw new Error(`${file}: not an 8-bit plain PNG`);
      channels = { 2: 3, 6: 4 }[body[9]];
      if (!channels) throw new Error(`${file}: colour type ${body[9]} unsupported`);
    } else if (type === 'IDAT') {
      idat.push(body);
    }
    pos += 12 + len;
  }
  const raw = zlib.inflateSync(Buffer.concat(idat));
  const stride = width * channels;
  const px = Buffer.alloc(height * stride);
  for (let y = 0; y < height; y++) {
    const filter = raw[y * (stride + 1)];
    for (let x = 0; x < stride; x++) {
      const v = raw[y * (stride + 1) + 1 + x];
      const a = x >= channels ? px[y * stride + x - channels] : 0;
      const b = y > 0 ? px[(y - 1) * stride + x] : 0;
      const c = x >= channels && y > 0 ? px[(y - 1) * stride + x - channels] : 0;
      let pred = 0;
      if (filter === 1) pred = a;
      else if (filter === 2) pred = b;
      else if (filter === 3) pred = (a + b) >> 1;
      else if (filter === 4) {
        const p = a + b - c;
        const pa = Math.abs(p - a), pb = Math.abs(p - b), pc = Math.abs(p - c);
        pred = pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
      }
      px[y * stride + x] = (v + pred) & 255;
    }
  }
  return { width, height, channels, px };
}

// Variance of the grey level over the 3D view (left of the 260-pixel side panel).
function ViewVariance(png) {
  let n = 0, sum = 0, sum2 = 0;
  for (let y = 0; y < png.height; y++) {
    for (let x = 0; x < png.width - 260; x++) {
      const i = (y * png.width + x) * png.channels;
      const g = (png.px[i] + png.px[i + 1] + png.px[i + 2]) / 3;
      n++;
      sum += g;
      sum2 += g * g;
    }
  }
  const mean = sum / n;
  return sum2 / n - mean * mean;
}

// ---------------------------------------------------------------------------------------------
const probe = spawnSync(semrec, ['view', '/nonexistent.usda'], { encoding: 'utf8' });
if (!/no such file/.test(probe.stderr)) {
  console.log(`FAIL: view of a missing file: ${probe.stderr}`);
  process.exit(1);
}
const chromium = ['/usr/bin/chromium', '/usr/bin/chromium-browser'].some((c) => fs.existsSync(c));
if (!chromium) Skip('Chromium missing: run scripts/setup');
const modules = process.env.SEMREC_NODE_MODULES ||
                path.join(process.env.SEMREC_SOURCE_DIR || '.', '.deps/node/node_modules');
if (!fs.existsSync(path.join(modules, 'three-usdz-loader/package.json'))) {
  Skip(`npm three-usdz-loader missing in ${modules}: run scripts/setup`);
}

// Scenes: six objects (layered .usda and .usdz), people with time samples (+ .glb).
Run(['synth', '--preset', 'six-objects', '--frames', '6', '--width', '320', '--height', '240',
     '--out', 'six-syn']);
Run(['mesh', 'six-syn', '--out', 'six', '--usdz', '--glb']);
Run(['synth', '--preset', 'people', '--frames', '12', '--width', '320', '--height', '240',
     '--out', 'people-syn']);
Run(['mesh', 'people-syn', '--people', 'people-syn/person', '--out', 'people', '--usdz', '--glb']);

const timelines = {};
for (const dir of ['six', 'people']) {
  const ours = JSON.parse(Run(['query', `${dir}/scene.usda`, '--json']).stdout);
  const report = JSON.parse(fs.readFileSync(path.join(tmp, dir, 'report.json'), 'utf8'));
  const ourClasses = ours.map((o) => o.class).sort();
  for (const file of ['scene.usda', 'scene.usdz', 'scene.glb']) {
    const scene = path.join(tmp, dir, file);
    const shot = path.join(tmp, `${dir}-${file}.png`);
    const r = Probe(scene, { time: 6, screenshot: file === 'scene.usda' ? shot : '' });
    const what = `${dir}/${file}`;
    Check(r.ok, `${what}: not loaded: ${r.error}`);
    Check(r.reader === (file === 'scene.glb' ? 'three.js GLTFLoader' : 'OpenUSD (WASM)'),
          `${what}: read by ${r.reader}`);
    Check(r.objects.length === ours.length,
          `${what}: ${r.objects.length} objects read, semrec wrote ${ours.length}`);
    Check(JSON.stringify(r.objects.map((o) => o.class).sort()) === JSON.stringify(ourClasses),
          `${what}: classes ${r.objects.map((o) => o.class)} vs ${ourClasses}`);
    Check(r.objects.every((o) => o.vertices > 0 && o.triangles > 0), `${what}: an empty mesh`);
    const ids = new Set(ours.map((o) => o.id));
    Check(r.objects.every((o) => ids.has(o.instanceId)), `${what}: instance ids differ`);
    const confidence = new Map(ours.map((o) => [o.id, o.confidence]));
    Check(r.objects.every((o) => typeof o.confidence === 'number' &&
                                 Math.abs(o.confidence - confidence.get(o.instanceId)) < 1e-4),
          `${what}: confidences ${JSON.stringify(r.objects.map((o) => o.confidence))} vs ` +
          `${JSON.stringify(ours.map((o) => o.confidence))}`);
    Check(r.people.length === report.people,
          `${what}: ${r.people.length} people read, semrec wrote ${report.people}`);
    Check(r.people.every((p) => p.points > 0), `${what}: a person without points`);
    Check(r.upAxis === (file === 'scene.glb' ? 'Y' : 'Z'), `${what}: up axis ${r.upAxis}`);
    if (dir === 'people') {
      Check(r.timeRange.end - r.timeRange.start === 11 || file === 'scene.glb' &&
            Math.abs(r.timeRange.end - 11) < 1e-3, `${what}: time range ${JSON.stringify(r.timeRange)}`);
      Check(r.view.visiblePeople.length > 0, `${what}: nobody visible at frame 6`);
      timelines[file] = r.view.visibleByFrame;
      // The picture at --time 6 shows whom the timeline says (after the sweep over all frames).
      Check(JSON.stringify(r.view.visiblePeople) === JSON.stringify(r.view.visibleByFrame[6]),
            `${what}: at frame 6 the picture shows ${r.view.visiblePeople}, the timeline ` +
            `${r.view.visibleByFrame[6]}`);
    }
    // Upright in the picture: the floor below the objects and the ceiling (pixel rows grow down).
    Check(r.view.floorScreen && r.view.objectsScreen &&
          r.view.floorScreen.y > r.view.objectsScreen.y,
          `${what}: floor not below the objects: ${JSON.stringify(r.view)}`);
    if (r.view.ceilingScreen) {
      Check(r.view.floorScreen.y > r.view.ceilingScreen.y, `${what}: floor above the ceiling`);
    }
    // Clicking on an object shows its class, id, path and size (a person may hide the plant).
    const hits = r.view.clicks.filter((c) => c.info.includes(c.path));
    Check(r.view.clicks.every((c) => /\S+.*\n.*\nsize [0-9.]+ × [0-9.]+ × [0-9.]+ m/.test(c.info)),
          `${what}: a click without class, path and size: ${JSON.stringify(r.view.clicks)}`);
    if (dir === 'six') {
      // (sofa_7 of six frames is a sliver inside the floor's thickness: the floor answers.)
      Check(hits.length >= r.view.clicks.length - 1 && hits.length >= 3,
            `${what}: clicks on objects show other objects: ${JSON.stringify(r.view.clicks)}`);
    }
    if (file === 'scene.usda') {
      const png = ReadPng(shot);
      Check(png.width === 960 && png.height === 600, `${what}: screenshot ${png.width}x${png.height}`);
      const variance = ViewVariance(png);
      Check(variance > 50, `${what}: the screenshot looks blank (grey variance ${variance.toFixed(1)})`);
    }
    console.log(`${what}: ${r.objects.length} objects, ${r.people.length} people, ` +
                `visible at 6: ${(r.view.visiblePeople || []).join(' ')}`);
  }
}

// Who is in view agrees between OpenUSD (time-sampled visibility) and glTF (STEP scale) at
// every frame, matches the people's observations, and someone is out of view somewhere.
Check(JSON.stringify(timelines['scene.usda']) === JSON.stringify(timelines['scene.glb']) &&
      JSON.stringify(timelines['scene.usdz']) === JSON.stringify(timelines['scene.glb']),
      `visibility per frame: OpenUSD ${JSON.stringify(timelines['scene.usda'])}, ` +
      `glTF ${JSON.stringify(timelines['scene.glb'])}`);
const counts = timelines['scene.usda'].map((names) => names.length);
console.log(`people visible per frame: ${counts.join(' ')}`);
Check(counts.length === 12 && Math.min(...counts) < Math.max(...counts) && Math.max(...counts) > 0,
      'the synthetic people should enter or leave the view');

// A malformed scene: a clear error from OpenUSD, exit 1; bad options: exit 2.
fs.writeFileSync(path.join(tmp, 'broken.usda'), '#usda 1.0\ndef Mesh "m" { point3f[] points = [(0, 0');
const broken = Run(['view', 'broken.usda', '--probe', 'b.json'], 1);
Check(/broken\.usda: OpenUSD cannot read it/.test(broken.stderr) && /syntax error/.test(broken.stderr),
      `broken scene message: ${broken.stderr}`);
fs.writeFileSync(path.join(tmp, 'not-usd.usda'), 'hello');
const notUsd = Run(['view', 'not-usd.usda', '--probe', 'n.json'], 1);
Check(/not-usd\.usda/.test(notUsd.stderr), `non-USD message: ${notUsd.stderr}`);
Check(/no scene\.usda/.test(Run(['view', 'six-syn'], 1).stderr), 'folder without a scene');
Check(/camera must be/.test(Run(['view', 'six', '--camera', 'up', '--probe', 'x.json'], 2).stderr),
      'bad --camera');

fs.rmSync(tmp, { recursive: true, force: true });
if (failures) process.exit(1);
console.log('PASS');
