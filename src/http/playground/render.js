// The picture: renders asked of POST /v1/render (a small preview while a
// control moves, the full size once it rests, each newer request aborting
// the one before), the view that draws them and turns drags, the wheel and
// keys into camera moves, and the same view in two precision tiers side by
// side with their difference amplified.

import { el, fixed } from './dom.js';
import { modelForm, problemOf } from './model.js';

/** Time a control must rest before the full size is asked for, in ms. */
export const REST_MS = 250;

/** Every request the page sends is announced here (`request` events), for "Copy as curl". */
export const sent = new EventTarget();

/** Says that a request is being sent: `{ url, body, accept, purpose, model }`, `model` the file's name when a model goes with it. */
export function announce(detail) {
  sent.dispatchEvent(new CustomEvent('request', { detail }));
}

/**
 * Posts `body` to /v1/render, for its JSON form or (`png`) the PNG alone,
 * which the server makes faster (it computes no term statistics); with
 * `model`, as the `request` part of a form whose `model` part is the GLB.
 * Resolves to `{ ok: true, json, ms }` or `{ ok: true, png, ms }` (a Blob),
 * or `{ ok: false, problem, retryAfter }`; rejects with an `AbortError`
 * when `signal` aborts it.
 */
export async function postRender(body, { signal, purpose, png = false, model = null }) {
  const url = new URL('/v1/render', location.href).href;
  const accept = png ? 'image/png' : 'application/json';
  announce({ url, body, accept, purpose, model: model?.name ?? null });
  const form = model ? modelForm(body, model) : { type: 'application/json', body: JSON.stringify(body) };
  const started = performance.now();
  const response = await fetch(url, {
    method: 'POST',
    headers: { 'content-type': form.type, accept },
    body: form.body,
    signal,
  });
  if (!response.ok) {
    const problem = await problemOf(response);
    const retryAfter = Number(response.headers.get('retry-after') ?? NaN);
    return { ok: false, problem, retryAfter };
  }
  if (png) {
    const blob = await response.blob();
    return { ok: true, png: blob, ms: performance.now() - started };
  }
  const json = await response.json();
  return { ok: true, json, ms: performance.now() - started };
}

/** The PNG of a JSON render, decoded (no URL is loaded: the page's policy allows none). */
export async function decode(base64) {
  const text = atob(base64);
  const bytes = new Uint8Array(text.length);
  for (let i = 0; i < text.length; i += 1) bytes[i] = text.charCodeAt(i);
  return createImageBitmap(new Blob([bytes], { type: 'image/png' }));
}

/**
 * Resolves once the browser has rendered the frame that shows what was drawn
 * before: the first task after that frame's animation callbacks.
 */
export function painted() {
  return new Promise((resolve) =>
    requestAnimationFrame(() => {
      const channel = new MessageChannel();
      channel.port1.onmessage = () => resolve(performance.now());
      channel.port2.postMessage(null);
    }),
  );
}

/** The canvas that shows the render, and the camera moves made on it. */
export class View {
  /**
   * `onOrbit(yaw, pitch)` and `onZoom(factor)` move the camera while the
   * person drags, turns the wheel or presses keys; `onSettle()` when a drag
   * ends; `onPick(x, y)` when a pixel is clicked.
   */
  constructor(canvas, marker, { onOrbit, onZoom, onSettle, onPick }) {
    this.canvas = canvas;
    this.marker = marker;
    this.context = canvas.getContext('2d');
    this.drag = null;
    canvas.addEventListener('pointerdown', (event) => {
      if (event.button !== 0) return;
      canvas.setPointerCapture(event.pointerId);
      this.drag = { x: event.clientX, y: event.clientY, moved: false };
    });
    canvas.addEventListener('pointermove', (event) => {
      const drag = this.drag;
      if (!drag) return;
      const dx = event.clientX - drag.x;
      const dy = event.clientY - drag.y;
      if (!drag.moved && Math.hypot(dx, dy) < 4) return;
      drag.moved = true;
      drag.x = event.clientX;
      drag.y = event.clientY;
      onOrbit(-dx * 0.01, dy * 0.01);
    });
    canvas.addEventListener('pointerup', (event) => {
      const drag = this.drag;
      this.drag = null;
      if (!drag) return;
      if (drag.moved) onSettle();
      else onPick(...this.pixelAt(event.clientX, event.clientY));
    });
    canvas.addEventListener('pointercancel', () => {
      if (this.drag?.moved) onSettle();
      this.drag = null;
    });
    canvas.addEventListener(
      'wheel',
      (event) => {
        event.preventDefault();
        onZoom(Math.exp(Math.max(-1, Math.min(1, event.deltaY / 500))));
      },
      { passive: false },
    );
    canvas.addEventListener('keydown', (event) => {
      const step = (5 * Math.PI) / 180;
      const moves = {
        ArrowLeft: () => onOrbit(step, 0),
        ArrowRight: () => onOrbit(-step, 0),
        ArrowUp: () => onOrbit(0, step),
        ArrowDown: () => onOrbit(0, -step),
        '+': () => onZoom(0.9),
        '=': () => onZoom(0.9),
        '-': () => onZoom(1 / 0.9),
      };
      const move = moves[event.key];
      if (!move || event.altKey || event.ctrlKey || event.metaKey) return;
      event.preventDefault();
      move();
    });
  }

