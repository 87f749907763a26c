// Opens lightgraph's HTML reports in headless Chromium (the system's, through the DevTools
// protocol with playwright-core) and checks them: no console error, no request off the disk,
// pixels read back from the canvas equal to the values the spec gives (the EXR's, tone-mapped
// by the test that wrote the spec), flip and split slider, plot hover, tables; optionally
// saves a screenshot. Usage: node check.mjs SPEC.json, where SPEC is
//   { "reports": [ { "html": PATH, "screenshot": PATH?, "mode": MODE?, "tables": N, "plots": N,
//       "viewers": [ { "index": I, "a": LABEL, "b": LABEL, "tmap": BOOL?,
//                      "pixels": [ { "x": X, "y": Y, "a": [R, G, B], "b": [R, G, B] } ] } ] } ] }
// Exits 1 naming every failure.
import { readFileSync } from "node:fs";
import { resolve } from "node:path";
import { pathToFileURL } from "node:url";
import { CHROMIUM, withChromium } from "./chromium.mjs";

const failures = [];
const fail = (report, what) => failures.push(`${report}: ${what}`);

async function pixelAt(page, index, x, y) {
  return page.evaluate(([index, x, y]) => {
    const v = window.lightgraph.viewers[index];
    const [sx, sy] = v.screenPoint(x, y);
    return Array.from(v.canvas.getContext("2d").getImageData(Math.floor(sx), Math.floor(sy), 1, 1).data.slice(0, 3));
  }, [index, x, y]);
}

// Checks the pixels of the spec against A's or B's values; `which(p)` says which.
async function expectPixels(page, name, v, which, what) {
  for (const p of v.pixels) {
    const got = await pixelAt(page, v.index, p.x, p.y), side = which(p);
    if (got.join() !== p[side].join())
      fail(name, `viewer ${v.index} ${what}: pixel (${p.x}, ${p.y}) is ${got}, the EXR's ${side.toUpperCase()} tone-mapped is ${p[side]}`);
  }
}

// One stop more exposure (ten steps of the slider's arrow key) brightens the image.
async function checkExposure(page, name, v, viewer, settle) {
  const before = await Promise.all(v.pixels.map((p) => pixelAt(page, v.index, p.x, p.y)));
  await viewer.locator("input[type=range]").nth(0).focus();
  for (let i = 0; i < 10; i++) await page.keyboard.press("ArrowRight");
  await settle();
  const after = await Promise.all(v.pixels.map((p) => pixelAt(page, v.index, p.x, p.y)));
  const flat = (l) => l.flat();
  if (!flat(after).every((c, i) => c >= flat(before)[i]) || flat(after).join() === flat(before).join())
    fail(name, `viewer ${v.index}: +1 stop of exposure gave ${flat(after)} from ${flat(before)}`);
  for (let i = 0; i < 10; i++) await page.keyboard.press("ArrowLeft");
  await settle();
}

// Chooses A and B in the viewer's selects and a mode by its button, as a user would.
async function choose(page, v) {
  const viewer = page.locator("section.lg-viewer").nth(v.index);
  await viewer.locator("select").nth(0).selectOption({ label: v.a });
  await viewer.locator("select").nth(1).selectOption({ label: v.b });
  await viewer.locator("button", { hasText: /^A$/ }).click();
  await page.evaluate((i) => window.lightgraph.viewers[i].ready(), v.index);
  return viewer;
}

