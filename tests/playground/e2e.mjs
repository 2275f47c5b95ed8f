// The playground in headless Chromium, against a running glint: each check
// of issue "The playground" as a person would meet it, every number compared
// with the API's own answer to the same request.
//
//   GLINT_BASE=http://127.0.0.1:8080 GLINT_PLAYWRIGHT_DIR=target/tools/node-playground \
//   GLINT_EXAMPLES=examples GLINT_SCREENSHOT=target/playground/playground.png \
//   GLINT_MODEL=target/playground/tent.glb GLINT_OUT=target/playground \
//   node tests/playground/e2e.mjs
//
// GLINT_MODEL is the GLB the page is given (its node moves and scales it,
// no rotation); the baked models the page offers are saved in GLINT_OUT,
// each beside the `request` part of the bake that made it
// (NAME.request.json), for the Rust side to check.
//
// Every wait is bounded and waits for a condition, never for a time. It
// prints one line per check and exits non-zero at the first that fails.

import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import { copyFileSync, existsSync, mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import os from 'node:os';
import path from 'node:path';

import { launch } from './browser.mjs';

const BASE = process.env.GLINT_BASE;
const EXAMPLES = process.env.GLINT_EXAMPLES;
const SCREENSHOT = process.env.GLINT_SCREENSHOT;
const MODEL = process.env.GLINT_MODEL;
const OUT = process.env.GLINT_OUT;
assert.ok(
  BASE && EXAMPLES && SCREENSHOT && MODEL && OUT && process.env.GLINT_PLAYWRIGHT_DIR,
  'GLINT_BASE, GLINT_EXAMPLES, GLINT_SCREENSHOT, GLINT_MODEL, GLINT_OUT and GLINT_PLAYWRIGHT_DIR are needed',
);
const ORIGIN = new URL(BASE).origin;
/** The longest any one condition is waited for. */
const WAIT = 30_000;

const example = (name) => JSON.parse(readFileSync(path.join(EXAMPLES, `${name}.json`), 'utf8'));

/** Asks the API itself: the JSON form of a render. */
async function api(body) {
  const response = await fetch(`${BASE}/v1/render`, {
    method: 'POST',
    headers: { 'content-type': 'application/json', accept: 'application/json' },
    body: JSON.stringify(body),
    signal: AbortSignal.timeout(WAIT),
  });
  return { status: response.status, json: await response.json() };
}

/** The four places the page shows a number to. */
const shown = (value) => {
  const text = value.toFixed(4);
  return /^-0\.?0*$/.test(text) ? text.slice(1) : text;
};

async function check(name, run) {
  const started = Date.now();
  try {
    await run();
    console.log(`ok   ${name} (${Date.now() - started} ms)`);
  } catch (error) {
    console.log(`FAIL ${name}\n${error.stack ?? error}`);
    await browser.close().catch(() => {});
    process.exit(1);
  }
}

const browser = await launch(process.env.GLINT_PLAYWRIGHT_DIR);
const context = await browser.newContext({ viewport: { width: 1280, height: 800 } });
await context.grantPermissions(['clipboard-read', 'clipboard-write'], { origin: ORIGIN });
const page = await context.newPage();
page.setDefaultTimeout(WAIT);

// What the page does that a person does not see: console errors, requests
// to other hosts, requests that fail other than by being aborted.
const consoleErrors = [];
const elsewhere = [];
const failed = [];
const renders = [];
const shades = [];
page.on('console', (message) => {
  if (message.type() === 'error') consoleErrors.push(message.text());
});
page.on('pageerror', (error) => consoleErrors.push(String(error)));
page.on('request', (request) => {
  const url = new URL(request.url());
  if (url.origin !== ORIGIN && url.protocol !== 'data:' && url.protocol !== 'blob:') elsewhere.push(request.url());
  if (url.pathname === '/v1/render') renders.push(request);
  if (url.pathname === '/v1/shade') shades.push(request);
});
page.on('requestfailed', (request) => failed.push({ url: request.url(), error: request.failure()?.errorText, request }));
// The answers with a problem, which the checks of bad values ask for.
const problems = [];
page.on('response', (response) => {
  if (response.status() >= 400) problems.push(response.status());
});

const canvas = page.locator('#view');
const drawn = () => canvas.evaluate((c) => Number(c.dataset.drawn ?? 0));
/**
 * Waits until the view has drawn after `count` draws and settled: the last
 * request sent is drawn, at full size, and no full size is still due.
 */
async function fullAfter(count) {
  await page.waitForFunction(
    (n) => {
      const c = document.querySelector('#view').dataset;
      return Number(c.drawn ?? 0) > n && c.kind === 'full' && c.shown === c.sent && c.resting === undefined;
    },
    count,
    { timeout: WAIT },
  );
}
/**
 * The parts of a `multipart/form-data` request (RFC 7578), by name: each
 * one's type, file name and bytes. A name twice fails.
 */
function parts(request) {
  const type = request.headers()['content-type'] ?? '';
  const boundary = /^multipart\/form-data; *boundary=(.+)$/.exec(type)?.[1];
  assert.ok(boundary, `a form: ${type}`);
  // Every delimiter but the first follows a line break: give the first one too.
  const data = Buffer.concat([Buffer.from('\r\n'), request.postDataBuffer()]);
  const delimiter = Buffer.from(`\r\n--${boundary}`);
  const found = {};
  let at = data.indexOf(delimiter);
  assert.equal(at, 0, 'the body starts with the first delimiter');
  for (;;) {
    const start = at + delimiter.length;
    if (data.toString('latin1', start, start + 2) === '--') break;
    const next = data.indexOf(delimiter, start);
    assert.ok(next > start, 'every part is closed');
    const part = data.subarray(start + 2, next);
    const split = part.indexOf('\r\n\r\n');
    const head = part.toString('utf8', 0, split);
    const name = /; *name="([^"]*)"/.exec(head)[1];
    assert.ok(!(name in found), `one ${name} part`);
    found[name] = {
      type: /^content-type: *(.+)$/im.exec(head)?.[1],
      filename: /; *filename="([^"]*)"/.exec(head)?.[1],
      bytes: part.subarray(split + 4),
    };
    at = next;
  }
  return found;
}
const isForm = (request) => (request.headers()['content-type'] ?? '').startsWith('multipart/form-data');
/** A render's request: the JSON body, or a form's `request` part. */
const body = (request) => JSON.parse(isForm(request) ? parts(request).request.bytes.toString('utf8') : request.postData());
/** A preview asks for the PNG alone; a full render for the JSON form. */
const preview = (request) => request.headers().accept === 'image/png';
/** The last render sent for the picture: a probe of a pixel, which the page
 * sends again after each full size, is not one. */
const lastPicture = () => renders.filter((r) => !body(r).probes).at(-1);
const field = (section, label) =>
  page.locator(`[data-section="${section}"]`).getByLabel(label, { exact: true });

const spheres = example('spheres');

