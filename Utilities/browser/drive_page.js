// Opens the main job's page (view.html) from the file system in headless Chromium (Debian's
// /usr/bin/chromium, driven by playwright-core: no browser of its own) and reports on stdout, as
// JSON: whether the take loaded (and in how many ms), its frames, vertices and colour; the
// canvas's pixels at frame 0 and after the slider moved to a late frame; the frame a click on the
// report's plot went to; whether playing advanced the frames; every console error and page
// error. With SHOTS, saves SHOTS-frame0.png and SHOTS-late.png (the whole page).
//
//   NODE_PATH=build/tools/node/node_modules node drive_page.js VIEW_HTML [SHOTS]
const path = require('path');
const { chromium } = require('playwright-core');

// What a headless Chromium needs here: no sandbox (root), no network calls of its own, WebGL in
// software (SwiftShader through ANGLE: there is no GPU).
const FLAGS = ['--no-sandbox', '--disable-quic', '--no-first-run', '--disable-background-networking',
  '--disable-component-update', '--disable-sync', '--use-angle=swiftshader',
  '--enable-unsafe-swiftshader'];

// The WebGL canvas read back: how many pixels are not the background, a checksum of them, and how
// many distinct colours (in steps of 16) they hold.
function readCanvas() {
  const canvas = document.querySelector('#view canvas');
  const copy = document.createElement('canvas');
  copy.width = canvas.width;
  copy.height = canvas.height;
  const context = copy.getContext('2d');
  context.drawImage(canvas, 0, 0);
  const d = context.getImageData(0, 0, copy.width, copy.height).data;
  let lit = 0, checksum = 0;
  const colours = new Set();
  for (let i = 0; i < d.length; i += 4) {
    const background = Math.abs(d[i] - 244) + Math.abs(d[i + 1] - 244) + Math.abs(d[i + 2] - 242) < 10;
    if (background) continue;
    ++lit;
    checksum = (checksum * 31 + d[i] * 7 + d[i + 1] * 13 + d[i + 2] * 17 + i) % 1000000007;
    colours.add(((d[i] >> 4) << 8) | ((d[i + 1] >> 4) << 4) | (d[i + 2] >> 4));
  }
  return { lit, checksum, colours: colours.size, pixels: d.length / 4 };
}

(async () => {
  const [page, shots] = process.argv.slice(2);
  const report = { errors: [] };
  const browser = await chromium.launch({ executablePath: '/usr/bin/chromium', headless: true,
                                          args: FLAGS });
  try {
    const tab = await browser.newPage({ viewport: { width: 1280, height: 800 } });
    tab.on('console', (m) => { if (m.type() === 'error') report.errors.push(m.text()); });
    tab.on('pageerror', (e) => report.errors.push(String(e)));
    const started = Date.now();
    await tab.goto('file://' + path.resolve(page));
    await tab.waitForFunction(() => window.dpViewer && (window.dpViewer.ready || window.dpViewer.error),
                              null, { timeout: 180000 });
    report.loadedMs = Date.now() - started;
    Object.assign(report, await tab.evaluate(() => ({
      ready: dpViewer.ready, error: dpViewer.error || null, frames: dpViewer.frames,
      vertices: dpViewer.vertices, coloured: dpViewer.coloured, flagged: dpViewer.flagged,
    })));
    if (!report.ready) return;
    report.frame0 = await tab.evaluate(readCanvas);
    if (shots) await tab.screenshot({ path: shots + '-frame0.png' });
    const late = Math.floor(0.8 * (report.frames - 1));
    await tab.$eval('#frame', (slider, value) => {
      slider.value = value;
      slider.dispatchEvent(new Event('input', { bubbles: true }));
    }, late);
    report.late = { frame: await tab.evaluate(() => dpViewer.frame()), canvas: await tab.evaluate(readCanvas) };
    if (shots) await tab.screenshot({ path: shots + '-late.png' });
    const target = report.flagged.length ? report.flagged[0] : Math.floor(report.frames / 2);
    const point = await tab.evaluate((t) => dpViewer.plotPoint(t), target);
    await tab.mouse.click(point.x, point.y);
    report.plotClick = { asked: target, reached: await tab.evaluate(() => dpViewer.frame()) };
    const before = await tab.evaluate(() => dpViewer.frame());
    // Playing moves on: the first frame shown after `before` (a fixed wait could land on the
    // same frame again, a whole number of loops of a short take later).
    // On a loaded machine the first click may come while the page still handles the plot's:
    // a second click after 10 s (play, pause, play) starts it then.
    await tab.click('#play');
    const moved = await tab.waitForFunction((b) => dpViewer.frame() !== b, before, { timeout: 10000 })
      .then(() => true).catch(() => false);
    if (!moved) {
      await tab.click('#play');
      await tab.click('#play');
      await tab.waitForFunction((b) => dpViewer.frame() !== b, before, { timeout: 10000 })
        .catch(() => {});
    }
    report.played = { from: before, to: await tab.evaluate(() => dpViewer.frame()) };
    await tab.click('#play');
  } finally {
    await browser.close();
    process.stdout.write(JSON.stringify(report) + '\n');
  }
})().catch((e) => { console.error(String(e)); process.exit(1); });
