// semrec's scene viewer host: a static server for the viewer page (cross-origin isolated, as the
// pthreads build of OpenUSD-WASM needs) and, headless, a Chromium driver over the DevTools
// protocol that waits for the page's result, sets time and camera, and takes a screenshot.
//
//   node view.mjs --modules DIR --scene FILE [--port P]
//       [--screenshot OUT.png] [--time T] [--camera iso|top|front|side] [--size WxH]
//       [--panel on|off] [--class-colors on|off]
//       [--probe OUT.json] [--timeout-s S] [--chromium PATH]
//
// --modules: the node_modules folder with three and three-usdz-loader (scripts/setup puts it in
// .deps/node/node_modules). --scene: a .usda/.usd/.usdz (OpenUSD reads it) or a .glb (three's
// GLTFLoader reads it). Without --screenshot/--probe it serves until interrupted and prints the
// URL. Exit codes: 0 ok, 1 the scene or the browser failed (message on stderr), 2 bad arguments.
import fs from 'node:fs';
import http from 'node:http';
import os from 'node:os';
import path from 'node:path';
import { spawn } from 'node:child_process';
import { fileURLToPath } from 'node:url';

const kViewerDir = path.dirname(fileURLToPath(import.meta.url));

function Fail(code, message) {
  process.stderr.write(`semrec view: ${message}\n`);
  process.exit(code);
}

function ParseArgs(argv) {
  const args = { port: 0, time: null, camera: 'iso', size: '1280x800', timeoutS: 90, panel: 'on',
                 classColors: 'off' };
  const names = {
    '--modules': 'modules', '--scene': 'scene', '--port': 'port', '--screenshot': 'screenshot',
    '--time': 'time', '--camera': 'camera', '--size': 'size', '--probe': 'probe',
    '--timeout-s': 'timeoutS', '--chromium': 'chromium', '--panel': 'panel',
    '--class-colors': 'classColors',
  };
  for (let i = 0; i < argv.length; i += 2) {
    const key = names[argv[i]];
    if (!key || i + 1 >= argv.length) Fail(2, `unknown or incomplete argument '${argv[i]}'`);
    args[key] = argv[i + 1];
  }
  if (!args.modules || !args.scene) Fail(2, '--modules and --scene are required');
  args.port = Number(args.port);
  args.timeoutS = Number(args.timeoutS);
  if (args.time !== null) {
    args.time = Number(args.time);
    if (!Number.isFinite(args.time)) Fail(2, '--time must be a number (a time code)');
  }
  if (!['iso', 'top', 'front', 'side'].includes(args.camera)) {
    Fail(2, `--camera must be iso, top, front or side, not '${args.camera}'`);
  }
  for (const key of ['panel', 'classColors']) {
    if (!['on', 'off'].includes(args[key])) Fail(2, `--${key} takes on or off, not '${args[key]}'`);
  }
  const size = /^(\d+)x(\d+)$/.exec(args.size);
  if (!size || +size[1] < 64 || +size[2] < 64 || +size[1] > 4096 || +size[2] > 4096) {
    Fail(2, `--size must be WIDTHxHEIGHT within 64..4096, not '${args.size}'`);
  }
  args.width = +size[1];
  args.height = +size[2];
  return args;
}

const kTypes = {
  '.html': 'text/html; charset=utf-8', '.js': 'text/javascript', '.mjs': 'text/javascript',
  '.css': 'text/css', '.json': 'application/json', '.wasm': 'application/wasm',
  '.data': 'application/octet-stream', '.usda': 'application/octet-stream',
  '.usd': 'application/octet-stream', '.usdc': 'application/octet-stream',
  '.usdz': 'model/vnd.usdz+zip', '.glb': 'model/gltf-binary', '.png': 'image/png',
};
const kSceneExtensions = ['.usda', '.usd', '.usdc', '.usdz', '.glb'];

// Maps a URL path to a file under one of the served roots; null when outside them.
function Resolve(roots, urlPath) {
  for (const [prefix, dir] of roots) {
    if (!urlPath.startsWith(prefix)) continue;
    const rel = decodeURIComponent(urlPath.slice(prefix.length));
    const file = path.resolve(dir, rel);
    if (file !== dir && !file.startsWith(dir + path.sep)) return null;  // no ../ escapes
    return file;
  }
  return null;
}