await check('the page loads and draws the spheres example at full size', async () => {
  const response = await page.goto(BASE + '/');
  assert.equal(response.status(), 200);
  assert.match(response.headers()['content-type'], /^text\/html/);
  assert.match(response.headers()['content-security-policy'], /default-src 'self'/);
  await fullAfter(0);
  assert.equal(await canvas.evaluate((c) => `${c.width}x${c.height}`), `${spheres.camera.width}x${spheres.camera.height}`);
  // The first render sent is the example as it is, but smaller; the full one is the example.
  const sentFull = renders.map(body).find((b) => b.camera.width === spheres.camera.width);
  assert.deepEqual(sentFull, spheres);
  assert.ok(renders.map(body).some((b) => b.camera.width < spheres.camera.width), 'a preview came first');
  assert.deepEqual(consoleErrors, [], 'no console error on load');
});

// The rest of the checks work on a smaller image with one sample, which
// even a build without optimisations renders in a moment.
const scene = structuredClone(spheres);
Object.assign(scene.camera, { width: 320, height: 180 });
scene.samples = 1;

await check('the size and the samples are controls too', async () => {
  const count = await drawn();
  await field('camera', 'Width (pixels)').fill('320');
  await field('camera', 'Height (pixels)').fill('180');
  await field('rendering', 'Samples per pixel').fill('1');
  await fullAfter(count);
  assert.deepEqual(body(lastPicture()), scene);
  assert.equal(await canvas.evaluate((c) => `${c.width}x${c.height}`), '320x180');
});

/** Checks that every form control has a label. */
async function everyControlLabelled() {
  const unlabelled = await page.evaluate(() =>
    [...document.querySelectorAll('input, select, textarea, button')]
      .filter((c) => !(c.labels?.length > 0 || c.getAttribute('aria-label') || (c.tagName === 'BUTTON' && c.textContent.trim())))
      .map((c) => c.outerHTML),
  );
  assert.deepEqual(unlabelled, []);
}

await check('every control has a label', async () => {
  await everyControlLabelled();
  const controls = await page.locator('input, select').count();
  assert.ok(controls > 80, `only ${controls} controls`);
});

await check('clicking a pixel shows the breakdown the API gives for it', async () => {
  const box = await canvas.boundingBox();
  const at = { x: box.width * 0.56, y: box.height * 0.62 };
  await canvas.click({ position: at });
  const x = Math.floor((at.x / box.width) * scene.camera.width);
  const y = Math.floor((at.y / box.height) * scene.camera.height);
  const result = page.locator('#probe-result');
  await page.waitForFunction((p) => document.querySelector('#probe-result').dataset.pixel === p && document.querySelector('#probe-result table'), `${x},${y}`);

  const { status, json } = await api({ ...scene, probes: [[x, y]] });
  assert.equal(status, 200);
  const probe = json.terms.probes[0];
  assert.ok(probe.hit, 'the pixel chosen hits something');
  const { breakdown } = probe;
  const expected = new Map([
    ['emission', breakdown.emission],
    ['global_ambient', breakdown.global_ambient],
    ['unclamped', breakdown.unclamped],
    ['color', probe.color],
  ]);
  breakdown.lights.forEach((light, i) => {
    for (const term of ['ambient', 'diffuse', 'specular']) expected.set(`lights[${i}].${term}`, light[term]);
    for (const factor of ['attenuation', 'spot']) expected.set(`lights[${i}].${factor}`, [light[factor]]);
  });
  const rows = await result.locator('table tbody tr').evaluateAll((trs) =>
    trs.map((tr) => ({
      term: tr.dataset.term,
      values: [...tr.querySelectorAll('td[data-value]')].map((td) => ({ value: Number(td.dataset.value), text: td.textContent })),
    })),
  );
  assert.deepEqual(rows.map((r) => r.term).sort(), [...expected.keys()].sort());
  for (const { term, values } of rows) {
    assert.deepEqual(values.map((v) => v.value), expected.get(term), term);
    assert.deepEqual(values.map((v) => v.text), expected.get(term).map(shown), term);
  }
  assert.deepEqual(await result.locator('ul.modeled li').allTextContents(), json.modeled);
  assert.match(await result.locator('.hit').textContent(), new RegExp(`object ${probe.hit.object} .* ${probe.hit.side} side`));

  // The bars: one per channel, a segment per positive term, each the API's value.
  for (const [c, channel] of ['R', 'G', 'B'].entries()) {
    const segments = await result.locator(`.bar[data-channel="${channel}"] .segment`).evaluateAll((spans) =>
      spans.map((s) => ({ term: s.dataset.term, value: Number(s.title.split(': ').pop()) })),
    );
    const positive = [...expected.entries()]
      .filter(([term]) => !['unclamped', 'color'].includes(term) && !/attenuation|spot/.test(term))
      .filter(([, rgb]) => rgb[c] > 0)
      .map(([term, rgb]) => ({ term, value: rgb[c] }));
    assert.deepEqual(segments, positive, channel);
  }
  // The unclamped sum beside the clamped colour.
  const colours = await result.locator('.colors .num').allTextContents();
  assert.deepEqual(colours, [breakdown.unclamped.map(shown).join(', '), probe.color.map(shown).join(', ')]);
});

await check('a probe by keyboard: x, y and Enter', async () => {
  await page.getByLabel('pixel x', { exact: true }).fill('5');
  await page.getByLabel('pixel y', { exact: true }).fill('3');
  await page.getByLabel('pixel y', { exact: true }).press('Enter');
  await page.waitForFunction(() => document.querySelector('#probe-result').dataset.pixel === '5,3');
  const { json } = await api({ ...scene, probes: [[5, 3]] });
  assert.equal(json.terms.probes[0].hit, null, 'the top-left corner sees the sky');
  assert.match(await page.locator('#probe-result').textContent(), /hits nothing/);
});

const lightThree = page.locator('[data-light="3"]');
const cutoffSlider = lightThree.getByLabel('Spot cutoff (degrees), slider', { exact: true });
const cutoffNumber = lightThree.getByLabel('Spot cutoff (degrees)', { exact: true });

await check('moving a control by keyboard sends a preview, then the full size, and changes the image', async () => {
  const before = await canvas.screenshot();
  const count = await drawn();
  const sentBefore = renders.length;
  await cutoffSlider.focus();
  for (let i = 0; i < 5; i += 1) await cutoffSlider.press('ArrowRight');
  await fullAfter(count);
  const sent = renders.slice(sentBefore);
  assert.ok(
    sent.some((r) => preview(r) && body(r).camera.width < scene.camera.width && body(r).lights[3].spot.cutoff > 40),
    'a smaller preview while it moved',
  );
  assert.ok(!preview(sent.at(-1)), 'the full size at rest');
  const last = body(sent.at(-1));
  assert.equal(last.camera.width, scene.camera.width);
  assert.equal(last.lights[3].spot.cutoff, 45);
  assert.equal(await cutoffNumber.inputValue(), '45');
  const after = await canvas.screenshot();
  assert.notDeepEqual(after, before, 'the image changed');
});

