// The viewer page showing a physics scene (what `dynahand play` streams: "scene" once, then
// "scene_poses"), fed by a minimal WebSocket server written here, in headless Chromium. Checks
// that the bodies are drawn where the poses put them (a magenta crate's pixels appear and move).
// Exits 77 (CTest: skipped) without playwright-core, Chromium or the built page.
//
//   node web/test/scene_test.mjs --page build/release/share/dynahand/viewer --out /tmp/scene
import crypto from 'node:crypto';
import fs from 'node:fs';
import http from 'node:http';
import path from 'node:path';
import { decodePng } from './png.mjs';
import { arg, chromiumOrSkip, fail, openBrowser, outDir, skip, waitForScene } from './harness.mjs';

const chromium = chromiumOrSkip();
const pageDir = arg('--page');
if (!pageDir || !fs.existsSync(path.join(pageDir, 'index.html'))) {
  skip(`no built viewer page in ${pageDir} (web/node_modules was missing at build time)`);
}
const out = outDir('dynahand-scene-');

// A box as the stream describes hulls: vertices and counter-clockwise faces.
function box(hx, hy, hz, withFaces) {
  const v = [];
  for (const z of [-hz, hz]) for (const y of [-hy, hy]) for (const x of [-hx, hx]) v.push([x, y, z]);
  const body = { vertices: v };
  if (withFaces) {
    body.faces = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
  }
  return body;
}
const scene = {
  type: 'scene', version: 1, up: 'z',
  bodies: [
    { name: 'floor', color: '#4a5a6a', ...box(0.3, 0.3, 0.01, true) },
    { name: 'crate', color: '#d040d0', ...box(0.04, 0.04, 0.04, false) },  // hull from vertices
  ],
};
function poses(step) {
  const x = -0.1 + 0.004 * (step % 50);
  return {
    type: 'scene_poses', version: 1, step, time: step / 60,
    poses: [{ p: [0, 0, -0.01], q: [1, 0, 0, 0] }, { p: [x, 0, 0.04], q: [1, 0, 0, 0] }],
  };
}

// Server-to-client frames are unmasked; text only.
function textFrame(text) {
  const payload = Buffer.from(text);
  const n = payload.length;
  const header = n < 126 ? Buffer.from([0x81, n])
    : n < 65536 ? Buffer.from([0x81, 126, n >> 8, n & 0xff])
      : Buffer.concat([Buffer.from([0x81, 127]), (() => { const b = Buffer.alloc(8); b.writeBigUInt64BE(BigInt(n)); return b; })()]);
  return Buffer.concat([header, payload]);
}
const types = { '.html': 'text/html', '.js': 'text/javascript', '.css': 'text/css' };
const server = http.createServer((req, res) => {
  const name = req.url === '/' ? 'index.html' : path.basename(req.url);
  const file = path.join(pageDir, name);
  if (!fs.existsSync(file)) {
    res.writeHead(404).end();
    return;
  }
  res.writeHead(200, { 'Content-Type': types[path.extname(name)] || 'application/octet-stream' });
  res.end(fs.readFileSync(file));
});
const timers = [];
server.on('upgrade', (req, socket) => {
  const accept = crypto.createHash('sha1')
    .update(req.headers['sec-websocket-key'] + '258EAFA5-E914-47DA-95CA-C5AB0DC85B11').digest('base64');
  socket.write('HTTP/1.1 101 Switching Protocols\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n' +
               `Sec-WebSocket-Accept: ${accept}\r\n\r\n`);
  socket.write(textFrame(JSON.stringify(scene)));
  let step = 0;
  const timer = setInterval(() => socket.write(textFrame(JSON.stringify(poses(step++)))), 50);
  timers.push(timer);
  socket.on('error', () => clearInterval(timer));
  socket.on('close', () => clearInterval(timer));
});
await new Promise((resolve) => server.listen(0, '127.0.0.1', resolve));
const url = `http://127.0.0.1:${server.address().port}/`;

// Pixels of the crate's colour (shaded magenta), and their mean column.
function crate(image) {
  let n = 0;
  let sumX = 0;
  for (let i = 0; i < image.width * image.height; ++i) {
    const o = i * image.channels;
    const [r, g, b] = [image.pixels[o], image.pixels[o + 1], image.pixels[o + 2]];
    if (r > 90 && b > 90 && r - g > 50 && b - g > 50) {
      ++n;
      sumX += i % image.width;
    }
  }
  return { n, x: n ? sumX / n : 0 };
}

let context;
try {
  let page, errors;
  ({ context, page, errors } = await openBrowser(chromium, { width: 960, height: 600 }));
  await page.goto(url);
  await waitForScene(page);
  const shotPath = path.join(out, 'scene.png');
  const first = crate(decodePng(await page.screenshot({ path: shotPath })));
  await page.waitForTimeout(800);
  const second = crate(decodePng(await page.screenshot()));
  console.log(`crate pixels ${first.n} at x ${first.x.toFixed(0)}, then ${second.n} at x ${second.x.toFixed(0)}`);
  if (first.n < 200) fail(`only ${first.n} crate-coloured pixels: the scene is not drawn`);
  if (Math.abs(second.x - first.x) < 2) fail('the crate did not move with its poses');
  await page.uncheck('#layer-scene');
  await page.waitForTimeout(300);
  if (crate(decodePng(await page.screenshot())).n > first.n / 10) fail('the scene toggle does not hide it');
  if (errors.length) fail(`page errors: ${errors.join('; ')}`);
  console.log('scene test passed');
} finally {
  if (context) await context.close();
  timers.forEach(clearInterval);
  server.close();
  server.closeAllConnections?.();
}
