// Opens `render --serve`'s live page in headless Chromium (the system's, through playwright-core)
// and follows the render to its end: no console error; the film is fetched anew as its version
// changes (at least MIN_LOADS times), after which it prints the line `watching` on stdout (the
// caller may then end the render, however long it took the browser to start); once the render
// is over, prints the canvas's pixels at the points asked for, as JSON on stdout, for the caller
// to compare with the film written, and optionally saves a screenshot. Usage: node live.mjs URL
// X,Y[;X,Y...] [SCREENSHOT]. Exits 1 naming every failure.
import { withChromium } from "./chromium.mjs";

const MIN_LOADS = 3;

const [url, points, screenshot] = process.argv.slice(2);
const failures = [];
try {
  await withChromium({}, (context) => follow(context));
} catch (e) {
  failures.push(String(e));
}
if (failures.length) {
  console.error(failures.join("\n"));
  process.exit(1);
}

// Follows the page to the render's end and prints what it shows.
async function follow(context) {
  const page = await context.newPage();
  page.on("console", (m) => { if (m.type() === "error") failures.push(`console error: ${m.text()}`); });
  page.on("pageerror", (e) => failures.push(`page error: ${e.message}`));
  await page.goto(url);
  await page.waitForFunction((n) => window.lightgraphLive && window.lightgraphLive.loads >= n,
    MIN_LOADS, { timeout: 120000, polling: 100 });
  console.log("watching");
  await page.waitForFunction(() => window.lightgraphLive && window.lightgraphLive.status
    && window.lightgraphLive.status.finished && window.lightgraphLive.drawn === window.lightgraphLive.status.version,
    null, { timeout: 120000, polling: 100 });
  const live = await page.evaluate(() => ({ ...window.lightgraphLive }));
  if (live.loads < MIN_LOADS) failures.push(`the film was loaded ${live.loads} times, fewer than ${MIN_LOADS}`);
  const line = await page.locator(".lg-live").textContent();
  if (!line.includes("samples/s") || !line.includes("the render is over")) failures.push(`the status line says '${line}'`);
  const pixels = await page.evaluate((points) => {
    const v = window.lightgraph.viewers[0];
    return points.split(";").map((p) => {
      const [x, y] = p.split(",").map(Number), [sx, sy] = v.screenPoint(x, y);
      return Array.from(v.canvas.getContext("2d").getImageData(Math.floor(sx), Math.floor(sy), 1, 1).data.slice(0, 3));
    });
  }, points);
  if (screenshot) await page.screenshot({ path: screenshot, fullPage: true });
  console.log(JSON.stringify({ pixels, loads: live.loads, version: live.status.version }));
}