await check('a newer request aborts the one in flight: no backlog', async () => {
  const held = [];
  await page.route('**/v1/render', (route) => held.push(route));
  const sentBefore = renders.length;
  const failedBefore = failed.length;
  await cutoffSlider.focus();
  for (let i = 0; i < 4; i += 1) {
    const seen = held.length;
    await cutoffSlider.press('ArrowLeft');
    await waitFor(() => held.length > seen || renders.length > sentBefore + i, 'a request for each move');
  }
  // At rest, the full size is asked for: then every earlier one has been aborted.
  await waitFor(() => renders.slice(sentBefore).some((r) => !preview(r)), 'the full size at rest');
  const mine = () => renders.slice(sentBefore);
  await waitFor(() => failed.length - failedBefore >= mine().length - 1, 'the earlier requests aborted');
  const aborted = failed.slice(failedBefore);
  assert.ok(mine().length >= 2, `${mine().length} requests`);
  assert.deepEqual(
    aborted.map((f) => f.error),
    aborted.map(() => 'net::ERR_ABORTED'),
  );
  assert.deepEqual(new Set(aborted.map((f) => f.request)), new Set(mine().slice(0, -1)), 'every request but the newest was aborted');
  const count = await drawn();
  await page.unroute('**/v1/render');
  for (const route of held) await route.continue().catch(() => {});
  await fullAfter(count);
  assert.equal(body(mine().at(-1)).lights[3].spot.cutoff, 41);
});

async function waitFor(condition, what) {
  const until = Date.now() + WAIT;
  while (!condition()) {
    if (Date.now() > until) throw new Error(`timed out waiting for ${what}`);
    await new Promise((resolve) => setTimeout(resolve, 10));
  }
}

await check('a bad value shows the problem beside its control, and the page stays usable', async () => {
  const bad = structuredClone(scene);
  bad.lights[3].spot.cutoff = 120;
  const { status, json: problem } = await api(bad);
  assert.equal(status, 422);
  assert.equal(problem.pointer, '/lights/3/spot/cutoff');

  await cutoffNumber.fill('120');
  const output = lightThree.locator('output.problem:not([hidden])');
  await output.waitFor();
  assert.equal(await output.count(), 1);
  const text = await output.textContent();
  assert.ok(text.includes(problem.detail), text);
  assert.ok(text.includes(problem.pointer), text);
  // Beside its control: in the control's own field, and named by it.
  const [same, describedBy, invalid] = await cutoffNumber.evaluate((input) => {
    const out = input.closest('.field').querySelector('output.problem');
    return [!out.hidden, input.getAttribute('aria-describedby') === out.id, input.getAttribute('aria-invalid')];
  });
  assert.deepEqual([same, describedBy, invalid], [true, true, 'true']);
  assert.ok(await canvas.evaluate((c) => c.classList.contains('stale')));

  const count = await drawn();
  await cutoffNumber.fill('40');
  await fullAfter(count);
  assert.equal(await lightThree.locator('output.problem:not([hidden])').count(), 0);
  assert.equal(await page.locator('[aria-invalid="true"]').count(), 0);
  assert.ok(!(await canvas.evaluate((c) => c.classList.contains('stale'))));
});

await check('a malformed value (an empty number) is shown at its pointer too', async () => {
  const shininess = page.locator('[data-section="materials"]').getByLabel('Shininess', { exact: true });
  const bad = structuredClone(scene);
  bad.materials.floor.shininess = null;
  const { status, json: problem } = await api(bad);
  assert.equal(status, 400);
  await shininess.fill('');
  const output = page.locator('[data-section="materials"] output.problem:not([hidden])');
  await output.waitFor();
  assert.ok((await output.textContent()).includes(problem.detail));
  const count = await drawn();
  await shininess.fill(String(scene.materials.floor.shininess));
  await fullAfter(count);
  assert.equal(await page.locator('output.problem:not([hidden])').count(), 0);
});

await check('two tiers side by side, with their times, bounds and amplified difference', async () => {
  await page.getByLabel('Tier', { exact: true }).selectOption('fast');
  await page.getByLabel('against', { exact: true }).selectOption('reference');
  await page.getByLabel('Difference ×', { exact: true }).selectOption('255');
  await page.getByRole('button', { name: 'Compare now' }).click();
  await page.waitForFunction(() => document.querySelector('#compare').dataset.state === 'done');
  const fast = await api({ ...scene, precision: 'fast' });
  const reference = await api({ ...scene, precision: 'reference' });
  const figures = page.locator('#compare figure.tier');
  for (const [i, answer] of [fast, reference].entries()) {
    const figure = figures.nth(i);
    assert.equal(await figure.getAttribute('data-tier'), answer.json.precision.mode);
    assert.equal(Number(await figure.locator('.bound').getAttribute('data-value')), answer.json.precision.max_abs_error);
    assert.ok(Number(await figure.locator('.time').getAttribute('data-value')) > 0);
  }
  // The images are the API's, and the difference is theirs, amplified.
  const verdict = await page.evaluate(
    async ([a, b]) => {
      const pixels = async (base64) => {
        const bytes = Uint8Array.from(atob(base64), (c) => c.charCodeAt(0));
        const bitmap = await createImageBitmap(new Blob([bytes], { type: 'image/png' }));
        const canvas = new OffscreenCanvas(bitmap.width, bitmap.height);
        const context = canvas.getContext('2d');
        context.drawImage(bitmap, 0, 0);
        return context.getImageData(0, 0, bitmap.width, bitmap.height).data;
      };
      const shown = (canvas) => canvas.getContext('2d').getImageData(0, 0, canvas.width, canvas.height).data;
      const [fastPixels, referencePixels] = [await pixels(a), await pixels(b)];
      const canvases = [...document.querySelectorAll('#compare canvas')];
      const same = (x, y) => x.length === y.length && x.every((v, i) => v === y[i]);
      const diff = shown(canvases[2]);
      let largest = 0;
      let differing = 0;
      let amplified = true;
      for (let i = 0; i < fastPixels.length; i += 4) {
        let any = false;
        for (let c = 0; c < 3; c += 1) {
          const step = Math.abs(fastPixels[i + c] - referencePixels[i + c]);
          largest = Math.max(largest, step);
          any ||= step > 0;
          amplified &&= diff[i + c] === Math.min(255, step * 255);
        }
        if (any) differing += 1;
      }
      const figure = document.querySelector('#compare figure.difference');
      return {
        fast: same(shown(canvases[0]), fastPixels),
        reference: same(shown(canvases[1]), referencePixels),
        amplified,
        largest: Number(figure.dataset.largest) === largest,
        differing: Number(figure.dataset.differing) === differing,
        caption: figure.querySelector('figcaption').textContent,
        differs: differing,
      };
    },
    [fast.json.png_base64, reference.json.png_base64],
  );
  assert.deepEqual(
    { ...verdict, caption: undefined, differs: undefined },
    { fast: true, reference: true, amplified: true, largest: true, differing: true, caption: undefined, differs: undefined },
    JSON.stringify(verdict),
  );
  assert.match(verdict.caption, verdict.differs ? new RegExp(`${verdict.differs} of`) : /identical/);
});

