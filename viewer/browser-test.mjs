// Browser test of `adamesh view`: opens the page in headless Chromium (Debian's chromium, driven
// by puppeteer-core), moves the slider with the mouse to two positions, and checks that
//  - the triangle count the page shows is the count of the same cut by `adamesh level`
//    (--triangles N must select exactly the prefix the slider shows, with N triangles),
//  - a uniform level chosen in the page has the count of `adamesh level --level K`,
//  - the rendered canvas is not blank (share of non-background pixels, luminance spread) and
//    differs between the two slider positions.
// usage: node browser-test.mjs ADAMESH FILE.amh PAGE.html [SCREENSHOT_DIR]
// Exits 0 when every check passes, 1 otherwise; prints one line per check.
import { execFileSync } from 'node:child_process';
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import path from 'node:path';
import puppeteer from 'puppeteer-core';

const [bin, amh, page, shots] = process.argv.slice(2);
if (!page) {
  console.error('usage: node browser-test.mjs ADAMESH FILE.amh PAGE.html [SCREENSHOT_DIR]');
  process.exit(2);
}
let failures = 0;
const check = (ok, what) => {
  console.log(`${ok ? 'ok  ' : 'FAIL'} ${what}`);
  if (!ok) failures++;
};

const tmp = mkdtempSync(path.join(tmpdir(), 'adamesh-view-'));
/// `adamesh level` on the hierarchy: { triangles, splits } of the cut.
function level(args) {
  const out = execFileSync(bin, ['level', amh, ...args, '-o', path.join(tmp, 'cut.ply')], { encoding: 'utf8' });
  const m = out.match(/: (\d+) triangles, \d+ vertices, depth \d+, (\d+) of (\d+) splits/);
  if (!m) throw new Error(`unexpected adamesh level output: ${out}`);
  return { triangles: Number(m[1]), splits: Number(m[2]), total: Number(m[3]) };
}

const browser = await puppeteer.launch({
  executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
  headless: true,
  args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--disable-gpu-sandbox'],
});
try {
  const tab = await browser.newPage();
  const errors = [];
  tab.on('pageerror', (e) => errors.push(e.message));
  tab.on('requestfailed', (r) => errors.push(`request failed: ${r.url()}`));
  const requests = [];
  tab.on('request', (r) => requests.push(r.url()));
  await tab.setViewport({ width: 1100, height: 700 });
  await tab.goto('file://' + path.resolve(page));
  await tab.waitForSelector('body[data-ready="1"]', { timeout: 60000 });
  check(requests.every((u) => u.startsWith('file://') || u.startsWith('data:')), `nothing fetched from the network (${requests.length} requests, all local)`);

  const shown = () => tab.evaluate(() => ({
    k: Number(document.getElementById('splits').value),
    max: Number(document.getElementById('splits').max),
    triangles: Number(document.getElementById('triangles').textContent),
  }));
  const pixels = () => tab.evaluate(async () => {
    const url = document.getElementById('view').toDataURL('image/png');
    const img = new Image();
    img.src = url;
    await img.decode();
    const c = document.createElement('canvas');
    c.width = img.width;
    c.height = img.height;
    const g = c.getContext('2d');
    g.drawImage(img, 0, 0);
    const d = g.getImageData(0, 0, c.width, c.height).data;
    const bg = [d[0], d[1], d[2]];  // the corner pixel: background
    let other = 0, sum = 0, sum2 = 0;
    const n = d.length / 4;
    for (let i = 0; i < d.length; i += 4) {
      const y = 0.299 * d[i] + 0.587 * d[i + 1] + 0.114 * d[i + 2];
      sum += y;
      sum2 += y * y;
      if (Math.abs(d[i] - bg[0]) + Math.abs(d[i + 1] - bg[1]) + Math.abs(d[i + 2] - bg[2]) > 24) other++;
    }
    const mean = sum / n;
    return { covered: other / n, std: Math.sqrt(Math.max(0, sum2 / n - mean * mean)), url };
  });

  // Move the slider with the mouse: a click at a fraction of its width.
  const slider = await tab.$('#splits');
  const box = await slider.boundingBox();
  const results = [];
  for (const [name, fraction, wire, colour] of [['coarse', 0.04, true, 'plain'], ['fine', 1.0, false, 'quality']]) {
    await tab.mouse.click(box.x + Math.min(fraction * box.width, box.width - 1), box.y + box.height / 2);
    if (wire !== (await tab.$eval('#wireframe', (e) => e.checked))) await tab.click('#wireframe');
    await tab.select('#colour', colour);
    const s = await shown();
    const cut = level(['--triangles', String(s.triangles)]);
    check(s.max === cut.total, `${name}: slider spans the ${cut.total} splits of the file`);
    check(cut.triangles === s.triangles && cut.splits === s.k,
      `${name}: page shows ${s.triangles} triangles after ${s.k} splits; adamesh level --triangles ${s.triangles}: ${cut.triangles} triangles, ${cut.splits} splits`);
    const px = await pixels();
    check(px.covered > 0.05 && px.std > 8, `${name}: canvas not blank (${(100 * px.covered).toFixed(1)} % of pixels off the background, luminance std ${px.std.toFixed(1)})`);
    results.push({ name, s, px });
    if (shots) await tab.screenshot({ path: path.join(shots, `view_${name}.png`) });
  }
  check(results[0].s.k < results[1].s.k && results[0].s.triangles < results[1].s.triangles, `the slider moved: ${results[0].s.triangles} then ${results[1].s.triangles} triangles`);
  check(results[0].px.url !== results[1].px.url, 'the two renderings differ');

  // A uniform level chosen in the selector.
  const levels = await tab.$$eval('#level option', (os) => os.map((o) => o.value).filter((v) => v !== ''));
  const K = levels[Math.min(3, levels.length - 1)];
  await tab.select('#level', K);
  const sl = await shown();
  const lc = level(['--level', K]);
  check(sl.triangles === lc.triangles, `level ${K}: page ${sl.triangles} triangles, adamesh level --level ${K}: ${lc.triangles}`);
  // Colour by quality and by distance bound must keep the count and render.
  for (const mode of ['quality', 'error']) {
    await tab.select('#colour', mode);
    const px = await pixels();
    check(px.covered > 0.05, `colour ${mode}: canvas not blank`);
  }
  check(errors.length === 0, `no page errors${errors.length ? ': ' + errors.join('; ') : ''}`);
} finally {
  await browser.close();
  rmSync(tmp, { recursive: true, force: true });
}
process.exit(failures ? 1 : 0);
