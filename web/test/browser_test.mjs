// End-to-end test of the viewer: starts `dynahand serve` on a synthetic clip, loads its page
// in headless Debian Chromium driven by playwright-core, and checks that frames arrive (the
// frame counter advances), that the hand mesh is drawn (the canvas changes; a screenshot has
// hand-coloured pixels, which vanish when the model layer is switched off), and that pause
// and step work. Then that only the page's own origin (or the run's token) opens the
// WebSocket: a page of another site (http://evil.example.com, mapped to 127.0.0.1 inside this
// browser only, served by a second HTTP server here) is refused without the token and let in
// with it, and the viewer page opened at that other name connects only with the ?token= of
// its printed address. Exits 77 (CTest: skipped) when playwright-core, Chromium or the page is
// missing.
//
//   node web/test/browser_test.mjs --dynahand build/release/apps/dynahand --out /tmp/viewer
import fs from 'node:fs';
import http from 'node:http';
import path from 'node:path';
import { decodePng, countHandPixels } from './png.mjs';
import { arg, chromiumOrSkip, fail, openBrowser, outDir, skip, startDynahand } from './harness.mjs';

const chromium = chromiumOrSkip();
const dynahand = arg('--dynahand');
if (!dynahand) fail('--dynahand PATH is required');
const out = outDir('dynahand-viewer-');
const clip = arg('--clip', 'wave');
const screenshotPath = arg('--screenshot', path.join(out, 'viewer.png'));

const { proc: server, address } = startDynahand(
  dynahand, ['serve', `synth:${clip}`, '--port', '0', '--init', 'gt']);
// "Another site": this name is this machine, for this browser only.
const OTHER_SITE = 'evil.example.com';
let context, otherSite;
try {
  const printed = await address;
  if (!printed) skip('this build has no viewer page (web/node_modules was missing at build time)');
  const token = new URL(printed).searchParams.get('token');
  if (!/^[0-9a-f]{32}$/.test(token || '')) {
    fail(`no 128-bit token in the printed address ${printed}`);
  }
  const port = new URL(printed).port;
  // The page at its own origin, without the token: the origin alone lets it in.
  const url = `http://127.0.0.1:${port}/`;
  let page, errors;
  ({ context, page, errors } = await openBrowser(chromium, { width: 1280, height: 720 },
    [`--host-resolver-rules=MAP ${OTHER_SITE} 127.0.0.1`]));
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

  // A page of another site opens ws://127.0.0.1:PORT/: refused (the handshake's 403 shows in
  // the browser as a close with 1006 before any message); with the token it is let in.
  otherSite = http.createServer((req, res) => {
    res.writeHead(200, { 'Content-Type': 'text/html' })
      .end('<!doctype html><title>another site</title>');
  });
  await new Promise((resolve) => otherSite.listen(0, '127.0.0.1', resolve));
  const other = await context.newPage();
  await other.goto(`http://${OTHER_SITE}:${otherSite.address().port}/`);
  const open = (wsUrl) => other.evaluate((u) => new Promise((resolve) => {
    const ws = new WebSocket(u);
    ws.onmessage = (event) => {
      resolve(`message ${JSON.parse(event.data).type}`);
      ws.close();
    };
    ws.onclose = (event) => resolve(`closed ${event.code}`);
    setTimeout(() => resolve('no answer in 20 s'), 20000);
  }), wsUrl);
  const refused = await open(`ws://127.0.0.1:${port}/`);
  console.log(`another site's page without the token: ${refused}`);
  if (refused !== 'closed 1006') fail(`a page of another site opened the WebSocket: ${refused}`);
  const withToken = await open(`ws://127.0.0.1:${port}/?token=${token}`);
  console.log(`another site's page with the token: ${withToken}`);
  if (withToken !== 'message hello') {
    fail(`the token did not let another site's page in: ${withToken}`);
  }

  // The viewer page itself at an address that is not its own origin: no frames without the
  // token (and the status says why), frames with the token its printed address carries.
  const elsewhere = `http://${OTHER_SITE}:${port}/`;
  await other.goto(elsewhere);
  await other.waitForFunction(
    () => document.querySelector('#status').textContent.startsWith('cannot connect'), null,
    { timeout: 30000 });
  await other.waitForTimeout(2000);
  const received = await other.evaluate(() => window.dynahandViewer.framesReceived);
  console.log(`the page at ${elsewhere}: ${received} frames, status ` +
              `"${await other.textContent('#status')}"`);
  if (received !== 0) {
    fail(`the page at ${elsewhere} received ${received} frames without the token`);
  }
  await other.goto(`${elsewhere}?token=${token}`);
  await other.waitForFunction(() => window.dynahandViewer.framesReceived >= 3, null,
    { timeout: 60000 });
  console.log(`the page at ${elsewhere}?token=... receives frames`);
  if (errors.length) fail(`page errors: ${errors.join('; ')}`);
  console.log('browser test passed');
} finally {
  if (context) await context.close();
  if (otherSite) otherSite.close();
  server.kill('SIGINT');
}