await check('the screenshot at 1280×800, of the example at its own size', async () => {
  const resize = async ([width, height, samples]) => {
    const count = await drawn();
    await field('camera', 'Width (pixels)').fill(String(width));
    await field('camera', 'Height (pixels)').fill(String(height));
    await field('rendering', 'Samples per pixel').fill(String(samples));
    await fullAfter(count);
  };
  await resize([spheres.camera.width, spheres.camera.height, spheres.samples]);
  const box = await canvas.boundingBox();
  await canvas.click({ position: { x: box.width * 0.56, y: box.height * 0.62 } });
  await page.waitForFunction(() => !document.querySelector('#probe-result').hasAttribute('aria-busy') && document.querySelector('#probe-result table'));
  await page.evaluate(() => {
    document.activeElement?.blur();
    document.querySelector('#controls').scrollTop = 0;
    window.scrollTo(0, 0);
  });
  await page.screenshot({ path: SCREENSHOT });
  await resize([scene.camera.width, scene.camera.height, scene.samples]);
  assert.deepEqual(body(lastPicture()), scene);
});

/** Whether the shell found no curl to run a copied command with: said and
 * passed over here, a failure in CI, where the commands must run. */
function curlMissing(run) {
  const missing = run.error?.code === 'ENOENT' || run.status === 127;
  assert.ok(!(missing && process.env.CI === 'true'), `curl is missing, and CI runs the copied commands: ${run.stderr}`);
  return missing;
}

await check('"Copy as curl" gives the request the page just sent', async () => {
  await page.getByRole('button', { name: 'Copy as curl' }).click();
  const copied = await page.evaluate(() => navigator.clipboard.readText());
  assert.equal(copied, await page.locator('#curl').inputValue());
  const lastSent = renders.at(-1);
  assert.ok(copied.startsWith(`curl -s '${ORIGIN}/v1/render'`), copied.slice(0, 80));
  assert.ok(copied.includes(`-H 'accept: application/json'`));
  const data = copied.slice(copied.indexOf("--data-binary '") + "--data-binary '".length, -1).replaceAll(`'\\''`, "'");
  assert.deepEqual(JSON.parse(data), body(lastSent));
  // Pasted into a shell, it gets the same answer (where curl is installed).
  const run = spawnSync('sh', ['-c', copied], { encoding: 'utf8', timeout: WAIT, maxBuffer: 64 << 20 });
  if (curlMissing(run)) {
    console.log('     (no curl here: the command is not run)');
  } else {
    assert.equal(run.status, 0, run.stderr);
    const { json } = await api(body(lastSent));
    assert.deepEqual(JSON.parse(run.stdout).terms, json.terms);
  }
});

await check('the camera orbits by dragging, zooms by the wheel and orbits by keys', async () => {
  const distance = (camera) => Math.hypot(...camera.eye.map((c, i) => c - camera.target[i]));
  const original = distance(scene.camera);
  const box = await canvas.boundingBox();
  let count = await drawn();
  let sent = renders.length;
  await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
  await page.mouse.down();
  for (let i = 1; i <= 6; i += 1) await page.mouse.move(box.x + box.width / 2 + i * 15, box.y + box.height / 2 + i * 3);
  await page.mouse.up();
  await fullAfter(count);
  let camera = body(lastPicture()).camera;
  assert.notDeepEqual(camera.eye, scene.camera.eye);
  assert.ok(Math.abs(distance(camera) - original) < 1e-3, 'an orbit keeps the distance');
  assert.ok(renders.slice(sent).length >= 2, 'previews while dragging');
  assert.equal(await page.locator('[data-section="camera"]').getByLabel('x', { exact: true }).first().inputValue(), String(camera.eye[0]));

  count = await drawn();
  await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
  await page.mouse.wheel(0, 250);
  await fullAfter(count);
  const zoomed = body(lastPicture()).camera;
  assert.ok(distance(zoomed) > distance(camera) + 0.1, 'the wheel moves the eye away');

  count = await drawn();
  sent = renders.length;
  await canvas.focus();
  await page.keyboard.press('ArrowLeft');
  await fullAfter(count);
  camera = body(lastPicture()).camera;
  assert.notDeepEqual(camera.eye, zoomed.eye);
  assert.ok(Math.abs(distance(camera) - distance(zoomed)) < 1e-3);
});

await check('lights are added and removed, and change kind', async () => {
  const lights = page.locator('[data-section="lights"]');
  let count = await drawn();
  await lights.getByRole('button', { name: 'Add a light' }).click();
  await fullAfter(count);
  assert.equal(body(lastPicture()).lights.length, scene.lights.length + 1);
  const added = page.locator(`[data-light="${scene.lights.length}"]`);
  count = await drawn();
  await added.getByLabel('Kind').selectOption('spot');
  await fullAfter(count);
  const spot = body(lastPicture()).lights.at(-1);
  assert.equal(spot.position[3], 1);
  assert.ok(spot.spot.cutoff <= 90);
  count = await drawn();
  await added.getByLabel('Kind').selectOption('directional');
  await fullAfter(count);
  assert.equal(body(lastPicture()).lights.at(-1).position[3], 0);
  count = await drawn();
  await added.getByRole('button', { name: `Remove light ${scene.lights.length}` }).click();
  await fullAfter(count);
  assert.equal(body(lastPicture()).lights.length, scene.lights.length);
});

await check('the light model, materials and render options reach the request', async () => {
  const edits = [
    [() => field('light-model', 'Two-sided').check(), (b) => b.light_model.two_side === true],
    [() => field('light-model', 'Separate specular').check(), (b) => b.light_model.color_control === 'separate_specular'],
    [() => field('light-model', 'Specular model').selectOption('phong'), (b) => b.light_model.specular_model === 'phong'],
    [() => field('light-model', 'Attenuation clamped to 1').check(), (b) => b.light_model.attenuation_clamp === true],
    [() => field('light-model', 'Normalise normals').uncheck(), (b) => b.light_model.normalize_normals === false],
    [() => field('rendering', 'Precision').selectOption('fast'), (b) => b.precision === 'fast'],
    [() => field('rendering', 'Shading').selectOption('per_vertex'), (b) => b.shading === 'per_vertex'],
    [() => field('rendering', 'Shadows').uncheck(), (b) => b.shadows === false],
    [() => field('rendering', 'Samples per pixel').fill('1'), (b) => b.samples === 1],
    [() => field('materials', 'Edit material').selectOption('paint1'), null],
    [() => page.locator('[data-section="materials"] fieldset', { hasText: 'Emission' }).getByLabel('R', { exact: true }).fill('0.5'), (b) => b.materials.paint1.emission[0] === 0.5],
  ];
  for (const [edit, sent] of edits) {
    const count = await drawn();
    await edit();
    if (!sent) continue;
    await fullAfter(count);
    const last = body(lastPicture());
    assert.ok(sent(last), `${sent}: ${JSON.stringify(last).slice(0, 300)}`);
  }
});

