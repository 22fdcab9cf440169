// Opens a frond preview page in headless Chromium (Debian's, through puppeteer-core) and checks
// its live view from the page itself: it prints one JSON object on stdout and saves screenshots
// for the Rust test (tests/preview_browser.rs) to compare.
//
//   node tools/preview_check.mjs URL OUTDIR [CHROMIUM]
//
// Steps: wait until window.frondView is ready (or reports an error); two screenshots of the
// canvas ~0.8 s apart while playing (anim_0.png, anim_1.png); pause; move the LOD slider to
// each LOD with the mouse-less 'input' event a user's drag sends (lod_<k>.png), reading back
// which LOD's nodes are visible. Output: {ok, error, lods, times, visible, console}.
import { mkdirSync } from 'node:fs';
import { join } from 'node:path';
import puppeteer from 'puppeteer-core';

const [url, outDir, chromium = '/usr/bin/chromium'] = process.argv.slice(2);
if (!url || !outDir) {
  console.error('usage: node tools/preview_check.mjs URL OUTDIR [CHROMIUM]');
  process.exit(2);
}
mkdirSync(outDir, { recursive: true });
const result = { ok: false, error: null, lods: [], times: [], visible: [], treePixels: 0, console: [] };
const browser = await puppeteer.launch({
  executablePath: chromium,
  headless: true,
  // WebGL in software: SwiftShader through ANGLE (headless Chromium has no GPU here).
  args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist', '--window-size=1200,900'],
});
try {
  const page = await browser.newPage();
  await page.setViewport({ width: 1200, height: 900 });
  page.on('console', (m) => result.console.push(`${m.type()}: ${m.text()}`));
  page.on('pageerror', (e) => result.console.push(`pageerror: ${e.message}`));
  await page.goto(url, { waitUntil: 'load', timeout: 120000 });
  await page.waitForFunction(() => window.frondView && (window.frondView.ready || window.frondView.error), { timeout: 240000 });
  const first = await page.evaluate(() => ({ error: window.frondView.error, lods: window.frondView.lods }));
  result.error = first.error;
  result.lods = first.lods;
  if (!first.error) {
    const canvas = await page.$('#live-canvas');
    await page.waitForFunction(() => window.frondView.frames > 5, { timeout: 60000 });
    for (const i of [0, 1]) {
      if (i) await new Promise((r) => setTimeout(r, 800));
      result.times.push(await page.evaluate(() => window.frondView.time));
      await canvas.screenshot({ path: join(outDir, `anim_${i}.png`) });
    }
    await page.evaluate(() => window.frondView.setPlaying(false));
    for (let k = 0; k < result.lods.length; k += 1) {
      await page.evaluate((k) => {
        const s = document.getElementById('lod-slider');
        s.value = String(k);
        s.dispatchEvent(new Event('input', { bubbles: true }));
      }, k);
      const seen = await page.evaluate(() => window.frondView.frames);
      await page.waitForFunction((n) => window.frondView.frames > n + 2, { timeout: 60000 }, seen);
      result.visible.push(await page.evaluate(() => window.frondView.visible));
      await canvas.screenshot({ path: join(outDir, `lod_${k}.png`) });
    }
    result.treePixels = await page.evaluate(() => window.frondView.treePixels);
    await page.screenshot({ path: join(outDir, 'page.png'), fullPage: true });
    result.ok = true;
  }
} catch (e) {
  result.error = `${e.message}`;
} finally {
  await browser.close();
}
console.log(JSON.stringify(result));
