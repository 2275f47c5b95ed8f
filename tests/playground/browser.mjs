// Debian's Chromium, driven by Playwright's core, for the playground's
// browser test and its latency benchmark. Playwright never downloads a
// browser here: it is given the system's, headless, with everything that
// would reach the network on its own turned off.

import { createRequire } from 'node:module';
import path from 'node:path';

/** The Chromium of Debian's package. */
export const CHROMIUM = process.env.GLINT_CHROMIUM ?? '/usr/bin/chromium';

export const FLAGS = [
  '--headless',
  '--no-sandbox',
  '--disable-gpu',
  '--disable-background-networking',
  '--disable-component-update',
  '--disable-sync',
  '--no-first-run',
  '--disable-dev-shm-usage',
  '--disable-default-apps',
  '--disable-extensions',
];

/**
 * Playwright's `chromium`, from the `node_modules` under `dir` (where
 * `npm ci` installed tests/playground/package-lock.json).
 */
export function playwright(dir) {
  const require = createRequire(path.join(path.resolve(dir), 'package.json'));
  return require('playwright-core');
}

/** A headless Chromium. */
export async function launch(dir) {
  const { chromium } = playwright(dir);
  return chromium.launch({ executablePath: CHROMIUM, headless: true, args: FLAGS, timeout: 60_000 });
}