await check('an error budget beside the tier: the cheapest tier within it, and a budget no tier keeps at its pointer', async () => {
  // Each tier's documented bound, as the API states it; the tiers from the
  // cheapest (docs/trade.md measures their speeds): fast, accurate, reference.
  const order = ['fast', 'accurate', 'reference'];
  const bounds = {};
  for (const tier of order) bounds[tier] = (await api({ ...scene, precision: tier })).json.precision.max_abs_error;
  const budget = bounds.accurate * 2;
  const expected = order.find((tier) => bounds[tier] <= budget);
  const budgetField = field('rendering', 'Error budget (max |error| per channel)');
  let count = await drawn();
  await field('rendering', 'Precision').selectOption({ label: 'an error budget' });
  await budgetField.fill(String(budget));
  await fullAfter(count);
  assert.deepEqual(body(lastPicture()).precision, { max_abs_error: budget });
  const status = await page.locator('#status').textContent();
  assert.ok(status.includes(`${expected} (the cheapest tier within the budget`), status);

  const tooSmall = bounds.reference / 2;
  const { status: code, json: problem } = await api({ ...scene, precision: { max_abs_error: tooSmall } });
  assert.equal(code, 422);
  assert.equal(problem.pointer, '/precision/max_abs_error');
  await budgetField.fill(String(tooSmall));
  const output = page.locator('[data-section="rendering"] output.problem:not([hidden])');
  await output.waitFor();
  assert.ok((await output.textContent()).includes(problem.detail));
  const describedBy = await budgetField.evaluate((input) => input.getAttribute('aria-describedby') === input.closest('.field').querySelector('output.problem').id);
  assert.ok(describedBy);

  count = await drawn();
  await field('rendering', 'Precision').selectOption('accurate');
  await fullAfter(count);
  assert.equal(body(lastPicture()).precision, 'accurate');
  assert.ok(await budgetField.isHidden());
});

await check('the other examples load and render', async () => {
  for (const name of ['mesh', 'triangle']) {
    const count = await drawn();
    await field('scene', 'Start from').selectOption(name);
    await fullAfter(count);
    const sent = body(lastPicture());
    const scene = example(name);
    if (name === 'mesh') {
      // As JSON has it (-0 is written 0).
      assert.equal(JSON.stringify(sent), JSON.stringify(scene));
    } else {
      // The shade example, as a mesh seen from GL's eye.
      assert.deepEqual(sent.objects[0].mesh.positions, scene.vertices.positions);
      assert.deepEqual(sent.objects[0].mesh.normals, scene.vertices.normals);
      assert.deepEqual(sent.lights, scene.lights);
      assert.deepEqual(sent.materials.material, scene.material);
      assert.deepEqual(sent.camera.eye, [0, 0, 0]);
    }
    assert.equal(await canvas.evaluate((c) => c.width), sent.camera.width);
  }
});

// A model of the person's own: GLINT_MODEL, given to the page through the
// file input and by a drop, rendered with the page's lighting and baked.

const modelBytes = readFileSync(MODEL);
const modelName = path.basename(MODEL);
const modelStem = modelName.replace(/\.glb$/i, '');
const MODEL_LABEL = 'Bake a model: drop a GLB on the picture, or choose one';
const modelInput = page.getByLabel(MODEL_LABEL, { exact: true });
const bakeLink = page.locator('#bake-link');

/** The JSON chunk and the BIN chunk of a GLB, its header checked. */
function readGlb(bytes) {
  assert.equal(bytes.toString('latin1', 0, 4), 'glTF');
  assert.equal(bytes.readUInt32LE(4), 2);
  assert.equal(bytes.readUInt32LE(8), bytes.length);
  const length = bytes.readUInt32LE(12);
  assert.equal(bytes.toString('latin1', 16, 20), 'JSON');
  const json = JSON.parse(bytes.toString('utf8', 20, 20 + length));
  const at = 20 + length;
  return { json, bin: at < bytes.length ? bytes.subarray(at + 8, at + 8 + bytes.readUInt32LE(at)) : Buffer.alloc(0) };
}

/** Sends a model to the API itself, as a form with `request`; the answer. */
async function apiModel(pathname, request, { accept = 'application/json', bytes = modelBytes, name = modelName } = {}) {
  const form = new FormData();
  form.append('request', new Blob([JSON.stringify(request)], { type: 'application/json' }));
  form.append('model', new Blob([bytes], { type: 'model/gltf-binary' }), name);
  return fetch(`${BASE}${pathname}`, { method: 'POST', body: form, headers: { accept }, signal: AbortSignal.timeout(WAIT) });
}

// The model's box as its own JSON says (POSITION's min and max, moved and
// scaled by its one node), which the page's camera must frame.
const tent = readGlb(modelBytes).json;
const tentNode = tent.nodes[0];
assert.equal(tentNode.rotation, undefined, 'the model is moved and scaled, not turned');
const tentPosition = tent.accessors[tent.meshes[0].primitives[0].attributes.POSITION];
const tentBox = [tentPosition.min, tentPosition.max].map((corner) => corner.map((c, k) => tentNode.translation[k] + tentNode.scale[k] * c));
const tentCenter = [0, 1, 2].map((k) => (tentBox[0][k] + tentBox[1][k]) / 2);

/** Checks that `camera` looks at the model's centre and sees every corner of its box. */
function framesTheModel(camera) {
  const sub = (a, b) => a.map((c, i) => c - b[i]);
  const dot = (a, b) => a.reduce((sum, c, i) => sum + c * b[i], 0);
  const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
  const unit = (a) => a.map((c) => c / Math.hypot(...a));
  camera.target.forEach((c, k) => assert.ok(Math.abs(c - tentCenter[k]) < 1e-3, `the target ${camera.target} is the centre ${tentCenter}`));
  const forward = unit(sub(camera.target, camera.eye));
  const right = unit(cross(forward, camera.up));
  const up = cross(right, forward);
  const tanY = Math.tan((camera.fov_y * Math.PI) / 360);
  const tanX = tanY * (camera.width / camera.height);
  for (let corner = 0; corner < 8; corner += 1) {
    const p = [0, 1, 2].map((k) => tentBox[(corner >> k) & 1][k]);
    const d = sub(p, camera.eye);
    const depth = dot(d, forward);
    assert.ok(depth > 0, `corner ${p} is in front of the eye`);
    assert.ok(Math.abs(dot(d, right) / depth) <= tanX && Math.abs(dot(d, up) / depth) <= tanY, `corner ${p} is in the picture`);
  }
}

/** The share of the view's pixels that are not the colour of its top-left one (the background). */
const lit = () =>
  canvas.evaluate((c) => {
    const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
    let n = 0;
    for (let i = 0; i < d.length; i += 4) if (d[i] !== d[0] || d[i + 1] !== d[1] || d[i + 2] !== d[2]) n += 1;
    return n / (d.length / 4);
  });

/** Waits until the download link offers a bake other than `before`'s URL. */
async function bakeReady(before = null) {
  await page.waitForFunction((old) => {
    const link = document.querySelector('#bake-link');
    return link.dataset.state === 'ready' && link.getAttribute('href') !== old;
  }, before);
}

/** The `request` part of the last bake sent, checked as a bake's form. */
function lastBake() {
  const request = shades.at(-1);
  assert.equal(request.headers().accept, 'model/gltf-binary');
  const form = parts(request);
  assert.deepEqual(Object.keys(form).sort(), ['model', 'request']);
  assert.equal(form.request.type, 'application/json');
  assert.equal(form.model.type, 'model/gltf-binary');
  assert.ok(form.model.bytes.equals(modelBytes), 'the bake\u2019s model part is the file, byte for byte');
  return { request, json: JSON.parse(form.request.bytes.toString('utf8')) };
}