async function checkViewer(page, name, v) {
  const viewer = await choose(page, v);
  const settle = () => page.evaluate((i) => window.lightgraph.viewers[i].ready(), v.index);
  await expectPixels(page, name, v, () => "a", "showing A");
  await checkExposure(page, name, v, viewer, settle);
  await expectPixels(page, name, v, () => "a", "back at exposure 0");
  await viewer.locator("button.lg-flip").click();
  await settle();
  await expectPixels(page, name, v, () => "b", "after flip");
  await viewer.locator("canvas").click();
  await page.keyboard.press("f");
  await settle();
  await expectPixels(page, name, v, () => "a", "after the key f on the image");
  await page.keyboard.press("f");
  await settle();
  await viewer.locator("button", { hasText: /^split$/ }).click();
  await settle();
  const width = await page.evaluate((i) => window.lightgraph.viewers[i].width, v.index);
  await expectPixels(page, name, v, (p) => (p.x < width / 2 ? "a" : "b"), "split in the middle");
  await viewer.locator("input[type=range]").nth(1).focus();
  await page.keyboard.press("End");
  await settle();
  await expectPixels(page, name, v, () => "a", "split slider at the right end (all A)");
  await page.keyboard.press("Home");
  await settle();
  await expectPixels(page, name, v, () => "b", "split slider at the left end (all B)");
  await viewer.locator("button", { hasText: "rel. error" }).click();
  await settle();
  const tmap = viewer.locator("button", { hasText: "t-map" });
  if (v.tmap && (await tmap.isDisabled())) fail(name, `viewer ${v.index}: no t-map for ${v.a} and ${v.b}`);
  if (v.tmap) { await tmap.click(); await settle(); }
  await viewer.locator("canvas").hover();
  const readout = await viewer.locator(".lg-readout").textContent();
  if (!readout.includes(v.a) || !readout.includes(v.b)) fail(name, `viewer ${v.index}: the readout under the cursor says '${readout}'`);
  await viewer.locator("button", { hasText: /^A$/ }).click();
  await settle();
}

async function checkPlots(page, name, count) {
  const plots = await page.evaluate(() => window.lightgraph.plots.length);
  if (plots < count) fail(name, `${plots} plots, expected ${count}`);
  for (let i = 0; i < Math.min(plots, count); i++) {
    const [x, y] = await page.evaluate((i) => window.lightgraph.plots[i].pointAt(0, 0), i);
    const canvas = page.locator(".lg-plot canvas").nth(i);
    await canvas.hover({ position: { x, y } });
    const tip = page.locator(".lg-plot .lg-tip").nth(i);
    if (!(await tip.isVisible()) || !(await tip.textContent()).includes(":")) fail(name, `plot ${i}: no values on hover`);
  }
}

// Saves a picture of the report's first viewer (in the spec's "mode", else split) or plot.
async function screenshot(page, report) {
  await page.evaluate((mode) => Promise.all(window.lightgraph.viewers.map((v) => v.set({ mode, split: 0.5 }))),
    report.mode || "split");
  await page.mouse.move(0, 0);
  await page.locator(".lg-viewer, .lg-plot").first().screenshot({ path: report.screenshot });
}

async function checkReport(context, report) {
  const name = report.html;
  const page = await context.newPage();
  page.on("console", (m) => { if (m.type() === "error") fail(name, `console error: ${m.text()}`); });
  page.on("pageerror", (e) => fail(name, `page error: ${e.message}`));
  await page.route("**/*", (route) => {
    const url = route.request().url();
    if (url.startsWith("file:")) return route.continue();
    fail(name, `request off the disk: ${url}`);
    return route.abort();
  });
  await page.goto(pathToFileURL(resolve(report.html)).href);
  const ready = await page.evaluate(() => window.lightgraph.ready.then(() => "ok", (e) => String(e)));
  if (ready !== "ok") fail(name, `the viewers did not draw: ${ready}`);
  else for (const v of report.viewers || []) await checkViewer(page, name, v);
  await checkPlots(page, name, report.plots || 0);
  const tables = await page.locator(".lg-table table").count();
  if (tables < (report.tables || 0)) fail(name, `${tables} tables, expected ${report.tables}`);
  if (report.screenshot) await screenshot(page, report);
  await page.close();
}

const spec = JSON.parse(readFileSync(process.argv[2], "utf8"));
await withChromium({ viewport: { width: 1200, height: 900 } }, async (context) => {
  for (const report of spec.reports) await checkReport(context, report);
});
if (failures.length) {
  console.error(failures.join("\n"));
  process.exit(1);
}
console.log(`checked ${spec.reports.length} reports in ${CHROMIUM}`);
