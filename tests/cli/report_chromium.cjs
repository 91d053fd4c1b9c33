// Opens a run report (report/index.html) from file:// in headless Chromium, driven by
// puppeteer-core, and checks that it renders offline:
//   - no console error, no uncaught exception, no failed request, no request leaving file://;
//   - the 3D view reaches body[data-viewer="ready"] for the first cell with a glTF;
//   - a screenshot of the 3D canvas is not blank: enough pixels differ from its background;
//   - dragging on the canvas (OrbitControls) changes the picture;
//   - the cells' and the timings' charts are on the page.
// Usage: node report_chromium.cjs PUPPETEER_CORE_DIR CHROMIUM INDEX_HTML SCREENSHOT_PNG
// Prints one JSON line with what it saw; exit 0 when every check passes, 1 otherwise.
'use strict';
const fs = require('fs');
const zlib = require('zlib');

const [puppeteerDir, chromium, indexHtml, screenshotPath] = process.argv.slice(2);
const puppeteer = require(puppeteerDir);

// RGBA pixels of an 8-bit RGB or RGBA, non-interlaced PNG (what Chromium writes).
function decodePng(buffer) {
  let offset = 8, width = 0, height = 0, channels = 0;
  const data = [];
  while (offset < buffer.length) {
    const length = buffer.readUInt32BE(offset);
    const type = buffer.toString('ascii', offset + 4, offset + 8);
    const body = buffer.subarray(offset + 8, offset + 8 + length);
    if (type === 'IHDR') {
      width = body.readUInt32BE(0);
      height = body.readUInt32BE(4);
      if (body[8] !== 8 || body[12] !== 0) throw new Error('unsupported PNG (depth/interlace)');
      channels = {2: 3, 6: 4}[body[9]];
      if (!channels) throw new Error('unsupported PNG colour type ' + body[9]);
    } else if (type === 'IDAT') {
      data.push(body);
    }
    offset += 12 + length;
  }
  const raw = zlib.inflateSync(Buffer.concat(data));
  const stride = width * channels;
  const pixels = Buffer.alloc(width * height * 4);
  const previous = Buffer.alloc(stride), current = Buffer.alloc(stride);
  for (let y = 0; y < height; ++y) {
    const filter = raw[y * (stride + 1)];
    raw.copy(current, 0, y * (stride + 1) + 1, (y + 1) * (stride + 1));
    for (let i = 0; i < stride; ++i) {
      const a = i >= channels ? current[i - channels] : 0;
      const b = previous[i];
      const c = i >= channels ? previous[i - channels] : 0;
      let predictor = 0;
      if (filter === 1) predictor = a;
      else if (filter === 2) predictor = b;
      else if (filter === 3) predictor = (a + b) >> 1;
      else if (filter === 4) {
        const p = a + b - c, pa = Math.abs(p - a), pb = Math.abs(p - b), pc = Math.abs(p - c);
        predictor = pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
      }
      current[i] = (current[i] + predictor) & 0xff;
    }
    for (let x = 0; x < width; ++x) {
      for (let k = 0; k < 4; ++k) {
        pixels[(y * width + x) * 4 + k] = k < channels ? current[x * channels + k] : 255;
      }
    }
    current.copy(previous);
  }
  return {width, height, pixels};
}

// Share of pixels further than `tolerance` (per channel) from the top-left pixel's colour.
function differingShare(png, tolerance) {
  const {pixels} = png;
  const background = [pixels[0], pixels[1], pixels[2]];
  let differing = 0;
  const total = pixels.length / 4;
  for (let i = 0; i < total; ++i) {
    for (let k = 0; k < 3; ++k) {
      if (Math.abs(pixels[i * 4 + k] - background[k]) > tolerance) {
        ++differing;
        break;
      }
    }
  }
  return {share: differing / total, background};
}

(async () => {
  const problems = [];
  const seen = {console_errors: [], page_errors: [], failed_requests: [], remote_requests: []};
  const browser = await puppeteer.launch({
    executablePath: chromium,
    headless: true,
    // Root in a container: no sandbox. No GPU: WebGL through SwiftShader (software), which
    // Chromium asks to be opted into explicitly.
    args: ['--no-sandbox', '--enable-unsafe-swiftshader', '--use-angle=swiftshader',
           '--window-size=1200,2400'],
  });
  try {
    const page = await browser.newPage();
    await page.setViewport({width: 1200, height: 2400});
    page.on('console', (message) => {
      if (message.type() === 'error') seen.console_errors.push(message.text());
    });
    page.on('pageerror', (error) => seen.page_errors.push(error.message));
    page.on('requestfailed', (request) => {
      seen.failed_requests.push(request.url() + ': ' + (request.failure() || {}).errorText);
    });
    page.on('request', (request) => {
      if (!/^(file|data|blob):/.test(request.url())) seen.remote_requests.push(request.url());
    });
    await page.goto('file://' + indexHtml, {waitUntil: 'load', timeout: 60000});
    await page.waitForFunction(
        () => ['ready', 'error', 'unavailable'].includes(document.body.dataset.viewer),
        {timeout: 60000});
    seen.viewer = await page.evaluate(() => document.body.dataset.viewer);
    seen.status = await page.$eval('#viewer-status', (node) => node.textContent);
    if (seen.viewer !== 'ready') problems.push('3D view ' + seen.viewer + ': ' + seen.status);

    seen.charts = await page.evaluate(() => ({
      top_view_cells: document.querySelectorAll('svg .cell').length,
      footprints: document.querySelectorAll('svg .footprint').length,
      bars: document.querySelectorAll('svg .bar').length,
      timing_bars: document.querySelectorAll('#timings svg .bar').length,
    }));
    if (seen.charts.top_view_cells === 0) problems.push('no cells in the top view');
    if (seen.charts.timing_bars === 0) problems.push('no stage timings drawn');

    if (seen.viewer === 'ready') {
      const canvas = await page.$('#viewer canvas');
      if (!canvas) {
        problems.push('no canvas in #viewer');
      } else {
        const before = await canvas.screenshot({type: 'png'});
        fs.writeFileSync(screenshotPath, before);
        const png = decodePng(before);
        const {share, background} = differingShare(png, 12);
        seen.canvas = {width: png.width, height: png.height, background,
                       differing_share: Number(share.toFixed(4))};
        if (share < 0.02) problems.push('3D canvas blank: ' + (share * 100).toFixed(2) + '% pixels differ');
        // Orbit: drag across the canvas, the picture must change.
        const box = await canvas.boundingBox();
        await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
        await page.mouse.down();
        await page.mouse.move(box.x + box.width / 2 + 150, box.y + box.height / 2 + 40, {steps: 8});
        await page.mouse.up();
        await new Promise((resolve) => setTimeout(resolve, 300));
        const after = await canvas.screenshot({type: 'png'});
        seen.orbit_changed = !before.equals(after);
        if (!seen.orbit_changed) problems.push('dragging the 3D view changed nothing');
      }
    }
  } finally {
    await browser.close();
  }
  for (const [name, list] of Object.entries(seen)) {
    if (Array.isArray(list) && list.length) problems.push(name + ': ' + list.join(' | '));
  }
  console.log(JSON.stringify({...seen, problems}));
  process.exit(problems.length ? 1 : 0);
})().catch((error) => {
  console.log(JSON.stringify({problems: [String(error && error.stack || error)]}));
  process.exit(1);
});