function StartServer(args, sceneFile) {
  const sceneDir = path.dirname(sceneFile);
  // Every USD layer beside the root: a layered scene's sublayers must be in OpenUSD's file system
  // before the root is opened.
  const layers = fs.readdirSync(sceneDir)
      .filter((f) => kSceneExtensions.includes(path.extname(f).toLowerCase()) &&
                     path.extname(f).toLowerCase() !== '.glb')
      .filter((f) => f !== path.basename(sceneFile));
  const config = {
    scene: path.basename(sceneFile),
    kind: path.extname(sceneFile).toLowerCase() === '.glb' ? 'glb' : 'usd',
    layers,
  };
  const roots = [
    ['/three/', path.join(args.modules, 'three')],
    ['/usd/', path.join(args.modules, 'three-usdz-loader', 'external')],
    ['/scene/', sceneDir],
    ['/', kViewerDir],
  ];
  const server = http.createServer((req, res) => {
    const urlPath = new URL(req.url, 'http://localhost').pathname;
    const headers = {
      'Cross-Origin-Opener-Policy': 'same-origin',
      'Cross-Origin-Embedder-Policy': 'require-corp',
      'Cross-Origin-Resource-Policy': 'same-origin',
      'Cache-Control': 'no-store',
    };
    if (urlPath === '/config.json') {
      res.writeHead(200, { ...headers, 'Content-Type': 'application/json' });
      res.end(JSON.stringify(config));
      return;
    }
    const file = Resolve(roots, urlPath === '/' ? '/index.html' : urlPath);
    if (!file || path.extname(file) === '.mjs' || !fs.existsSync(file) ||
        !fs.statSync(file).isFile()) {
      res.writeHead(404, headers);
      res.end('not found');
      return;
    }
    res.writeHead(200, {
      ...headers,
      'Content-Type': kTypes[path.extname(file).toLowerCase()] || 'application/octet-stream',
    });
    fs.createReadStream(file).pipe(res);
  });
  return new Promise((resolve, reject) => {
    server.once('error', reject);
    server.listen(args.port, '127.0.0.1', () => resolve(server));
  });
}

function FindChromium(explicit) {
  const candidates = explicit ? [explicit] : ['/usr/bin/chromium', '/usr/bin/chromium-browser'];
  for (const c of candidates) if (fs.existsSync(c)) return c;
  Fail(1, `Chromium not found (${candidates.join(', ')}): run scripts/setup, or pass --chromium`);
}

// A minimal DevTools protocol client over Chromium's --remote-debugging-pipe (fd 3: commands to
// the browser, fd 4: its replies and events, each a JSON message ended by a NUL byte): no
// WebSocket needed, so any Node works.
class Cdp {
  constructor(toBrowser, fromBrowser) {
    this.next = 1;
    this.pending = new Map();
    this.console = [];
    this.session = undefined;
    this.toBrowser = toBrowser;
    let buffer = '';
    fromBrowser.setEncoding('utf8');
    fromBrowser.on('data', (chunk) => {
      buffer += chunk;
      for (let end; (end = buffer.indexOf('\0')) >= 0;) {
        const msg = JSON.parse(buffer.slice(0, end));
        buffer = buffer.slice(end + 1);
        this.dispatch(msg);
      }
    });
  }
  dispatch(msg) {
    if (msg.id && this.pending.has(msg.id)) {
      const { resolve, reject } = this.pending.get(msg.id);
      this.pending.delete(msg.id);
      if (msg.error) reject(new Error(msg.error.message));
      else resolve(msg.result);
    } else if (msg.method === 'Runtime.consoleAPICalled') {
      const text = msg.params.args.map((a) => a.value ?? a.description ?? '').join(' ');
      this.console.push(`${msg.params.type}: ${text}`);
    } else if (msg.method === 'Runtime.exceptionThrown') {
      const d = msg.params.exceptionDetails;
      this.console.push(`exception: ${d.exception?.description ?? d.text}`);
    }
  }
  // Browser-level without a session; page-level once attach() set one.
  send(method, params = {}, browserLevel = false) {
    const id = this.next++;
    const msg = { id, method, params };
    if (!browserLevel && this.session) msg.sessionId = this.session;
    this.toBrowser.write(JSON.stringify(msg) + '\0');
    return new Promise((resolve, reject) => this.pending.set(id, { resolve, reject }));
  }
  async attach() {
    const { targetId } = await this.send('Target.createTarget', { url: 'about:blank' }, true);
    const { sessionId } =
        await this.send('Target.attachToTarget', { targetId, flatten: true }, true);
    this.session = sessionId;
  }
  async evaluate(expression) {
    const r = await this.send('Runtime.evaluate',
                              { expression, awaitPromise: true, returnByValue: true });
    if (r.exceptionDetails) {
      throw new Error(r.exceptionDetails.exception?.description ?? r.exceptionDetails.text);
    }
    return r.result.value;
  }
}

async function WithTimeout(promise, seconds, what) {
  let timer;
  const timeout = new Promise((_, reject) => {
    timer = setTimeout(() => reject(new Error(`${what}: no answer after ${seconds} s`)),
                       seconds * 1000);
  });
  try {
    return await Promise.race([promise, timeout]);
  } finally {
    clearTimeout(timer);
  }
}