  /** The pixel of the full image under a point of the window. */
  pixelAt(clientX, clientY) {
    const box = this.canvas.getBoundingClientRect();
    const x = Math.floor(((clientX - box.left) / box.width) * this.canvas.width);
    const y = Math.floor(((clientY - box.top) / box.height) * this.canvas.height);
    return [Math.max(0, Math.min(this.canvas.width - 1, x)), Math.max(0, Math.min(this.canvas.height - 1, y))];
  }

  /** Draws `bitmap` over the whole canvas, which has the full image's size. */
  draw(bitmap, width, height, kind) {
    if (this.canvas.width !== width || this.canvas.height !== height) {
      this.canvas.width = width;
      this.canvas.height = height;
      this.marker.hidden = true;
    }
    this.context.imageSmoothingEnabled = kind === 'preview';
    this.context.drawImage(bitmap, 0, 0, width, height);
    bitmap.close();
    this.canvas.dataset.kind = kind;
    this.canvas.dataset.drawn = String(Number(this.canvas.dataset.drawn ?? 0) + 1);
  }

  /** Marks the probed pixel. */
  mark(x, y) {
    this.marker.style.left = `${((x + 0.5) / this.canvas.width) * 100}%`;
    this.marker.style.top = `${((y + 0.5) / this.canvas.height) * 100}%`;
    this.marker.hidden = false;
  }

  /** Greys the picture while it no longer shows the request. */
  stale(on) {
    this.canvas.classList.toggle('stale', on);
  }
}

/**
 * Asks for renders as the request changes. A newer request aborts the one in
 * flight (the server then drops its work), so nothing queues; previews are
 * sent no more often than they come back, so a fast drag still shows some.
 */
export class Renderer {
  /**
   * `request()` gives the request as it is now, `model()` the model that
   * goes with it (or null), `previewOf(request)` its small version; `onDrawn({ kind, json, ms, editAt, drawnAt })` after a
   * render is on screen (`json`, the JSON form, for a full render only);
   * `onProblem(problem, kind)` when the server refuses.
   */
  constructor(view, { request, model = () => null, previewOf, onDrawn, onProblem, onError }) {
    Object.assign(this, { view, request, model, previewOf, onDrawn, onProblem, onError });
    this.controller = null;
    this.inFlight = null;
    this.restTimer = null;
    this.previewTimer = null;
    this.previewMs = 0;
    this.editAt = null;
    this.then = null;
    this.sent = 0;
  }

  /**
   * Says on the canvas what is under way, for whoever waits for the picture
   * to settle: `data-sent` and `data-shown` count the requests sent and the
   * one drawn and told last (its status and warnings written), `data-resting`
   * is set while a full size is due.
   */
  mark(key, value) {
    if (value === null) delete this.view.canvas.dataset[key];
    else this.view.canvas.dataset[key] = String(value);
  }