/** The lighting of a render request, as its bake must send it: with its camera as the view. */
function lightingOf(render) {
  const lighting = {};
  for (const key of ['light_model', 'materials', 'back_material', 'lights', 'precision']) {
    if (render[key] !== undefined) lighting[key] = render[key];
  }
  const { eye, target, up } = render.camera;
  return { ...lighting, view: { eye, target, up } };
}

/** Clicks the download link; saves the file as OUT/`name`.glb beside the bake's request part; returns its bytes. */
async function download(name, request) {
  const [file] = await Promise.all([page.waitForEvent('download'), bakeLink.click()]);
  assert.equal(file.suggestedFilename(), `${modelStem}-baked.glb`);
  const saved = path.join(OUT, `${name}.glb`);
  await file.saveAs(saved);
  writeFileSync(path.join(OUT, `${name}.request.json`), JSON.stringify(request));
  return readFileSync(saved);
}

await check('a GLB chosen with the file input is rendered per vertex with the page\u2019s lighting, sent as a form', async () => {
  // The spheres' lights (a spot among them, and a local viewer) light the model, at a smaller size.
  let count = await drawn();
  await field('scene', 'Start from').selectOption('spheres');
  await fullAfter(count);
  count = await drawn();
  await field('camera', 'Width (pixels)').fill('320');
  await field('camera', 'Height (pixels)').fill('180');
  await field('rendering', 'Samples per pixel').fill('1');
  await fullAfter(count);
  const before = body(lastPicture());
  const shot = await canvas.screenshot();

  count = await drawn();
  const sentBefore = renders.length;
  await modelInput.setInputFiles(MODEL);
  await fullAfter(count);
  const mine = renders.slice(sentBefore);
  assert.ok(mine.length >= 2, 'a preview, then the full size');
  assert.ok(mine.every(isForm), 'every render of the model is a form');
  const last = mine.at(-1);
  assert.ok(!preview(last));
  const form = parts(last);
  assert.deepEqual(Object.keys(form).sort(), ['model', 'request']);
  assert.equal(form.request.type, 'application/json');
  assert.equal(form.model.type, 'model/gltf-binary');
  assert.equal(form.model.filename, modelName);
  assert.ok(form.model.bytes.equals(modelBytes), 'the model part is the file, byte for byte');

  // The page's lighting and options, per vertex, no objects, the model's own materials, a camera on the model.
  const sent = body(last);
  assert.equal(sent.shading, 'per_vertex');
  assert.equal(sent.objects, undefined);
  assert.equal(sent.materials, undefined);
  for (const key of ['light_model', 'lights', 'background', 'samples', 'shadows', 'precision', 'encoding']) {
    assert.deepEqual(sent[key], before[key], key);
  }
  assert.deepEqual([sent.camera.width, sent.camera.height, sent.camera.fov_y], [320, 180, before.camera.fov_y]);
  framesTheModel(sent.camera);

  // The picture is the model: it changed, and is not the background alone.
  assert.notDeepEqual(await canvas.screenshot(), shot, 'the image changed');
  const share = await lit();
  assert.ok(share > 0.02, `the model covers ${share} of the picture`);
  // The render's warnings (those of the model's mapping among them) as the API gave them.
  const answer = await (await last.response()).json();
  assert.ok(answer.warnings.some((w) => w.code === 'pbr_approximated'), JSON.stringify(answer.warnings));
  assert.deepEqual(await page.locator('#warnings li').allTextContents(), answer.warnings.map((w) => `${w.code}: ${w.detail}`));
  // Its name, and the way back.
  assert.match(await page.locator('#model-about').textContent(), new RegExp(modelName.replace('.', '\\.')));
  assert.ok(await page.getByRole('button', { name: 'Remove the model' }).isVisible());
  await everyControlLabelled();

  // A probe of the model: the API's numbers for the same form.
  const box = await canvas.boundingBox();
  await canvas.click({ position: { x: box.width / 2, y: box.height / 2 } });
  const [x, y] = [Math.floor(sent.camera.width / 2), Math.floor(sent.camera.height / 2)];
  await page.waitForFunction((p) => document.querySelector('#probe-result').dataset.pixel === p && document.querySelector('#probe-result table'), `${x},${y}`);
  const probe = (await (await apiModel('/v1/render', { ...sent, probes: [[x, y]] })).json()).terms.probes[0];
  assert.ok(probe.hit, 'the middle of the picture is the model');
  assert.match(await page.locator('#probe-result .hit').textContent(), /a mesh of the model/);
  const color = await page.locator('#probe-result tr[data-term="color"] td[data-value]').evaluateAll((tds) => tds.map((td) => Number(td.dataset.value)));
  assert.deepEqual(color, probe.color);
});

await check('the bake of the lighting shown is a download: a GLB whose primitives carry COLOR_0', async () => {
  await bakeReady();
  const { request, json } = lastBake();
  assert.equal(json.vertices, undefined);
  assert.deepEqual(json, lightingOf(body(renders.filter((r) => !preview(r)).at(-1))));
  assert.equal(await bakeLink.getAttribute('download'), `${modelStem}-baked.glb`);
  assert.match(await bakeLink.getAttribute('href'), /^blob:/);
  const bytes = await download('tent-baked', json);
  assert.ok(bytes.equals(await (await request.response()).body()), 'the download is the answer to the bake');
  const baked = readGlb(bytes).json;
  for (const mesh of baked.meshes) {
    for (const primitive of mesh.primitives) assert.equal(typeof primitive.attributes.COLOR_0, 'number', JSON.stringify(primitive));
  }
  // What the bake says of the model is on the page: in the render's warnings, or beside the link.
  const shownWarnings = [...(await page.locator('#warnings li').allTextContents()), ...(await page.locator('#bake-warnings li').allTextContents())];
  const warnings = baked.extras.glint.warnings.map((w) => `${w.code}: ${w.detail}`);
  assert.ok(warnings.length > 0);
  for (const warning of warnings) assert.ok(shownWarnings.includes(warning), warning);
});

await check('moving a light re-renders the model and makes its bake again', async () => {
  const href = await bakeLink.getAttribute('href');
  const shot = await canvas.screenshot();
  const count = await drawn();
  const x = page.locator('[data-light="0"] fieldset.triple').first().getByLabel('x', { exact: true });
  await x.fill('-3');
  assert.notEqual(await bakeLink.getAttribute('data-state'), 'ready', 'the old bake is not offered for the new lighting');
  await fullAfter(count);
  const sent = body(renders.filter((r) => !preview(r)).at(-1));
  assert.equal(sent.lights[0].position[0], -3);
  assert.notDeepEqual(await canvas.screenshot(), shot, 'the image changed');
  await bakeReady(href);
  assert.deepEqual(lastBake().json, lightingOf(sent));
});

