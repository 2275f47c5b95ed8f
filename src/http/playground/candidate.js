// Your renderer against GL: a PNG rendered elsewhere from the page's scene
// ("Copy as curl" gives the scene) is sent with that scene to
// POST /v1/compare, and the answer is shown: the error figures, the
// per-pixel error as a heatmap over the image, the worst pixels (each a
// button that probes it) and the diagnosis, the known mistakes of
// hand-written ports ranked by how much of the error each explains.

import { el, fixed } from './dom.js';
import { boundaryFor, fileForm, problemOf } from './model.js';
import { announce, decode } from './render.js';

/** How strongly the heatmap covers the candidate's image. */
const HEATMAP_ALPHA = 0.65;

export class CandidatePanel {
  /**
   * `request()` is the scene being edited, `model()` the model shown (an
   * image compare takes the scene alone), `onPixel(x, y)` probes a pixel.
   */
  constructor(root, { request, model, onPixel }) {
    this.root = root;
    this.request = request;
    this.model = model;
    this.onPixel = onPixel;
    this.controller = null;
    this.input = root.querySelector('#candidate-file');
    this.problem = root.querySelector('#candidate-problem');
    this.result = root.querySelector('#candidate-result');
    this.input.addEventListener('change', () => {
      const file = this.input.files?.[0];
      if (file) this.check(file);
    });
    // A drop here is the candidate, not a model for the stage around it.
    for (const type of ['dragenter', 'dragover']) {
      root.addEventListener(type, (event) => {
        event.preventDefault();
        event.stopPropagation();
        root.classList.add('dropping');
      });
    }
    root.addEventListener('dragleave', (event) => {
      event.stopPropagation();
      root.classList.remove('dropping');
    });
    root.addEventListener('drop', (event) => {
      event.preventDefault();
      event.stopPropagation();
      root.classList.remove('dropping');
      const file = event.dataTransfer?.files?.[0];
      if (file) this.check(file);
    });
  }

  /** Sends `file` (the candidate's PNG) with the scene, and shows the answer. */
  async check(file) {
    const scene = this.request();
    if (!scene) return;
    this.problem.hidden = true;
    if (this.model()) {
      return this.fail({
        title: 'Not with a model',
        detail: 'an image is compared with the scene alone: remove the model first',
      });
    }
    this.controller?.abort();
    const controller = new AbortController();
    this.controller = controller;
    this.root.dataset.state = 'comparing';
    this.root.setAttribute('aria-busy', 'true');
    try {
      const bytes = new Uint8Array(await file.arrayBuffer());
      const url = new URL('/v1/compare', location.href).href;
      const accept = 'application/json';
      const form = fileForm(
        scene,
        { name: 'image', type: 'image/png', filename: file.name || 'candidate.png', bytes },
        boundaryFor(bytes),
      );
      announce({ url, body: scene, accept, purpose: 'compare', model: null });
      const response = await fetch(url, {
        method: 'POST',
        headers: { 'content-type': form.type, accept },
        body: form.body,
        signal: controller.signal,
      });
      if (!response.ok) return this.fail(await problemOf(response));
      const json = await response.json();
      const candidate = await createImageBitmap(new Blob([bytes], { type: 'image/png' }));
      const heatmap = json.heatmap_png_base64 ? await decode(json.heatmap_png_base64) : null;
      this.show(json, candidate, heatmap);
      this.root.dataset.state = 'done';
    } catch (error) {
      if (error.name !== 'AbortError') this.fail({ title: 'The comparison failed', detail: error.message });
    } finally {
      if (this.controller === controller) {
        this.controller = null;
        this.root.removeAttribute('aria-busy');
      }
    }
  }

  fail(problem) {
    this.root.dataset.state = 'problem';
    this.problem.textContent =
      `${problem.title ?? 'Problem'}${problem.status ? ` (${problem.status})` : ''}: ${problem.detail ?? ''}` +
      (problem.pointer ? ` [at ${problem.pointer}]` : '');
    this.problem.hidden = false;
  }

  show(json, candidate, heatmap) {
    const { error, worst, diagnosis } = json;
    const canvas = el('canvas', {
      width: candidate.width,
      height: candidate.height,
      class: 'candidate-image',
      role: 'img',
      'aria-label': 'Your image, with the error against GL over it as a heatmap',
    });
    const context = canvas.getContext('2d');
    context.drawImage(candidate, 0, 0);
    if (heatmap) {
      context.globalAlpha = HEATMAP_ALPHA;
      context.drawImage(heatmap, 0, 0, candidate.width, candidate.height);
    }
    const figure = (label, value, key) =>
      el('div', { class: 'figure', 'data-key': key, 'data-value': value }, el('dt', { text: label }), el('dd', { text: String(value) }));
    const figures = el(
      'dl',
      { class: 'figures' },
      figure('largest |error|', Number(error.max_abs.toPrecision(3)), 'max_abs'),
      figure('mean |error|', Number(error.mean_abs.toPrecision(3)), 'mean_abs'),
      figure('99th percentile', Number(error.p99_abs.toPrecision(3)), 'p99_abs'),
      figure('8-bit channels that differ', `${fixed(100 * error.differing_8bit, 2)}%`, 'differing_8bit'),
      figure('PSNR', error.psnr_db === null || error.psnr_db === undefined ? '\u221e' : `${fixed(error.psnr_db, 1)} dB`, 'psnr_db'),
      figure('within the tier\u2019s bound', error.within_bound ? 'yes' : 'no', 'within_bound'),
    );
    const rgb = (c) => c.slice(0, 3).map((x) => fixed(x, 3)).join(', ');
    const worstList = el(
      'ol',
      { class: 'worst', 'aria-label': 'The worst pixels' },
      ...worst.map(({ pixel: [x, y], expected, candidate: theirs }) => {
        const button = el('button', {
          type: 'button',
          'data-pixel': `${x},${y}`,
          text: `pixel (${x}, ${y}): GL ${rgb(expected)}, yours ${rgb(theirs)}`,
        });
        button.addEventListener('click', () => this.onPixel(x, y));
        return el('li', {}, button);
      }),
    );
    const explaining = diagnosis.filter((d) => d.explains);
    const diagnosisList = el(
      'ol',
      { class: 'diagnosis', 'aria-label': 'The diagnosis' },
      ...diagnosis.map((d) =>
        el(
          'li',
          { 'data-deviations': d.deviations.join('+'), 'data-explains': String(d.explains) },
          el('strong', { text: d.deviations.join(' + ') }),
          ` ${d.explains ? 'explains it' : 'does not explain it'}: the error left is ${Number(d.max_abs.toPrecision(3))} at most. `,
          el('span', { class: 'hint', text: d.detail ?? '' }),
        ),
      ),
    );
    const verdict = explaining.length
      ? `Most likely: ${explaining[0].deviations.join(' + ')}.`
      : error.within_bound
        ? 'Your image is GL\u2019s within the tier\u2019s bound.'
        : 'No known mistake explains the difference.';
    this.result.replaceChildren(
      el('p', { class: 'verdict', text: verdict }),
      canvas,
      figures,
      el('h3', { text: 'The worst pixels (click one to probe it)' }),
      worstList,
      el('h3', { text: 'Diagnosis' }),
      diagnosisList,
    );
  }
}
