// The playground in headless Chromium, against a running glint: each check
// of issue "The playground" as a person would meet it, every number compared
// with the API's own answer to the same request.
//
//   GLINT_BASE=http://127.0.0.1:8080 GLINT_PLAYWRIGHT_DIR=target/tools/playwright \
//   GLINT_EXAMPLES=examples GLINT_SCREENSHOT=target/playground/playground.png \
//   node tests/playground/e2e.mjs
//
// Every wait is bounded and waits for a condition, never for a time. It
// prints one line per check and exits non-zero at the first that fails.

import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import { readFileSync } from 'node:fs';
import path from 'node:path';

import { launch } from './browser.mjs';

const BASE = process.env.GLINT_BASE;
const EXAMPLES = process.env.GLINT_EXAMPLES;
const SCREENSHOT = process.env.GLINT_SCREENSHOT;
assert.ok(BASE && EXAMPLES && SCREENSHOT && process.env.GLINT_PLAYWRIGHT_DIR, 'GLINT_BASE, GLINT_EXAMPLES, GLINT_SCREENSHOT and GLINT_PLAYWRIGHT_DIR are needed');
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
page.on('console', (message) => {
  if (message.type() === 'error') consoleErrors.push(message.text());
});
page.on('pageerror', (error) => consoleErrors.push(String(error)));
page.on('request', (request) => {
  const url = new URL(request.url());
  if (url.origin !== ORIGIN && url.protocol !== 'data:' && url.protocol !== 'blob:') elsewhere.push(request.url());
  if (url.pathname === '/v1/render') renders.push(request);
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
const body = (request) => JSON.parse(request.postData());
/** A preview asks for the PNG alone; a full render for the JSON form. */
const preview = (request) => request.headers().accept === 'image/png';
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
  assert.deepEqual(body(renders.at(-1)), scene);
  assert.equal(await canvas.evaluate((c) => `${c.width}x${c.height}`), '320x180');
});

await check('every control has a label', async () => {
  const unlabelled = await page.evaluate(() =>
    [...document.querySelectorAll('input, select, textarea, button')]
      .filter((c) => !(c.labels?.length > 0 || c.getAttribute('aria-label') || (c.tagName === 'BUTTON' && c.textContent.trim())))
      .map((c) => c.outerHTML),
  );
  assert.deepEqual(unlabelled, []);
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
  assert.deepEqual(body(renders.at(-1)), scene);
});

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
  if (run.error?.code === 'ENOENT' || run.status === 127) {
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
  let camera = body(renders.at(-1)).camera;
  assert.notDeepEqual(camera.eye, scene.camera.eye);
  assert.ok(Math.abs(distance(camera) - original) < 1e-3, 'an orbit keeps the distance');
  assert.ok(renders.slice(sent).length >= 2, 'previews while dragging');
  assert.equal(await page.locator('[data-section="camera"]').getByLabel('x', { exact: true }).first().inputValue(), String(camera.eye[0]));

  count = await drawn();
  await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
  await page.mouse.wheel(0, 250);
  await fullAfter(count);
  const zoomed = body(renders.at(-1)).camera;
  assert.ok(distance(zoomed) > distance(camera) + 0.1, 'the wheel moves the eye away');

  count = await drawn();
  sent = renders.length;
  await canvas.focus();
  await page.keyboard.press('ArrowLeft');
  await fullAfter(count);
  camera = body(renders.at(-1)).camera;
  assert.notDeepEqual(camera.eye, zoomed.eye);
  assert.ok(Math.abs(distance(camera) - distance(zoomed)) < 1e-3);
});

await check('lights are added and removed, and change kind', async () => {
  const lights = page.locator('[data-section="lights"]');
  let count = await drawn();
  await lights.getByRole('button', { name: 'Add a light' }).click();
  await fullAfter(count);
  assert.equal(body(renders.at(-1)).lights.length, scene.lights.length + 1);
  const added = page.locator(`[data-light="${scene.lights.length}"]`);
  count = await drawn();
  await added.getByLabel('Kind').selectOption('spot');
  await fullAfter(count);
  const spot = body(renders.at(-1)).lights.at(-1);
  assert.equal(spot.position[3], 1);
  assert.ok(spot.spot.cutoff <= 90);
  count = await drawn();
  await added.getByLabel('Kind').selectOption('directional');
  await fullAfter(count);
  assert.equal(body(renders.at(-1)).lights.at(-1).position[3], 0);
  count = await drawn();
  await added.getByRole('button', { name: `Remove light ${scene.lights.length}` }).click();
  await fullAfter(count);
  assert.equal(body(renders.at(-1)).lights.length, scene.lights.length);
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
    const last = body(renders.at(-1));
    assert.ok(sent(last), `${sent}: ${JSON.stringify(last).slice(0, 300)}`);
  }
});

await check('the other examples load and render', async () => {
  for (const name of ['mesh', 'triangle']) {
    const count = await drawn();
    await field('scene', 'Start from').selectOption(name);
    await fullAfter(count);
    const sent = body(renders.at(-1));
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

await check('keyboard: Tab reaches the picture, the controls, the probe and the comparison', async () => {
  await page.evaluate(() => document.activeElement?.blur());
  const reached = new Set();
  for (let i = 0; i < 400 && reached.size < 5; i += 1) {
    await page.keyboard.press('Tab');
    const id = await page.evaluate(() => {
      const a = document.activeElement;
      if (a.id === 'view' || a.id === 'copy-curl' || a.id === 'compare-now') return a.id;
      if (a.closest('#probe-form')) return 'probe';
      if (a.closest('#controls')) return 'controls';
      return null;
    });
    if (id) reached.add(id);
  }
  assert.deepEqual([...reached].sort(), ['compare-now', 'controls', 'copy-curl', 'probe', 'view']);
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