await check('a GL material of the page\u2019s own starts as the model\u2019s mapping, and reaches the render and the bake', async () => {
  const fullRenders = () => renders.filter((r) => !preview(r) && !body(r).probes);
  const before = fullRenders().at(-1);
  let count = await drawn();
  await field('materials', 'A GL material of my own').check();
  await fullAfter(count);
  let last = fullRenders().at(-1);
  let sent = body(last);
  assert.deepEqual(Object.keys(sent.materials), ['#0']);
  assert.deepEqual(sent.materials['#0'].diffuse, tent.materials[0].pbrMetallicRoughness.baseColorFactor);
  // The contract's mapping, now sent: the same picture.
  const [a, b] = [await (await before.response()).json(), await (await last.response()).json()];
  assert.equal(a.png_base64, b.png_base64, 'the same picture with the mapping sent as the page\u2019s own');
  assert.ok(!b.warnings.some((w) => w.code === 'pbr_approximated'), 'no material left to map');

  const href = await bakeLink.getAttribute('href');
  count = await drawn();
  const diffuse = page.locator('[data-section="materials"] fieldset', { hasText: 'Diffuse' });
  await diffuse.getByLabel('G', { exact: true }).fill('0.9');
  await fullAfter(count);
  last = fullRenders().at(-1);
  sent = body(last);
  assert.equal(sent.materials['#0'].diffuse[1], 0.9);
  await bakeReady(href);
  const { json } = lastBake();
  assert.deepEqual(json, lightingOf(sent));
  await download('tent-baked-own', json);
});

await check('"Copy as curl" of a form: the JSON on stdin, the model from its file, the same answers', async () => {
  await page.getByRole('button', { name: 'Copy as curl' }).click();
  const copied = await page.evaluate(() => navigator.clipboard.readText());
  assert.equal(copied, await page.locator('#curl').inputValue());
  const lastSent = renders.at(-1);
  assert.ok(copied.startsWith(`curl -s '${ORIGIN}/v1/render'`), copied.slice(0, 80));
  assert.ok(copied.includes(`-F 'request=<-;type=application/json'`), copied);
  assert.ok(copied.includes(`-F 'model=@${modelName};type=model/gltf-binary'`), copied);
  const json = copied.slice(copied.indexOf("<<'JSON'\n") + "<<'JSON'\n".length, copied.lastIndexOf('\nJSON'));
  assert.deepEqual(JSON.parse(json), body(lastSent));
  assert.ok(copied.endsWith('\nJSON'));

  await page.getByRole('button', { name: 'Copy the bake as curl' }).click();
  const bakeCurl = await page.evaluate(() => navigator.clipboard.readText());
  assert.ok(bakeCurl.startsWith(`curl -s '${ORIGIN}/v1/shade'`), bakeCurl.slice(0, 80));
  assert.ok(bakeCurl.includes(`-H 'accept: model/gltf-binary'`) && bakeCurl.includes(`-o '${modelStem}-baked.glb'`), bakeCurl);

  // Pasted into a shell beside the model, they get the same answers (where curl is installed).
  const dir = mkdtempSync(path.join(os.tmpdir(), 'glint-playground-'));
  try {
    copyFileSync(MODEL, path.join(dir, modelName));
    const run = spawnSync('sh', ['-c', copied], { cwd: dir, encoding: 'utf8', timeout: WAIT, maxBuffer: 64 << 20 });
    if (curlMissing(run)) {
      console.log('     (no curl here: the commands are not run)');
      return;
    }
    assert.equal(run.status, 0, run.stderr);
    const answer = await (await lastSent.response()).json();
    const pasted = JSON.parse(run.stdout);
    assert.deepEqual(pasted.terms, answer.terms);
    assert.deepEqual(pasted.warnings, answer.warnings);
    const bake = spawnSync('sh', ['-c', bakeCurl], { cwd: dir, encoding: 'utf8', timeout: WAIT });
    assert.equal(bake.status, 0, bake.stderr);
    const file = path.join(dir, `${modelStem}-baked.glb`);
    assert.ok(existsSync(file), 'the bake is written to its file');
    // The colours of the download, in the same buffer: the same bake (its JSON differs by the times it states).
    assert.ok(readGlb(readFileSync(file)).bin.equals(readGlb(readFileSync(path.join(OUT, 'tent-baked-own.glb'))).bin));
  } finally {
    rmSync(dir, { recursive: true, force: true });
  }
});

await check('one real drop: a GLB dropped on the picture is the model', async () => {
  const count = await drawn();
  const href = await bakeLink.getAttribute('href');
  const dataTransfer = await page.evaluateHandle(
    ([bytes, name]) => {
      const transfer = new DataTransfer();
      transfer.items.add(new File([new Uint8Array(bytes)], name));
      return transfer;
    },
    [[...modelBytes], 'dropped.glb'],
  );
  for (const type of ['dragenter', 'dragover']) await canvas.dispatchEvent(type, { dataTransfer });
  assert.ok(await page.locator('.stage').evaluate((stage) => stage.classList.contains('dropping')), 'the picture says it takes the drop');
  await canvas.dispatchEvent('drop', { dataTransfer });
  await fullAfter(count);
  assert.ok(!(await page.locator('.stage').evaluate((stage) => stage.classList.contains('dropping'))));
  const form = parts(lastPicture());
  assert.equal(form.model.filename, 'dropped.glb');
  assert.equal(form.model.type, 'model/gltf-binary');
  assert.ok(form.model.bytes.equals(modelBytes));
  const sent = body(lastPicture());
  assert.equal(sent.materials, undefined, 'a new model starts with its own materials');
  framesTheModel(sent.camera);
  assert.match(await page.locator('#model-about').textContent(), /dropped\.glb/);
  assert.ok((await lit()) > 0.02);
  await bakeReady(href);
  assert.equal(await bakeLink.getAttribute('download'), 'dropped-baked.glb');
});

await check('a file that is no GLB: the server\u2019s problem is shown, and removing it brings the example back', async () => {
  const notes = Buffer.from('the notes of a person, not a model\n');
  const refused = await apiModel('/v1/render', body(lastPicture()), { bytes: notes, name: 'notes.glb' });
  assert.equal(refused.status, 400);
  const problem = await refused.json();
  assert.equal(problem.pointer, '/model');

  await modelInput.setInputFiles({ name: 'notes.glb', mimeType: 'application/octet-stream', buffer: notes });
  const output = page.locator('#model-problem:not([hidden])');
  await output.waitFor();
  const text = await output.textContent();
  assert.ok(text.includes(problem.detail) && text.includes('/model'), text);
  assert.ok(await canvas.evaluate((c) => c.classList.contains('stale')));
  assert.notEqual(await bakeLink.getAttribute('data-state'), 'ready');
  assert.match(await page.locator('#status').textContent(), /refused the request \(400\)/);

  const count = await drawn();
  await page.getByRole('button', { name: 'Remove the model' }).click();
  await fullAfter(count);
  const last = lastPicture();
  assert.ok(!isForm(last));
  assert.deepEqual(body(last), spheres);
  assert.ok(await page.locator('#model-loaded').isHidden());
  assert.ok(await page.locator('#model-problem').isHidden());
  assert.ok(!(await canvas.evaluate((c) => c.classList.contains('stale'))));
  assert.equal(await field('scene', 'Start from').inputValue(), 'spheres');
  assert.equal(await modelInput.inputValue(), '');
});