  /** A control moved: a preview now (or as soon as the last one is back), the full size at rest. */
  moving() {
    this.editAt ??= performance.now();
    clearTimeout(this.restTimer);
    this.restTimer = setTimeout(() => this.full(), REST_MS);
    this.mark('resting', true);
    if (this.previewTimer !== null) return;
    const flying = this.inFlight?.kind === 'preview' ? performance.now() - this.inFlight.at : Infinity;
    const wait = Math.max(0, this.previewMs - flying);
    this.previewTimer = setTimeout(() => {
      this.previewTimer = null;
      this.send('preview', this.previewOf(this.request()));
    }, wait);
  }

  /** A discrete change, or the end of a move: the full size now. */
  full() {
    clearTimeout(this.restTimer);
    clearTimeout(this.previewTimer);
    this.previewTimer = null;
    this.mark('resting', null);
    this.editAt ??= performance.now();
    this.send('full', this.request());
  }

  /** A new scene: a preview first, then the full size. */
  start() {
    this.editAt = performance.now();
    this.then = 'full';
    this.send('preview', this.previewOf(this.request()));
  }

  async send(kind, body, retried = false) {
    this.controller?.abort();
    const controller = new AbortController();
    this.controller = controller;
    this.sent += 1;
    const seq = this.sent;
    this.mark('sent', seq);
    const editAt = this.editAt;
    this.editAt = null;
    const then = kind === 'preview' ? this.then : null;
    this.then = null;
    this.inFlight = { kind, at: performance.now() };
    this.view.canvas.setAttribute('aria-busy', 'true');
    const { width, height } = body.camera;
    const full = kind === 'preview' ? this.request().camera : body.camera;
    try {
      // A preview is only a picture: the PNG form, the faster one.
      const png = kind === 'preview';
      const result = await postRender(body, { signal: controller.signal, purpose: kind, png, model: this.model() });
      if (controller.signal.aborted) return;
      if (!result.ok) {
        this.finish(controller);
        this.onProblem(result.problem, kind);
        // A saturated server says when to come back: the full size is asked for once more.
        if (result.problem.status === 503 && kind === 'full' && !retried && result.retryAfter >= 0) {
          setTimeout(() => this.controller === null && this.send('full', this.request(), true), result.retryAfter * 1000);
        }
        return;
      }
      const bitmap = await (png ? createImageBitmap(result.png) : decode(result.json.png_base64));
      if (controller.signal.aborted) {
        bitmap.close();
        return;
      }
      this.finish(controller);
      if (kind === 'preview') this.previewMs = this.previewMs * 0.5 + result.ms * 0.5;
      this.view.draw(bitmap, full.width, full.height, kind);
      const drawnAt = await painted();
      const detail = { kind, json: result.json, ms: result.ms, editAt, drawnAt, width, height };
      this.view.canvas.dispatchEvent(new CustomEvent('glint:drawn', { detail }));
      this.onDrawn(detail);
      this.mark('shown', seq);
      if (then === 'full' && this.controller === null) this.full();
    } catch (error) {
      if (error.name === 'AbortError') return;
      this.finish(controller);
      this.onError(error);
    }
  }

  finish(controller) {
    if (this.controller !== controller) return;
    this.controller = null;
    this.inFlight = null;
    this.view.canvas.removeAttribute('aria-busy');
  }
}

/** How two tiers' images differ, in 8-bit steps of their PNGs. */
function difference(a, b, gain, out) {
  let largest = 0;
  let differing = 0;
  for (let i = 0; i < a.data.length; i += 4) {
    let any = false;
    for (let c = 0; c < 3; c += 1) {
      const step = Math.abs(a.data[i + c] - b.data[i + c]);
      if (step > largest) largest = step;
      if (step) any = true;
      out.data[i + c] = Math.min(255, step * gain);
    }
    out.data[i + 3] = 255;
    if (any) differing += 1;
  }
  return { largest, differing, pixels: a.data.length / 4 };
}

/** The same view in two tiers side by side, each with its time and bound, and their difference amplified. */
export class Comparison {
  constructor(root, { request, model = () => null, withTier, onProblem }) {
    Object.assign(this, { root, request, model, withTier, onProblem });
    this.controller = null;
    this.images = null;
    this.left = root.querySelector('#tier-a');
    this.right = root.querySelector('#tier-b');
    this.gain = root.querySelector('#gain');
    this.gain.addEventListener('input', () => this.showDifference());
  }

