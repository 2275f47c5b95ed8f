// The breakdown of one pixel: the probe the API answers, as a table of
// every term and as a stacked bar per colour channel with a segment per
// light and term, the unclamped sum beside the clamped colour, and the list
// of terms the evaluation modeled.

import { el, fixed } from './dom.js';

/** The terms of one light, in the order the equation adds them. */
const LIGHT_TERMS = ['ambient', 'diffuse', 'specular'];
const CHANNELS = ['R', 'G', 'B'];

/** Every coloured term of a breakdown, each with its name as `modeled` spells it. */
function terms(breakdown) {
  const list = [
    { term: 'emission', label: 'emission e_cm', kind: 'emission', rgb: breakdown.emission },
    { term: 'global_ambient', label: 'global ambient a_cm\u00b7a_cs', kind: 'global', rgb: breakdown.global_ambient },
  ];
  breakdown.lights.forEach((light, i) => {
    for (const name of LIGHT_TERMS) {
      list.push({ term: `lights[${i}].${name}`, label: `light ${i} ${name}`, kind: name, light: i, rgb: light[name] });
    }
  });
  return list;
}

/** A cell that shows a number to four places and keeps all of it. */
function numberCell(value, attributes = {}) {
  return el('td', { class: 'num', 'data-value': value, title: String(value), text: fixed(value), ...attributes });
}

/** A colour's channel as the PNG writes it: linear, or through the sRGB curve (IEC 61966-2-1). */
function encode(c, encoding) {
  const v = Math.min(1, Math.max(0, c));
  if (encoding !== 'srgb') return v;
  return v <= 0.0031308 ? 12.92 * v : 1.055 * v ** (1 / 2.4) - 0.055;
}

function swatch(rgb, label, encoding) {
  const [r, g, b] = rgb.slice(0, 3).map((c) => Math.round(255 * encode(c, encoding)));
  const chip = el('span', { class: 'chip', role: 'img', 'aria-label': label });
  chip.style.background = `rgb(${r}, ${g}, ${b})`;
  return chip;
}

/** One bar per channel: the terms stacked from 0, the clamp at 1 marked. */
function bars(list, unclamped) {
  const top = Math.max(1, ...unclamped, ...CHANNELS.map((_, c) => list.reduce((sum, t) => sum + Math.max(0, t.rgb[c]), 0)));
  const figure = el('figure', { class: 'bars' });
  CHANNELS.forEach((channel, c) => {
    const bar = el('div', { class: 'bar', 'data-channel': channel });
    for (const t of list) {
      const value = t.rgb[c];
      if (!(value > 0)) continue;
      const segment = el('span', {
        class: `segment ${t.kind}${t.light === undefined ? '' : ` light-${t.light % 4}`}`,
        title: `${t.label}: ${value}`,
        'data-term': t.term,
      });
      segment.style.width = `${(100 * value) / top}%`;
      bar.append(segment);
    }
    const clamp = el('span', { class: 'clamp', title: 'the clamp at 1' });
    clamp.style.left = `${100 / top}%`;
    bar.append(clamp);
    const sum = unclamped[c];
    figure.append(
      el(
        'div',
        { class: 'bar-row' },
        el('span', { class: 'channel', text: channel }),
        bar,
        el('span', { class: 'num', text: fixed(sum) }),
      ),
    );
  });
  const kinds = [
    ['emission', 'emission'],
    ['global', 'global ambient'],
    ['ambient', 'light ambient'],
    ['diffuse', 'diffuse'],
    ['specular', 'specular'],
  ];
  figure.append(
    el(
      'figcaption',
      {},
      ...kinds.map(([kind, text]) => el('span', { class: 'key' }, el('span', { class: `segment ${kind}` }), ` ${text}`)),
      el('span', { class: 'key' }, el('span', { class: 'clamp-key' }), ' clamp at 1'),
    ),
  );
  figure.setAttribute('aria-hidden', 'true');
  return figure;
}

