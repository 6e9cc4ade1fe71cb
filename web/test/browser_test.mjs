// End-to-end test of the viewer: starts `dynahand serve` on a synthetic clip, loads its page
// in headless Debian Chromium driven by playwright-core, and checks that frames arrive (the
// frame counter advances), that the hand mesh is drawn (the canvas changes; a screenshot has
// hand-coloured pixels, which vanish when the model layer is switched off), and that pause
// and step work. Exits 77 (CTest: skipped) when playwright-core, Chromium or the page is
// missing.
//
//   node web/test/browser_test.mjs --dynahand build/release/apps/dynahand --out /tmp/viewer
import fs from 'node:fs';
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
let context;
try {
  const url = await address;
  if (!url) skip('this build has no viewer page (web/node_modules was missing at build time)');
  let page, errors;
  ({ context, page, errors } = await openBrowser(chromium, { width: 1280, height: 720 }));
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
