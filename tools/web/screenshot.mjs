// SPDX-License-Identifier: MIT
// Opens the citymesh viewer in headless Chromium (Debian's /usr/bin/chromium, driven by
// playwright-core), waits until every tile the view needs is loaded and drawn, and saves a
// screenshot. Prints the page's status line and its legend's text; with --click, clicks that
// pixel first and prints what the page says was picked. Exits 1 when the page reports an
// error or the tiles do not load in time. Usage:
//   node tools/web/screenshot.mjs http://127.0.0.1:8080/ viewer.png [--timeout 60] [--click X,Y]
import { chromium } from 'playwright-core';

const [url, out] = process.argv.slice(2);
const timeoutIndex = process.argv.indexOf('--timeout');
const timeout = 1000 * (timeoutIndex > 0 ? Number(process.argv[timeoutIndex + 1]) : 60);
const clickIndex = process.argv.indexOf('--click');
const click = clickIndex > 0 ? process.argv[clickIndex + 1].split(',').map(Number) : null;
if (!url || !out) {
  console.error('usage: node screenshot.mjs URL OUT.png [--timeout SECONDS] [--click X,Y]');
  process.exit(2);
}
const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM ?? '/usr/bin/chromium',
  args: ['--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run', '--disable-background-networking',
    '--disable-component-update', '--disable-sync', '--use-angle=swiftshader', '--enable-unsafe-swiftshader'],
});
let failed = false;
try {
  const page = await browser.newPage({ viewport: { width: 1024, height: 640 } });
  page.on('pageerror', (e) => { console.error(`page error: ${e.message}`); failed = true; });
  page.on('console', (m) => { if (m.type() === 'error') console.error(`console error: ${m.text()}`); });
  await page.goto(url, { timeout });
  // The viewer sets data-settled once the tile queue is empty and something is drawn.
  await page.waitForSelector('body[data-settled="true"]', { timeout });
  if (click) {
    await page.mouse.click(click[0], click[1]);
    await page.waitForFunction(() => document.getElementById('picked')?.textContent, null, { timeout: 20000 });
    console.log(`picked: ${await page.textContent('#picked')}`);
  }
  await page.screenshot({ path: out });
  console.log(await page.textContent('#status'));
  const legend = await page.$('#legend');
  if (legend) console.log(`legend: ${await legend.textContent()}`);
} catch (e) {
  console.error(`screenshot: ${e.message}`);
  failed = true;
} finally {
  await browser.close();
}
process.exit(failed ? 1 : 0);
