// The playground's latency, measured in the browser: the time from a
// control's change to its preview on screen, for the spheres example. Each
// sample moves the cutoff slider of the spotlight (40° and 41° in turns) by
// an input event dispatched in the page, and stops the clock when the page
// announces the preview on screen (the first task after the frame that
// shows it is rendered). The full-size render that follows at rest is waited for before
// the next sample, so that samples do not overlap. Not a test: it prints
// the median and the spread.
//
//   node benches/playground_latency.mjs --glint target/release/glint [--samples 40]
//   node benches/playground_latency.mjs --url http://127.0.0.1:8080
//
// `benches/playground_latency.sh` builds the release server, installs
// Playwright's core under target/tools/node-playground and runs this.

import { spawn } from 'node:child_process';
import { createInterface } from 'node:readline';
import { parseArgs } from 'node:util';

import { launch } from '../tests/playground/browser.mjs';

const { values: options } = parseArgs({
  options: {
    glint: { type: 'string' },
    url: { type: 'string' },
    samples: { type: 'string', default: '40' },
    warmup: { type: 'string', default: '5' },
    playwright: { type: 'string', default: 'target/tools/node-playground' },
  },
});
const samples = Number(options.samples);
const warmup = Number(options.warmup);

/** Starts `glint serve` on a port of the kernel's choosing and learns it from its log. */
async function serve(binary) {
  const child = spawn(binary, ['serve', '--listen', '127.0.0.1:0', '--log-format', 'json'], {
    stdio: ['ignore', 'pipe', 'inherit'],
  });
  const lines = createInterface({ input: child.stdout });
  const address = await new Promise((resolve, reject) => {
    const timer = setTimeout(() => reject(new Error('glint did not say where it listens within 30 s')), 30_000);
    lines.on('line', (line) => {
      try {
        const entry = JSON.parse(line);
        if (entry.fields?.message === 'glint listening') {
          clearTimeout(timer);
          resolve(entry.fields.address);
        }
      } catch {
        // Not a log line of ours.
      }
    });
    child.on('exit', () => reject(new Error('glint exited before it listened')));
  });
  return { child, url: `http://${address}` };
}

const quantile = (sorted, q) => sorted[Math.min(sorted.length - 1, Math.floor(q * sorted.length))];

const server = options.glint ? await serve(options.glint) : { child: null, url: options.url };
if (!server.url) throw new Error('give --glint BINARY or --url URL');
const browser = await launch(options.playwright);
try {
  const page = await browser.newPage({ viewport: { width: 1280, height: 800 } });
  page.setDefaultTimeout(60_000);
  await page.goto(`${server.url}/`);
  await page.waitForFunction(() => document.querySelector('#view').dataset.kind === 'full');
  const measured = [];
  for (let i = 0; i < warmup + samples; i += 1) {
    const sample = await page.evaluate(async (value) => {
      const canvas = document.querySelector('#view');
      const slider = document.querySelector('[data-light="3"]').querySelector('input[type="range"]');
      const drawn = (kind) =>
        new Promise((resolve) => {
          canvas.addEventListener('glint:drawn', function once(event) {
            if (event.detail.kind !== kind) return;
            canvas.removeEventListener('glint:drawn', once);
            resolve(event.detail);
          });
        });
      const preview = drawn('preview');
      const full = drawn('full');
      const changed = performance.now();
      slider.value = String(value);
      slider.dispatchEvent(new Event('input', { bubbles: true }));
      const shown = await preview;
      await full;
      return { ms: shown.drawnAt - changed, roundTrip: shown.ms, size: `${shown.width}x${shown.height}` };
    }, i % 2 === 0 ? 41 : 40);
    if (i >= warmup) measured.push(sample);
  }
  const sorted = (key) => measured.map((s) => s[key]).sort((a, b) => a - b);
  const ms = sorted('ms');
  const fmt = (x) => x.toFixed(1);
  console.log(`playground latency, spheres example, control change -> preview on screen (${measured[0].size} preview), ${samples} samples after ${warmup} of warm-up`);
  console.log(`  median ${fmt(quantile(ms, 0.5))} ms   p10 ${fmt(quantile(ms, 0.1))} ms   p90 ${fmt(quantile(ms, 0.9))} ms   min ${fmt(ms[0])} ms   max ${fmt(ms.at(-1))} ms`);
  console.log(`  of it, the request's round trip (fetch to the PNG's last byte): median ${fmt(quantile(sorted('roundTrip'), 0.5))} ms`);
} finally {
  await browser.close();
  server.child?.kill('SIGTERM');
}