async function Headless(args, url) {
  const profile = fs.mkdtempSync(path.join(os.tmpdir(), 'semrec-view-'));
  const chrome = spawn(FindChromium(args.chromium), [
    '--headless=new', '--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
    '--disable-gpu-sandbox', '--no-first-run', '--disable-background-networking',
    '--disable-component-update', '--disable-sync', '--disable-quic', '--hide-scrollbars',
    `--user-data-dir=${profile}`, '--remote-debugging-pipe',
    `--window-size=${args.width},${args.height}`, 'about:blank',
  ], { stdio: ['ignore', 'ignore', 'pipe', 'pipe', 'pipe'], detached: true });
  let chromeLog = '';
  const exited = new Promise((resolve) => chrome.on('exit', resolve));
  const cleanup = async () => {
    try {
      process.kill(-chrome.pid, 'SIGKILL');  // the whole process group: renderers, GPU, zygote
    } catch {
      chrome.kill('SIGKILL');
    }
    await exited;
    try {
      fs.rmSync(profile, { recursive: true, force: true, maxRetries: 10, retryDelay: 100 });
    } catch (e) {
      process.stderr.write(`semrec view: warning: could not remove ${profile}: ${e.message}\n`);
    }
  };
  try {
    chrome.stderr.on('data', (d) => { chromeLog = (chromeLog + d).slice(-4000); });
    const failed = new Promise((_, reject) => chrome.on('exit', (code) => {
      reject(new Error(`Chromium exited (${code}): ${chromeLog.slice(-2000)}`));
    }));
    failed.catch(() => {});
    const cdp = new Cdp(chrome.stdio[3], chrome.stdio[4]);
    await WithTimeout(Promise.race([cdp.attach(), failed]), 60, 'starting Chromium');
    await cdp.send('Runtime.enable');
    await cdp.send('Page.enable');
    await cdp.send('Emulation.setDeviceMetricsOverride',
                   { width: args.width, height: args.height, deviceScaleFactor: 1, mobile: false });
    await cdp.send('Page.navigate', { url });
    // The page defines window.semrecLoaded (a promise of the result) once its module runs.
    const result = await WithTimeout((async () => {
      for (;;) {
        const ready = await cdp.evaluate('typeof window.semrecLoaded !== "undefined"');
        if (ready) break;
        await new Promise((r) => setTimeout(r, 100));
      }
      return cdp.evaluate('window.semrecLoaded');
    })(), args.timeoutS, 'loading the scene in Chromium');
    result.console = cdp.console;
    if (result.ok) {
      const view = { camera: args.camera, time: args.time, panel: args.panel === 'on',
                     classColors: args.classColors === 'on' };
      result.view = await cdp.evaluate(`window.semrecSetView(${JSON.stringify(view)})`);
    }
    if (result.ok && args.screenshot) {
      const shot = await cdp.send('Page.captureScreenshot', { format: 'png' });
      const tmp = `${args.screenshot}.tmp-${process.pid}`;
      fs.writeFileSync(tmp, Buffer.from(shot.data, 'base64'));
      fs.renameSync(tmp, args.screenshot);  // atomic: never a half-written PNG
    }
    return result;
  } finally {
    await cleanup();
  }
}

async function Main() {
  const args = ParseArgs(process.argv.slice(2));
  const sceneFile = path.resolve(args.scene);
  if (!fs.existsSync(sceneFile) || !fs.statSync(sceneFile).isFile()) {
    Fail(1, `${args.scene}: no such scene file`);
  }
  if (!kSceneExtensions.includes(path.extname(sceneFile).toLowerCase())) {
    Fail(1, `${args.scene}: not a scene (expected ${kSceneExtensions.join(', ')})`);
  }
  for (const pkg of ['three', 'three-usdz-loader']) {
    if (!fs.existsSync(path.join(args.modules, pkg, 'package.json'))) {
      Fail(1, `npm package ${pkg} not found in ${args.modules}: run scripts/setup`);
    }
  }
  const server = await StartServer(args, sceneFile).catch((e) => Fail(1, `cannot serve: ${e.message}`));
  const url = `http://127.0.0.1:${server.address().port}/`;
  if (!args.screenshot && !args.probe) {
    process.stdout.write(`semrec view: ${path.basename(sceneFile)} at ${url}  (Ctrl-C stops)\n`);
    return;
  }
  let result;
  try {
    result = await Headless(args, url);
  } catch (e) {
    server.close();
    Fail(1, `${args.scene}: ${e.message}`);
  }
  server.close();
  if (args.probe) {
    const tmp = `${args.probe}.tmp-${process.pid}`;
    fs.writeFileSync(tmp, JSON.stringify(result, null, 1));
    fs.renameSync(tmp, args.probe);
  }
  if (!result.ok) {
    // OpenUSD reports why it failed as "Runtime Error: in F at line N of S -- what" on the
    // console; its abort message is only a stack trace.
    const usdErrors = result.console.map((l) => /Runtime Error: .*? -- (.*)/.exec(l))
                          .filter(Boolean).map((m) => `  OpenUSD: ${m[1]}`);
    const first = result.error.split('\n')[0];
    const why = usdErrors.length ? 'OpenUSD cannot read it' : first;
    Fail(1, `${args.scene}: ${why}${usdErrors.length ? '\n' + usdErrors.slice(-5).join('\n') : ''}`);
  }
  const summary = `${result.objects.length} objects, ${result.people.length} people`;
  process.stdout.write(`semrec view: ${path.basename(sceneFile)}: ${summary}` +
                       (args.screenshot ? ` -> ${args.screenshot}` : '') + '\n');
  process.exit(0);
}

Main();
