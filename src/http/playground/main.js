// The playground: wires the request being edited, the form, the picture,
// the tier comparison, the probe, a dropped model with its bake and a
// candidate image compared with GL together. Everything it asks goes to the public API of the server that
// served it.

import { CandidatePanel } from './candidate.js';
import { Controls } from './controls.js';
import { el, fixed } from './dom.js';
import { bake, modelMaterials, modelScene, readModel, stem } from './model.js';
import { showProbe } from './probe.js';
import { Comparison, Renderer, View, announce, postRender, sent } from './render.js';
import { EXAMPLES, loadExample, orbit, previewOf, probeOf, toCurl, withTier, zoom } from './request.js';

const $ = (selector) => document.querySelector(selector);

let scene = null;
let last = null;
let probeController = null;
let probed = null;
/** The example shown, or shown before the model. */
let example = EXAMPLES[0].name;
/** The model dropped or chosen (see model.js), while it is shown. */
let model = null;
let lastBake = null;
/** The warnings of the last full render, which a bake's need not repeat. */
let renderWarnings = [];
let bakeController = null;
let bakeUrl = null;

const status = $('#status');
const say = (text) => (status.textContent = text);

const view = new View($('#view'), $('#marker'), {
  onOrbit(yaw, pitch) {
    if (!scene) return;
    scene.camera = orbit(scene.camera, yaw, pitch);
    controls.refreshCamera();
    bakeIsStale();
    renderer.moving();
  },
  onZoom(factor) {
    if (!scene) return;
    scene.camera = zoom(scene.camera, factor);
    controls.refreshCamera();
    bakeIsStale();
    renderer.moving();
  },
  onSettle: () => renderer.full(),
  onPick: (x, y) => probe(x, y),
});

const renderer = new Renderer(view, {
  request: () => scene,
  model: () => model,
  previewOf,
  onDrawn({ kind, json, ms, width, height }) {
    controls.clearProblems();
    $('#model-problem').hidden = true;
    view.stale(false);
    if (kind === 'preview') {
      say(`Preview ${width}\u00d7${height}, one sample: the round trip took ${fixed(ms, 0)} ms; the full size follows when the controls rest.`);
      return;
    }
    const { stats } = json;
    say(
      `Full size ${width}\u00d7${height}, ${stats.samples} sample${stats.samples > 1 ? 's' : ''}, ` +
        `${json.precision.mode}${typeof scene.precision === 'object' ? ` (the cheapest tier within the budget; its bound ${Number(json.precision.max_abs_error.toPrecision(3))})` : ''}: the server took ${fixed(stats.compute_ms, 1)} ms (tracing and lighting ${fixed(stats.render_ms, 1)} ms), ` +
        `the round trip ${fixed(ms, 0)} ms.`,
    );
    renderWarnings = json.warnings;
    $('#warnings').replaceChildren(...json.warnings.map((w) => el('li', { text: `${w.code}: ${w.detail}` })));
    if (probed) probe(...probed);
    if ($('#comparing').checked) comparison.run();
    // The bake follows the full size: the same lighting, seen the same way.
    if (model) bakeModel();
  },
  onProblem(problem) {
    view.stale(true);
    showProblem(problem);
    if (model) bakeState('waiting', 'No bake while the server refuses the render');
    say(`The server refused the request (${problem.status}); the picture is the last one it drew. ${problem.detail ?? ''}`);
  },
  onError(error) {
    view.stale(true);
    say(`The request failed: ${error.message}`);
  },
});

const controls = new Controls($('#controls'), {
  onEdit(how) {
    bakeIsStale();
    if (how === 'moving') renderer.moving();
    else renderer.full();
  },
  onExample: (name) => start(name),
});

/**
 * The pointer of a problem as the scene being edited names its fields, or
 * null for a problem of the model itself: with a model, the request's
 * fields are under `/request` and the model's under `/model`.
 */
function scenePointer(problem) {
  const ptr = typeof problem.pointer === 'string' ? problem.pointer : '';
  if (!model) return ptr;
  if (ptr === '/request' || ptr.startsWith('/request/')) return ptr.slice('/request'.length);
  return null;
}

