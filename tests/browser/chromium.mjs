// The system's Chromium, headless, through playwright-core: what every browser check launches.
import { chromium } from "playwright-core";
import { mkdtempSync, rmSync } from "node:fs";
import { tmpdir } from "node:os";
import { join } from "node:path";

export const CHROMIUM = process.env.LIGHTGRAPH_CHROMIUM || "/usr/bin/chromium";
// Chromium's background connections off: the machines the tests run on have no network.
const ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
  "--disable-background-networking", "--disable-component-update", "--disable-sync"];

// Runs `use(context)` in a browser with a new, empty profile (playwright passes it as
// --user-data-dir), closed and removed afterwards.
export async function withChromium(options, use) {
  const profile = mkdtempSync(join(tmpdir(), "lightgraph-chromium-"));
  const context = await chromium.launchPersistentContext(profile, { executablePath: CHROMIUM, args: ARGS, headless: true, ...options });
  try {
    return await use(context);
  } finally {
    await context.close();
    rmSync(profile, { recursive: true, force: true });
  }
}