  /** Renders the request in both tiers, one after the other (so that neither slows the other's time). */
  async run() {
    this.controller?.abort();
    const controller = new AbortController();
    this.controller = controller;
    const tiers = [this.left.value, this.right.value];
    this.root.dataset.state = 'running';
    this.root.setAttribute('aria-busy', 'true');
    const shown = [];
    try {
      for (const [side, tier] of tiers.entries()) {
        const result = await postRender(this.withTier(this.request(), tier), {
          signal: controller.signal,
          purpose: `compare ${tier}`,
          model: this.model(),
        });
        if (!result.ok) {
          this.onProblem(result.problem);
          this.root.dataset.state = 'problem';
          return;
        }
        const bitmap = await decode(result.json.png_base64);
        if (controller.signal.aborted) return;
        shown.push(this.showTier(side, tier, bitmap, result.json));
      }
      this.images = shown;
      this.showDifference();
      this.root.querySelector('#tier-speed').textContent = this.speed(shown);
      this.root.dataset.state = 'done';
    } catch (error) {
      if (error.name !== 'AbortError') {
        this.onProblem({ title: 'The comparison failed', detail: String(error) });
        this.root.dataset.state = 'problem';
      }
    } finally {
      if (this.controller === controller) {
        this.controller = null;
        this.root.removeAttribute('aria-busy');
      }
    }
  }

  /** Draws one tier's image and says its time and bound. */
  showTier(side, tier, bitmap, json) {
    const figure = this.root.querySelectorAll('.tier')[side];
    const canvas = figure.querySelector('canvas');
    canvas.width = bitmap.width;
    canvas.height = bitmap.height;
    const context = canvas.getContext('2d', { willReadFrequently: true });
    context.drawImage(bitmap, 0, 0);
    bitmap.close();
    const { stats, precision } = json;
    const caption = figure.querySelector('figcaption');
    caption.replaceChildren(
      el('strong', { text: tier }),
      el('span', { class: 'time', 'data-value': stats.render_ms, text: ` render ${fixed(stats.render_ms, 1)} ms` }),
      el('span', { text: ` (${fixed(stats.compute_ms, 1)} ms in all)` }),
      el('br'),
      el('span', {
        class: 'bound',
        'data-value': precision.max_abs_error,
        title: String(precision.max_abs_error),
        text: `documented bound ${Number(precision.max_abs_error.toPrecision(3))} per channel`,
      }),
    );
    figure.dataset.tier = precision.mode;
    return { tier, data: context.getImageData(0, 0, canvas.width, canvas.height), stats };
  }

  speed([a, b]) {
    const ratio = b.stats.render_ms / a.stats.render_ms;
    return `${a.tier} renders in ${fixed(a.stats.render_ms, 1)} ms, ${b.tier} in ${fixed(b.stats.render_ms, 1)} ms: ${
      ratio >= 1 ? `${fixed(ratio, 2)}\u00d7 faster` : `${fixed(1 / ratio, 2)}\u00d7 slower`
    }.`;
  }

  /** The difference image, amplified by the chosen gain. */
  showDifference() {
    if (!this.images) return;
    const [a, b] = this.images;
    const figure = this.root.querySelector('.difference');
    const canvas = figure.querySelector('canvas');
    const caption = figure.querySelector('figcaption');
    if (a.data.width !== b.data.width || a.data.height !== b.data.height) {
      caption.textContent = 'The two images differ in size.';
      return;
    }
    canvas.width = a.data.width;
    canvas.height = a.data.height;
    const context = canvas.getContext('2d');
    const out = context.createImageData(canvas.width, canvas.height);
    const gain = Number(this.gain.value);
    const { largest, differing, pixels } = difference(a.data, b.data, gain, out);
    context.putImageData(out, 0, 0);
    figure.dataset.largest = String(largest);
    figure.dataset.differing = String(differing);
    caption.textContent =
      `|${a.tier} \u2212 ${b.tier}| \u00d7 ${gain}: ` +
      (differing === 0
        ? 'the two PNGs are identical.'
        : `${differing} of ${pixels} pixels differ (${fixed((100 * differing) / pixels, 2)}%), ` +
          `by at most ${largest}/255 of a channel after 8-bit rounding.`);
  }
}