/** Shows a problem where its pointer points: beside a control, or at the model. */
function showProblem(problem) {
  const ptr = scenePointer(problem);
  if (ptr !== null) {
    $('#model-problem').hidden = true;
    controls.showProblem({ ...problem, pointer: ptr });
    return;
  }
  controls.clearProblems();
  const output = $('#model-problem');
  output.textContent = `${problem.title ?? 'Problem'} (${problem.status ?? '?'}): ${problem.detail ?? ''}${problem.pointer ? ` [at ${problem.pointer}]` : ''}`;
  output.hidden = false;
}

const comparison = new Comparison($('#compare'), {
  request: () => scene,
  model: () => model,
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

new CandidatePanel($('#candidate'), {
  request: () => scene,
  model: () => model,
  onPixel: (x, y) => probe(x, y),
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
    const result = await postRender(probeOf(scene, x, y), { signal: controller.signal, purpose: 'probe', model });
    if (!result.ok) {
      problem$.textContent = `${result.problem.title}: ${result.problem.detail}`;
      problem$.hidden = false;
      const ptr = scenePointer(result.problem);
      if (ptr === null || (ptr && !ptr.startsWith('/probes') && !ptr.startsWith('/region'))) showProblem(result.problem);
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

// "Copy as curl": the request the page sent last, as a command to paste;
// a model's bake has its own, as it follows every full render.
sent.addEventListener('request', (event) => {
  const detail = event.detail;
  const curl = detail.purpose === 'bake' ? $('#bake-curl') : $('#curl');
  if (detail.purpose === 'bake') lastBake = detail;
  else last = detail;
  curl.value = toCurl(detail.url, detail.body, detail.accept, detail.model);
  curl.dataset.purpose = detail.purpose;
});

/** Puts a command on the clipboard, or selects it where it is shown when the clipboard is not there. */
async function copy(curl, detail) {
  if (!detail) return say('Nothing has been sent yet.');
  try {
    await navigator.clipboard.writeText(curl.value);
    say(`The ${detail.purpose} request is on the clipboard as a curl command.`);
  } catch {
    curl.closest('details').open = true;
    curl.focus();
    curl.select();
    say('The clipboard is not available here: the command is selected below.');
  }
}
$('#copy-curl').addEventListener('click', () => copy($('#curl'), last));
$('#copy-bake-curl').addEventListener('click', () => copy($('#bake-curl'), lastBake));

/** Forgets the probe of the scene before. */
function unprobe() {
  probed = null;
  $('#marker').hidden = true;
  $('#probe-result').replaceChildren(el('p', { class: 'hint', text: 'Click a pixel of the render, or give its x and y.' }));
}

/** Loads an example and renders it (leaving the model, if one is shown). */
async function start(name) {
  say(`Loading the example \u201c${name}\u201d\u2026`);
  try {
    scene = await loadExample(name);
  } catch (error) {
    say(error.message);
    return;
  }
  example = name;
  leaveModel();
  unprobe();
  controls.show(scene, name);
  renderer.start();
}

// A model: a GLB dropped on the picture or chosen with the file input. It
// is rendered per vertex with the lighting being edited, and baked with the
// same lighting after every full render, for the link to download.

/** Shows `file` as the model, lit as the scene being edited is. */
async function useModel(file) {
  say(`Reading \u201c${file.name}\u201d\u2026`);
  let read;
  try {
    read = await readModel(file);
  } catch (error) {
    say(`The file could not be read: ${error.message}`);
    return;
  }
  leaveModel({ keepFile: true });
  model = { ...read, materials: modelMaterials(read.gltf) };
  scene = modelScene(scene ?? {}, model);
  unprobe();
  controls.show(scene, example, model);
  const meshes = model.gltf?.meshes?.length;
  $('#model-about').textContent = model.gltf
    ? `The model \u201c${model.name}\u201d (${meshes ?? 0} mesh${meshes === 1 ? '' : 'es'}, ${model.materials.length} material${model.materials.length === 1 ? '' : 's'}), ` +
      'lit per vertex by the controls, as its bake is; the camera frames it.'
    : `\u201c${model.name}\u201d: the page cannot read it as a GLB; the server\u2019s answer says why.`;
  $('#model-loaded').hidden = false;
  bakeState('waiting', 'The bake follows the render');
  renderer.start();
}

/** Forgets the model and its bake (the scene is the caller's to replace). */
function leaveModel({ keepFile = false } = {}) {
  if (!model) return;
  model = null;
  bakeController?.abort();
  bakeController = null;
  if (bakeUrl) URL.revokeObjectURL(bakeUrl);
  bakeUrl = null;
  lastBake = null;
  $('#bake-curl').value = '';
  $('#model-loaded').hidden = true;
  $('#model-problem').hidden = true;
  $('#bake-warnings').replaceChildren();
  // The same file chosen again is a change again.
  if (!keepFile) $('#model-file').value = '';
}

$('#model-file').addEventListener('change', (event) => {
  const [file] = event.target.files;
  if (file) useModel(file);
});
$('#model-remove').addEventListener('click', () => {
  $('#model-file').focus();
  start(example);
});

// Dropping: on the picture and what is around it. A file dropped anywhere
// else on the page is not opened by the browser, which would leave the page.
const stage = $('.stage');
const carriesFiles = (event) => [...(event.dataTransfer?.types ?? [])].includes('Files');
for (const type of ['dragenter', 'dragover']) {
  stage.addEventListener(type, (event) => {
    if (!carriesFiles(event)) return;
    event.preventDefault();
    event.dataTransfer.dropEffect = 'copy';
    stage.classList.add('dropping');
  });
}
stage.addEventListener('dragleave', (event) => {
  if (!stage.contains(event.relatedTarget)) stage.classList.remove('dropping');
});
stage.addEventListener('drop', (event) => {
  stage.classList.remove('dropping');
  if (!carriesFiles(event)) return;
  event.preventDefault();
  const [file] = event.dataTransfer.files;
  if (!file) return;
  // The file input no longer names the model shown.
  $('#model-file').value = '';
  useModel(file);
});
for (const type of ['dragover', 'drop']) {
  window.addEventListener(type, (event) => {
    if (carriesFiles(event)) event.preventDefault();
  });
}

/** Says on the download link what the bake is doing; `ready` gives it the bake's URL. */
function bakeState(state, text, url = null) {
  const link = $('#bake-link');
  link.dataset.state = state;
  link.textContent = text;
  if (url) {
    link.href = url;
    link.removeAttribute('aria-disabled');
  } else {
    link.removeAttribute('href');
    link.setAttribute('aria-disabled', 'true');
  }
}

/** The lighting changed: the bake there is no longer its bake. */
function bakeIsStale() {
  if (!model) return;
  bakeController?.abort();
  bakeState('waiting', 'The bake follows the render');
}

/** Bakes the model with the lighting being edited (POST /v1/shade) and offers the result. */
async function bakeModel() {
  bakeController?.abort();
  const controller = new AbortController();
  bakeController = controller;
  const baking = model;
  const file = `${stem(baking.name)}-baked.glb`;
  bakeState('baking', `Baking ${file}\u2026`);
  try {
    const result = await bake(scene, baking, { signal: controller.signal, announce });
    if (controller.signal.aborted || model !== baking) return;
    if (!result.ok) {
      showProblem(result.problem);
      bakeState('problem', 'No bake: the server refused it');
      return;
    }
    if (bakeUrl) URL.revokeObjectURL(bakeUrl);
    bakeUrl = URL.createObjectURL(result.blob);
    $('#bake-link').download = file;
    bakeState('ready', `Download ${file}`, bakeUrl);
    // The model's mapping warns of the same things in the render and the bake: each is said once.
    const said = new Set(renderWarnings.map((w) => `${w.code}: ${w.detail}`));
    const more = result.warnings.map((w) => `${w.code}: ${w.detail}`).filter((text) => !said.has(text));
    $('#bake-warnings').replaceChildren(...more.map((text) => el('li', { text })));
  } catch (error) {
    if (error.name !== 'AbortError' && model === baking) bakeState('problem', `No bake: ${error.message}`);
  } finally {
    if (bakeController === controller) bakeController = null;
  }
}

start(EXAMPLES[0].name);
