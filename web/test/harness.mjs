// What the page tests share: arguments, skip/fail conventions (exit 77 = CTest "skipped"),
// headless Debian Chromium through playwright-core, and starting a dynahand command that
// serves the page.
import { spawn } from 'node:child_process';
import { createRequire } from 'node:module';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';

export const SKIP = 77;
const CHROMIUM = '/usr/bin/chromium';
// Chromium as the machine allows it: no GPU, no network beyond localhost, a fresh profile.
const CHROMIUM_ARGS = [
  '--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
  '--disable-background-networking', '--disable-component-update', '--disable-sync',
  '--enable-unsafe-swiftshader', '--use-angle=swiftshader',
];

export function arg(name, fallback) {
  const i = process.argv.indexOf(name);
  return i > 0 && i + 1 < process.argv.length ? process.argv[i + 1] : fallback;
}
export function skip(why) {
  console.log(`SKIPPED: ${why}`);
  process.exit(SKIP);
}
export function fail(why) {
  console.error(`FAILED: ${why}`);
  process.exitCode = 1;
  throw new Error(why);
}
// A scratch folder: --out, or a fresh one under the system's temporary folder.
export function outDir(prefix) {
  const dir = arg('--out', fs.mkdtempSync(path.join(os.tmpdir(), prefix)));
  fs.mkdirSync(dir, { recursive: true });
  return dir;
}

// playwright-core's Chromium driver; skips the test when it or Chromium is missing.
export function chromiumOrSkip() {
  let chromium;
  try {
    ({ chromium } = createRequire(new URL('../package.json', import.meta.url))('playwright-core'));
  } catch {
    skip('playwright-core is not installed (run scripts/install-deps.sh: npm ci in web/)');
  }
  if (!fs.existsSync(CHROMIUM)) skip(`${CHROMIUM} is missing (run scripts/install-deps.sh)`);
  return chromium;
}

// A fresh browser with one page; `errors` collects the page's uncaught exceptions.
// extraArgs: more Chromium switches (e.g. --host-resolver-rules).
export async function openBrowser(chromium, viewport, extraArgs = []) {
  const profile = fs.mkdtempSync(path.join(os.tmpdir(), 'dynahand-chromium-'));
  const context = await chromium.launchPersistentContext(profile, {
    executablePath: CHROMIUM, headless: true, args: [...CHROMIUM_ARGS, ...extraArgs], viewport,
  });
  const page = context.pages()[0] || (await context.newPage());
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  return { context, page, errors };
}

// Runs `dynahand ARGS...` (a command that serves the page) and resolves `address` with the
// page's URL once it prints it, or null when the build has no page.
export function startDynahand(dynahand, args) {
  const proc = spawn(dynahand, args, { stdio: ['ignore', 'pipe', 'inherit'] });
  const address = new Promise((resolve, reject) => {
    let out = '';
    proc.stdout.on('data', (chunk) => {
      out += chunk;
      const page = out.match(/viewer at (http:\/\/\S+)/);
      if (page) resolve(page[1]);
      else if (out.includes('viewer page unavailable')) resolve(null);
    });
    proc.on('exit', (code) => reject(new Error(`dynahand ${args[0]} exited with ${code}: ${out}`)));
  });
  return { proc, address };
}

// A page showing a playground scene: waits until it has drawn a few frames and checks the
// scene layer has its toggle.
export async function waitForScene(page) {
  await page.waitForFunction(() => window.dynahandViewer && window.dynahandViewer.framesDrawn >= 5,
    null, { timeout: 60000 });
  if ((await page.locator('#layer-scene').count()) !== 1) fail('no toggle for the scene layer');
}
