// End-to-end test of the playground in the viewer: synthesises a pose clip, runs
// `dynahand play SCENE POSES --serve`, loads the page in headless Chromium and checks that
// the scene arrives and is drawn (the virtual hand's skin-coloured pixels), that it moves
// (the frame counter advances, the canvas changes) and that the scene layer's toggle hides
// it. Saves play.png. Exits 77 (CTest: skipped) when playwright-core, Chromium or the page
// is missing.
//
//   node web/test/play_test.mjs --dynahand build/release/apps/dynahand \
//        --scene examples/scenes/lever.json --out /tmp/play
import { spawnSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { decodePng, countHandPixels } from './png.mjs';
import { arg, chromiumOrSkip, fail, openBrowser, outDir, skip, startDynahand, waitForScene } from './harness.mjs';

const chromium = chromiumOrSkip();
const dynahand = arg('--dynahand');
const sceneFile = arg('--scene');
if (!dynahand || !sceneFile) fail('--dynahand PATH and --scene FILE are required');
const out = outDir('dynahand-play-');

// The hand's poses: a synthetic clip's ground truth (no tracking needed to test the page).
const clipDir = path.join(out, 'clip');
fs.rmSync(clipDir, { recursive: true, force: true });
const synth = spawnSync(dynahand, ['synth', '--motion', 'push-forward', '--frames', '60',
  '--out', clipDir], { encoding: 'utf8' });
if (synth.status !== 0) fail(`dynahand synth failed: ${synth.stderr}`);
const poses = path.join(clipDir, 'poses.jsonl');
if (!fs.existsSync(poses)) fail(`dynahand synth wrote no ${poses}`);

const { proc, address } = startDynahand(
  dynahand, ['play', sceneFile, poses, '--serve', '--port', '0', '--loop']);
let context;
try {
  const url = await address;
  if (!url) skip('this build has no viewer page (web/node_modules was missing at build time)');
  let page, errors;
  ({ context, page, errors } = await openBrowser(chromium, { width: 960, height: 600 }));
  await page.goto(url);
  await waitForScene(page);
  const counter = async () => Number(await page.textContent('#frame-count'));
  const firstCount = await counter();
  const firstShot = await page.screenshot();
  await page.waitForTimeout(1500);
  const shotPath = path.join(out, 'play.png');
  const shot = await page.screenshot({ path: shotPath });
  const secondCount = await counter();
  if (!(secondCount > firstCount)) fail(`frame counter did not advance (${firstCount} -> ${secondCount})`);
  if (Buffer.compare(firstShot, shot) === 0) fail('the canvas did not change over 1.5 s');
  // The hand must show in the canvas; on a loaded machine a screenshot can land on a frame
  // drawn before the scene's hand was posed, so up to ten more are taken, 300 ms apart.
  let handPixels = countHandPixels(decodePng(shot));
  let tries = 1;
  for (; handPixels < 300 && tries <= 10; ++tries) {
    await page.waitForTimeout(300);
    handPixels = countHandPixels(decodePng(await page.screenshot({ path: shotPath })));
  }
  console.log(`scene poses ${firstCount} -> ${secondCount} in 1.5 s; ${handPixels} hand-coloured ` +
              `pixels in ${shotPath} (screenshot ${tries})`);
  if (handPixels < 300) {
    fail(`only ${handPixels} hand-coloured pixels in ${tries} screenshots: ` +
         'the virtual hand is not drawn');
  }

  await page.uncheck('#layer-scene');
  await page.waitForTimeout(300);
  const hidden = countHandPixels(decodePng(await page.screenshot()));
  if (hidden > handPixels / 10) fail(`${hidden} hand-coloured pixels remain without the scene layer`);
  if (errors.length) fail(`page errors: ${errors.join('; ')}`);
  console.log('play test passed');
} finally {
  if (context) await context.close();
  proc.kill('SIGINT');
}