/** The table of every term (the accessible form of the bars). */
function table(breakdown, color, modeled) {
  const head = el('tr', {}, el('th', { scope: 'col', text: 'term' }), ...[...CHANNELS, 'A'].map((c) => el('th', { scope: 'col', text: c })));
  const body = el('tbody');
  const row = (term, label, cells, extra = {}) =>
    el('tr', { 'data-term': term, class: modeled.includes(term) ? 'modeled' : undefined, ...extra }, el('th', { scope: 'row', text: label }), ...cells);
  const rgb = (values) => [...values.map((v) => numberCell(v)), el('td')];
  body.append(row('emission', 'emission', rgb(breakdown.emission)));
  body.append(row('global_ambient', 'global ambient', rgb(breakdown.global_ambient)));
  breakdown.lights.forEach((light, i) => {
    for (const name of LIGHT_TERMS) body.append(row(`lights[${i}].${name}`, `light ${i} ${name}`, rgb(light[name])));
    for (const factor of ['attenuation', 'spot']) {
      body.append(
        row(`lights[${i}].${factor}`, `light ${i} ${factor}`, [numberCell(light[factor], { colspan: 3 }), el('td')], { class: `factor${modeled.includes(`lights[${i}].${factor}`) ? ' modeled' : ''}` }),
      );
    }
  });
  body.append(row('unclamped', 'sum, unclamped', rgb(breakdown.unclamped), { class: 'total' }));
  body.append(row('color', 'colour, clamped', color.map((v) => numberCell(v)), { class: 'total' }));
  return el('table', { class: 'terms' }, el('caption', { text: 'Every term before clamping (colour terms include attenuation \u00b7 spot)' }), el('thead', {}, head), body);
}

/**
 * Shows the probe of `json` (a JSON render whose `terms.probes[0]` is the
 * pixel) in `root`; `scene` names the object hit.
 */
export function showProbe(root, json, scene) {
  const probe = json.terms.probes[0];
  const [x, y] = probe.pixel;
  root.dataset.pixel = `${x},${y}`;
  const parts = [el('h3', { text: `Pixel (${x}, ${y})` })];
  if (!probe.hit) {
    parts.push(el('p', { text: 'The centre ray hits nothing: the pixel is the background.' }));
    parts.push(el('p', { class: 'colors' }, swatch(probe.color, 'background colour', scene.encoding), ` colour ${probe.color.map((c) => fixed(c)).join(', ')}`));
    root.replaceChildren(...parts);
    return;
  }
  const object = scene.objects?.[probe.hit.object];
  // A model's meshes follow the request's objects.
  const what = object
    ? `a ${['sphere', 'plane', 'mesh'].find((k) => k in object) ?? 'object'}, material \u201c${object.material ?? '?'}\u201d`
    : 'a mesh of the model';
  parts.push(
    el('p', {
      class: 'hit',
      text: `The centre ray hits object ${probe.hit.object} (${what}) on its ${probe.hit.side} side.`,
    }),
  );
  const { breakdown } = probe;
  const list = terms(breakdown);
  parts.push(bars(list, breakdown.unclamped));
  parts.push(
    el(
      'div',
      { class: 'colors' },
      el('span', {}, swatch(breakdown.unclamped, 'unclamped sum', scene.encoding), ' sum ', el('span', { class: 'num', text: breakdown.unclamped.map((c) => fixed(c)).join(', ') })),
      el('span', { class: 'arrow', text: 'clamped \u2192' }),
      el('span', {}, swatch(probe.color, 'clamped colour', scene.encoding), ' colour ', el('span', { class: 'num', text: probe.color.map((c) => fixed(c)).join(', ') })),
    ),
  );
  const factors = breakdown.lights.map((light, i) => `light ${i}: attenuation ${fixed(light.attenuation)}, spot ${fixed(light.spot)}`);
  if (factors.length) parts.push(el('p', { class: 'factors', text: factors.join('; ') }));
  parts.push(table(breakdown, probe.color, json.modeled));
  parts.push(
    el('p', {
      class: 'precision',
      text: `The terms come from the f64 reference; the colour from the ${json.precision.mode} tier (bound ${json.precision.max_abs_error}).`,
    }),
  );
  parts.push(el('h4', { text: 'Modeled terms' }), el('ul', { class: 'modeled' }, ...json.modeled.map((term) => el('li', { text: term }))));
  root.replaceChildren(...parts);
}