/** POSTs `image` with `request` to /v1/compare as the contract's form, as a client of the API would. */
async function compareForm(request, image) {
  const form = new FormData();
  form.append('request', new Blob([JSON.stringify(request)], { type: 'application/json' }));
  form.append('image', new Blob([image], { type: 'image/png' }), 'candidate.png');
  const response = await fetch(`${BASE}/v1/compare`, {
    method: 'POST',
    headers: { accept: 'application/json' },
    body: form,
    signal: AbortSignal.timeout(WAIT),
  });
  return { status: response.status, json: await response.json() };
}

/** The PNG the API renders for `request`. */
async function png(request) {
  const response = await fetch(`${BASE}/v1/render`, {
    method: 'POST',
    headers: { 'content-type': 'application/json', accept: 'image/png' },
    body: JSON.stringify(request),
    signal: AbortSignal.timeout(WAIT),
  });
  assert.equal(response.status, 200);
  return Buffer.from(await response.arrayBuffer());
}

await check('a PNG from another renderer: the error, the heatmap over it, the worst pixels and the diagnosis the API gives', async () => {
  // The page's scene, and a renderer that lights it with Phong's (r·v)^s
  // where GL uses (n·h)^s: the scene rendered with the phong option.
  const shown = body(renders.at(-1));
  const candidate = await png({ ...shown, light_model: { ...shown.light_model, specular_model: 'phong' } });
  const expected = await compareForm(shown, candidate);
  assert.equal(expected.status, 200, JSON.stringify(expected.json));

  const sentCompare = page.waitForRequest((r) => new URL(r.url()).pathname === '/v1/compare');
  await page.locator('#candidate-file').setInputFiles({ name: 'mine.png', mimeType: 'image/png', buffer: candidate });
  const request = await sentCompare;
  await page.waitForFunction(() => document.querySelector('#candidate').dataset.state === 'done');
  const form = parts(request);
  assert.deepEqual(JSON.parse(form.request.bytes.toString('utf8')), shown);
  assert.equal(form.image.type, 'image/png');
  assert.ok(form.image.bytes.equals(candidate), 'the image part is the file');

  const panel = page.locator('#candidate');
  const value = async (key) => panel.locator(`.figures [data-key="${key}"]`).getAttribute('data-value');
  assert.equal(Number(await value('max_abs')), Number(expected.json.error.max_abs.toPrecision(3)));
  assert.equal(await value('within_bound'), expected.json.error.within_bound ? 'yes' : 'no');
  const ranked = await panel.locator('.diagnosis li').evaluateAll((items) => items.map((li) => li.dataset.deviations));
  assert.deepEqual(ranked, expected.json.diagnosis.map((d) => d.deviations.join('+')));
  assert.equal(expected.json.diagnosis[0].deviations.join('+'), 'phong_specular');
  assert.equal(await panel.locator('.diagnosis li').first().getAttribute('data-explains'), 'true');
  // The heatmap is drawn over the candidate: the canvas is the image's size
  // and not the candidate alone.
  const drawnSize = await panel.locator('canvas.candidate-image').evaluate((c) => [c.width, c.height]);
  assert.deepEqual(drawnSize, [shown.camera.width, shown.camera.height]);
  assert.ok(expected.json.heatmap_png_base64.length > 0);

  const [x, y] = expected.json.worst[0].pixel;
  await panel.locator('.worst button').first().click();
  await page.waitForFunction(([px, py]) => document.querySelector('#probe-x').value === String(px) && document.querySelector('#probe-y').value === String(py), [x, y]);

  // A PNG of another size is the API's problem, shown in the panel.
  const small = await png({ ...shown, camera: { ...shown.camera, width: 16, height: 9 } });
  const refused = await compareForm(shown, small);
  assert.ok(refused.status === 422 || refused.status === 400, String(refused.status));
  await page.locator('#candidate-file').setInputFiles({ name: 'small.png', mimeType: 'image/png', buffer: small });
  const problem = panel.locator('#candidate-problem');
  await problem.waitFor();
  assert.ok((await problem.textContent()).includes(refused.json.detail));
});

await check('keyboard: Tab reaches the picture, the controls, the model, the probe, the comparison and the candidate', async () => {
  await page.evaluate(() => document.activeElement?.blur());
  const reached = new Set();
  for (let i = 0; i < 400 && reached.size < 7; i += 1) {
    await page.keyboard.press('Tab');
    const id = await page.evaluate(() => {
      const a = document.activeElement;
      if (['view', 'copy-curl', 'compare-now', 'model-file', 'candidate-file'].includes(a.id)) return a.id;
      if (a.closest('#probe-form')) return 'probe';
      if (a.closest('#controls')) return 'controls';
      return null;
    });
    if (id) reached.add(id);
  }
  assert.deepEqual([...reached].sort(), ['candidate-file', 'compare-now', 'controls', 'copy-curl', 'model-file', 'probe', 'view']);
});

await check('the layout at 1280×800 and on a narrow window', async () => {
  const layout = () =>
    page.evaluate(() => {
      const box = (s) => document.querySelector(s).getBoundingClientRect().toJSON();
      return {
        scroll: document.documentElement.scrollWidth,
        width: innerWidth,
        controls: box('#controls'),
        view: box('#view'),
        probe: box('#probe'),
      };
    });
  const overlap = (a, b) => a.left < b.right && b.left < a.right && a.top < b.bottom && b.top < a.bottom;
  let l = await layout();
  assert.ok(l.scroll <= l.width, `no sideways scroll at 1280: ${l.scroll}`);
  assert.ok(!overlap(l.controls, l.view) && !overlap(l.view, l.probe) && !overlap(l.controls, l.probe));
  assert.ok(l.view.bottom <= 800 && l.view.width >= 400, 'the picture is on screen');
  await page.setViewportSize({ width: 390, height: 800 });
  l = await layout();
  assert.ok(l.scroll <= l.width, `no sideways scroll at 390: ${l.scroll}`);
  assert.ok(l.view.width > 300 && l.view.right <= l.width, 'the picture fits');
  assert.ok(l.controls.width > 300 && l.controls.right <= l.width, 'the controls fit');
  await page.setViewportSize({ width: 1280, height: 800 });
});

await check('no console error, no request to another host, no failure but aborts', async () => {
  // Chromium logs each answer with a problem status; those of the bad values asked for are the only errors.
  const logged = consoleErrors.map((text) => Number(/^Failed to load resource: the server responded with a status of (4\d\d)\b/.exec(text)?.[1]));
  assert.ok(problems.length > 0);
  assert.deepEqual(logged.filter((status) => !problems.includes(status)), [], consoleErrors.join('\n'));
  assert.ok(logged.length <= problems.length, consoleErrors.join('\n'));
  assert.deepEqual(elsewhere, []);
  assert.deepEqual(
    failed.filter((f) => f.error !== 'net::ERR_ABORTED').map((f) => `${f.url}: ${f.error}`),
    [],
  );
});

await browser.close();
console.log('playground: every check passed');
