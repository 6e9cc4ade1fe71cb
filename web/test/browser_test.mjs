// End-to-end test of the viewer: starts `dynahand serve` on a synthetic clip, loads its page
// in headless Debian Chromium driven by playwright-core, and checks that frames arrive (the
// frame counter advances), that the hand mesh is drawn (the canvas changes; a screenshot has
// hand-coloured pixels, which vanish when the model layer is switched off), and that pause
// and step work. Exits 77 (CTest: skipped) when playwright-core, Chromium or the page is
// missing.
//
//   node web/test/browser_test.mjs --dynahand build/release/apps/dynahand --out /tmp/viewer
import { spawn } from 'node:child_process';
import { createRequire } from 'node:module';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { decodePng, countHandPixels } from './png.mjs';

const SKIP = 77;
const CHROMIUM = '/usr/bin/chromium';
// Chromium as the machine allows it: no GPU, no network beyond localhost, a fresh profile.
const CHROMIUM_ARGS = [
  '--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
  '--disable-background-networking', '--disable-component-update', '--disable-sync',
  '--enable-unsafe-swiftshader', '--use-angle=swiftshader',
];

function arg(name, fallback) {
  const i = process.argv.indexOf(name);
  return i > 0 && i + 1 < process.argv.length ? process.argv[i + 1] : fallback;
}
const dynahand = arg('--dynahand');
const outDir = arg('--out', fs.mkdtempSync(path.join(os.tmpdir(), 'dynahand-viewer-')));
const clip = arg('--clip', 'wave');
const screenshotPath = arg('--screenshot', path.join(outDir, 'viewer.png'));

function skip(why) {
  console.log(`SKIPPED: ${why}`);
  process.exit(SKIP);
}
function fail(why) {
  console.error(`FAILED: ${why}`);
  process.exitCode = 1;
  throw new Error(why);
}

let chromium;
try {
  const require = createRequire(new URL('../package.json', import.meta.url));
  ({ chromium } = require('playwright-core'));
} catch {
  skip('playwright-core is not installed (run scripts/install-deps.sh: npm ci in web/)');
}
if (!fs.existsSync(CHROMIUM)) skip(`${CHROMIUM} is missing (run scripts/install-deps.sh)`);
if (!dynahand) fail('--dynahand PATH is required');
fs.mkdirSync(outDir, { recursive: true });

// Starts the server and resolves with its page address once it prints it.
function startServer() {
  const server = spawn(dynahand, ['serve', `synth:${clip}`, '--port', '0', '--init', 'gt'], {
    stdio: ['ignore', 'pipe', 'inherit'],
  });
  const address = new Promise((resolve, reject) => {
    let out = '';
    server.stdout.on('data', (chunk) => {
      out += chunk;
      const page = out.match(/viewer at (http:\/\/\S+)/);
      if (page) resolve(page[1]);
      else if (out.includes('viewer page unavailable')) resolve(null);
    });
    server.on('exit', (code) => reject(new Error(`dynahand serve exited with ${code}: ${out}`)));
  });
  return { server, address };
}

const { server, address } = startServer();
let context;
try {
  const url = await address;
  if (!url) skip('this build has no viewer page (web/node_modules was missing at build time)');
  const profile = fs.mkdtempSync(path.join(os.tmpdir(), 'dynahand-chromium-'));
  context = await chromium.launchPersistentContext(profile, {
    executablePath: CHROMIUM, headless: true, args: CHROMIUM_ARGS,
    viewport: { width: 1280, height: 720 },
  });
  const page = context.pages()[0] || (await context.newPage());
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  await page.goto(url);

  // Frames arrive and the tracked hand is shown.
  await page.waitForFunction(
    () => window.dynahandViewer && window.dynahandViewer.framesDrawn >= 5 &&
          window.dynahandViewer.handVisible, null, { timeout: 60000 });
  const counter = async () => Number(await page.textContent('#frame-count'));
  const firstCount = await counter();
  const firstShot = await page.screenshot();
  await page.waitForTimeout(1500);
  const secondCount = await counter();
  if (!(secondCount > firstCount)) fail(`frame counter did not advance (${firstCount} -> ${secondCount})`);
  const shot = await page.screenshot({ path: screenshotPath });
  if (Buffer.compare(firstShot, shot) === 0) fail('the canvas did not change over 1.5 s');
  console.log(`frames received ${firstCount} -> ${secondCount} in 1.5 s`);

  // The saved screenshot: a real picture with the hand's colour in it.
  const image = decodePng(fs.readFileSync(screenshotPath));
  if (image.width !== 1280 || image.height !== 720) fail(`screenshot is ${image.width}x${image.height}`);
  const handPixels = countHandPixels(image);
  console.log(`screenshot ${screenshotPath}: ${handPixels} hand-coloured pixels`);
  if (handPixels < 1000) fail(`only ${handPixels} hand-coloured pixels in the screenshot`);
  const bars = await page.locator('#errors .bar').count();
  if (bars < 1) fail('no simulation error bars');

  // Those pixels are the hand model: switching its layer off removes them.
  await page.uncheck('#layer-model');
  await page.waitForTimeout(300);
  const withoutModel = countHandPixels(decodePng(await page.screenshot()));
  console.log(`without the model layer: ${withoutModel} hand-coloured pixels`);
  if (withoutModel > handPixels / 10) fail('hand-coloured pixels remain without the model layer');
  await page.check('#layer-model');

  // Pause stops the stream; step tracks exactly one more frame. Frames already sent when
  // the pause arrived still come in (software rendering makes the page slow to read them),
  // so first wait for the counter to settle.
  await page.click('#pause');
  let pausedAt = await counter();
  for (let settled = 0, tries = 0; settled < 3 && tries < 40; ++tries) {
    await page.waitForTimeout(500);
    const now = await counter();
    settled = now === pausedAt ? settled + 1 : 0;
    pausedAt = now;
  }
  await page.waitForTimeout(1000);
  if ((await counter()) !== pausedAt) fail('frames kept coming while paused');
  await page.click('#step');
  await page.waitForFunction((n) => Number(document.querySelector('#frame-count').textContent) === n + 1,
    pausedAt, { timeout: 10000 });
  await page.click('#pause');  // resume
  await page.waitForFunction((n) => Number(document.querySelector('#frame-count').textContent) > n + 3,
    pausedAt, { timeout: 10000 });
  console.log('pause, step and resume work');

  if (errors.length) fail(`page errors: ${errors.join('; ')}`);
  console.log('browser test passed');
} finally {
  if (context) await context.close();
  server.kill('SIGINT');
}
