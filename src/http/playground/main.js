// The playground: wires the request being edited, the form, the picture,
// the tier comparison and the probe together. Everything it asks goes to
// the public API of the server that served it.

import { Controls } from './controls.js';
import { el, fixed } from './dom.js';
import { showProbe } from './probe.js';
import { Comparison, Renderer, View, postRender, sent } from './render.js';
import { EXAMPLES, loadExample, orbit, previewOf, probeOf, toCurl, withTier, zoom } from './request.js';

const $ = (selector) => document.querySelector(selector);

let scene = null;
let last = null;
let probeController = null;
let probed = null;

const status = $('#status');
const say = (text) => (status.textContent = text);

const view = new View($('#view'), $('#marker'), {
  onOrbit(yaw, pitch) {
    if (!scene) return;
    scene.camera = orbit(scene.camera, yaw, pitch);
    controls.refreshCamera();
    renderer.moving();
  },
  onZoom(factor) {
    if (!scene) return;
    scene.camera = zoom(scene.camera, factor);
    controls.refreshCamera();
    renderer.moving();
  },
  onSettle: () => renderer.full(),
  onPick: (x, y) => probe(x, y),
});

const renderer = new Renderer(view, {
  request: () => scene,
  previewOf,
  onDrawn({ kind, json, ms, width, height }) {
    controls.clearProblems();
    view.stale(false);
    if (kind === 'preview') {
      say(`Preview ${width}\u00d7${height}, one sample: the round trip took ${fixed(ms, 0)} ms; the full size follows when the controls rest.`);
      return;
    }
    const { stats } = json;
    say(
      `Full size ${width}\u00d7${height}, ${stats.samples} sample${stats.samples > 1 ? 's' : ''}, ` +
        `${json.precision.mode}: the server took ${fixed(stats.compute_ms, 1)} ms (tracing and lighting ${fixed(stats.render_ms, 1)} ms), ` +
        `the round trip ${fixed(ms, 0)} ms.`,
    );
    $('#warnings').replaceChildren(...json.warnings.map((w) => el('li', { text: `${w.code}: ${w.detail}` })));
    if (probed) probe(...probed);
    if ($('#comparing').checked) comparison.run();
  },
  onProblem(problem) {
    view.stale(true);
    controls.showProblem(problem);
    say(`The server refused the request (${problem.status}); the picture is the last one it drew. ${problem.detail ?? ''}`);
  },
  onError(error) {
    view.stale(true);
    say(`The request failed: ${error.message}`);
  },
});

const controls = new Controls($('#controls'), {
  onEdit: (how) => (how === 'moving' ? renderer.moving() : renderer.full()),
  onExample: (name) => start(name),
});

const comparison = new Comparison($('#compare'), {
  request: () => scene,
  withTier,
  onProblem(problem) {
    const output = $('#compare-problem');
    output.textContent = `${problem.title ?? 'Problem'}: ${problem.detail ?? ''}`;
    output.hidden = false;
  },
});
$('#compare-form').addEventListener('submit', (event) => {
  event.preventDefault();
  $('#compare-problem').hidden = true;
  if (scene) comparison.run();
});
$('#comparing').addEventListener('input', (event) => {
  if (event.target.checked && scene) comparison.run();
});

/** Explains pixel (x, y) of the full image with a probe of the API. */
async function probe(x, y) {
  if (!scene) return;
  probed = [x, y];
  $('#probe-x').value = String(x);
  $('#probe-y').value = String(y);
  view.mark(x, y);
  probeController?.abort();
  const controller = new AbortController();
  probeController = controller;
  const result$ = $('#probe-result');
  const problem$ = $('#probe-problem');
  result$.setAttribute('aria-busy', 'true');
  try {
    const result = await postRender(probeOf(scene, x, y), { signal: controller.signal, purpose: 'probe' });
    if (!result.ok) {
      problem$.textContent = `${result.problem.title}: ${result.problem.detail}`;
      problem$.hidden = false;
      if (result.problem.pointer && !result.problem.pointer.startsWith('/probes') && !result.problem.pointer.startsWith('/region')) {
        controls.showProblem(result.problem);
      }
      return;
    }
    problem$.hidden = true;
    showProbe(result$, result.json, scene);
  } catch (error) {
    if (error.name !== 'AbortError') {
      problem$.textContent = `The probe failed: ${error.message}`;
      problem$.hidden = false;
    }
  } finally {
    if (probeController === controller) {
      probeController = null;
      result$.removeAttribute('aria-busy');
    }
  }
}

$('#probe-form').addEventListener('submit', (event) => {
  event.preventDefault();
  const x = $('#probe-x').valueAsNumber;
  const y = $('#probe-y').valueAsNumber;
  probe(Number.isFinite(x) ? x : 0, Number.isFinite(y) ? y : 0);
});

// "Copy as curl": the request the page sent last, as a command to paste.
sent.addEventListener('request', (event) => {
  last = event.detail;
  const curl = $('#curl');
  curl.value = toCurl(last.url, last.body, last.accept);
  curl.dataset.purpose = last.purpose;
});
$('#copy-curl').addEventListener('click', async () => {
  const curl = $('#curl');
  if (!last) return say('Nothing has been sent yet.');
  try {
    await navigator.clipboard.writeText(curl.value);
    say(`The ${last.purpose} request is on the clipboard as a curl command.`);
  } catch {
    curl.closest('details').open = true;
    curl.focus();
    curl.select();
    say('The clipboard is not available here: the command is selected below.');
  }
});

/** Loads an example and renders it. */
async function start(name) {
  say(`Loading the example \u201c${name}\u201d\u2026`);
  try {
    scene = await loadExample(name);
  } catch (error) {
    say(error.message);
    return;
  }
  probed = null;
  $('#marker').hidden = true;
  $('#probe-result').replaceChildren(el('p', { class: 'hint', text: 'Click a pixel of the render, or give its x and y.' }));
  controls.show(scene, name);
  renderer.start();
}

start(EXAMPLES[0].name);
