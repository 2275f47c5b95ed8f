// The form: one labelled control for every field of the lighting
// description, the camera and the render options, each bound to its place in
// the request and named by that place's JSON Pointer, so that a problem the
// server answers is shown beside the control its `pointer` names.

import { el, uid } from './dom.js';
import {
  DEFAULTS,
  EXAMPLES,
  MAX_LIGHTS,
  TIERS,
  get,
  keys,
  lightKind,
  newLight,
  pointer,
  set,
  setLightKind,
} from './request.js';

const BACK = '\u0000back';

/** The precision choice that stands for an error budget rather than a tier. */
const BUDGET = '\u0000budget';

/** The budget first offered: `fast`'s documented bound, 1/512. */
const DEFAULT_BUDGET = 1 / 512;

/** `[r, g, b]` in [0, 1] as `#rrggbb`. */
function hex(rgb) {
  return (
    '#' +
    rgb
      .slice(0, 3)
      .map((c) => Math.round(255 * Math.min(1, Math.max(0, Number.isFinite(c) ? c : 0))))
      .map((c) => c.toString(16).padStart(2, '0'))
      .join('')
  );
}

/** A number input's value for the request: empty is `null`, which the server names. */
function numberOf(input) {
  return input.value === '' || Number.isNaN(input.valueAsNumber) ? null : input.valueAsNumber;
}

export class Controls {
  /**
   * `onEdit(how)` runs after every change of the request: `how` is
   * `moving` for a value that moves continuously (a slider, a number, a
   * colour), `set` for a discrete one (a checkbox, a choice, a light added).
   * `onExample(name)` asks for an example scene (and leaves the model).
   */
  constructor(form, { onEdit, onExample }) {
    this.form = form;
    this.onEdit = onEdit;
    this.onExample = onExample;
    this.material = null;
    this.scene = null;
    form.addEventListener('submit', (event) => event.preventDefault());
  }

  /**
   * Builds every control for `scene`, the request they edit in place;
   * with `model` (`{ name, materials }`), the request that goes with that
   * model, whose materials are the model's.
   */
  show(scene, example, model = null) {
    this.scene = scene;
    this.example = example;
    this.model = model;
    const names = this.materialNames();
    if (!names.includes(this.material) && this.material !== BACK) this.material = names[0] ?? null;
    this.form.replaceChildren(
      el('div', { class: 'problem request-problem', id: 'request-problem', role: 'alert', hidden: true }),
      this.section('scene', 'Scene', () => this.sceneFields()),
      this.section('rendering', 'Rendering', () => this.renderingFields()),
      this.section('light-model', 'Light model', () => this.lightModelFields(), 'light_model'),
      this.section('materials', 'Materials', () => this.materialFields(), 'materials'),
      this.section('lights', 'Lights', () => this.lightFields(), 'lights'),
      this.section('camera', 'Camera', () => this.cameraFields(), 'camera'),
    );
    // A new example keeps the keyboard where it was: on the choice of example.
    if (this.refocus) this.form.querySelector('[data-section="scene"] select')?.focus();
    this.refocus = false;
  }

  /** A collapsible part of the form, rebuilt by `rebuild(name)`. */
  section(name, title, fields, root) {
    const details = el('details', { class: 'section', 'data-section': name, open: true });
    if (root) details.dataset.pointer = pointer([root]);
    details.append(
      el('summary', { text: title }),
      el('output', { class: 'problem', id: uid('problem'), hidden: true }),
      el('div', { class: 'fields' }, ...fields()),
    );
    this[`${name}Builder`] = fields;
    return details;
  }

  /** Builds one section's controls again, keeping whether it is open. */
  rebuild(name) {
    const details = this.form.querySelector(`[data-section="${name}"]`);
    if (!details) return;
    details.querySelector('.fields').replaceChildren(...this[`${name}Builder`]());
  }

  /** The camera's controls again, after the view was orbited or zoomed. */
  refreshCamera() {
    this.rebuild('camera');
  }

  edited(how) {
    this.onEdit(how);
  }

  // The controls, each bound to `path` in the request.

  /** A control with its label and the place for its problem. */
  wrap(label, control, path, kind = '') {
    control.dataset.pointer = pointer(path);
    const problem = el('output', { class: 'problem', id: `${control.id}-problem`, for: control.id, hidden: true });
    const labelled = el('label', { for: control.id, text: label });
    return el('div', { class: `field ${kind}`.trim() }, labelled, control, problem);
  }

  checkbox(label, path, fallback, encode = (on) => on, decode = (value) => value) {
    const input = el('input', { type: 'checkbox', id: uid('check') });
    input.checked = decode(get(this.scene, path) ?? fallback);
    input.addEventListener('input', () => {
      set(this.scene, path, encode(input.checked));
      this.edited('set');
    });
    return this.wrap(label, input, path, 'check');
  }

  choice(label, path, options, fallback) {
    const select = el('select', { id: uid('choice') });
    for (const [value, text] of options) select.append(el('option', { value, text }));
    select.value = get(this.scene, path) ?? fallback;
    select.addEventListener('input', () => {
      set(this.scene, path, select.value);
      this.edited('set');
    });
    return this.wrap(label, select, path);
  }

  /** A number, with a slider beside it when `slider` gives its range. */
  number(label, path, fallback, { min, max, step = 'any', slider, integer = false } = {}) {
    const value = get(this.scene, path) ?? fallback;
    const input = el('input', { type: 'number', id: uid('number'), min, max, step, inputmode: 'decimal' });
    input.value = String(value);
    const field = this.wrap(label, input, path, slider ? 'slider' : 'number');
    let range = null;
    if (slider) {
      range = el('input', {
        type: 'range',
        id: uid('range'),
        min: slider.min,
        max: slider.max,
        step: slider.step,
      });
      range.value = String(value);
      range.addEventListener('input', () => {
        input.value = range.value;
        set(this.scene, path, integer ? Math.round(range.valueAsNumber) : range.valueAsNumber);
        this.edited('moving');
      });
      const rangeLabel = el('label', { for: range.id, class: 'visually-hidden', text: `${label}, slider` });
      field.querySelector('label').after(rangeLabel, range);
    }
    input.addEventListener('input', () => {
      const number = numberOf(input);
      if (range && number !== null) range.value = String(number);
      set(this.scene, path, number);
      this.edited('moving');
    });
    return field;
  }

  /** Three numbers, each named (`x`, `y`, `z` or `r`, `g`, `b`), as one group. */
  triple(label, path, fallback, names, { step = 0.1, read, write, picker = false } = {}) {
    const current = () => (read ? read() : get(this.scene, path) ?? fallback);
    const group = el('fieldset', { class: `triple${picker ? ' color' : ''}`, 'data-pointer': pointer(path) });
    const problem = el('output', { class: 'problem', id: uid('problem'), hidden: true });
    group.setAttribute('aria-describedby', problem.id);
    group.append(el('legend', { text: label }));
    const inputs = names.map((name, i) => {
      const input = el('input', { type: 'number', id: uid('component'), step, inputmode: 'decimal' });
      input.value = String(current()[i]);
      input.dataset.pointer = pointer([...path, i]);
      group.append(el('span', { class: 'component' }, el('label', { for: input.id, text: name }), input));
      return input;
    });
    let swatch = null;
    const store = (values) => {
      const old = current();
      // Keep an alpha the request gave; change only what the controls show.
      const next = old.length > names.length ? [...values, ...old.slice(names.length)] : values;
      if (write) write(next);
      else set(this.scene, path, next);
    };
    if (picker) {
      swatch = el('input', { type: 'color', id: uid('picker') });
      swatch.value = hex(current());
      swatch.addEventListener('input', () => {
        const rgb = [1, 3, 5].map((at) => Math.round((parseInt(swatch.value.slice(at, at + 2), 16) / 255) * 1000) / 1000);
        rgb.forEach((c, i) => (inputs[i].value = String(c)));
        store(rgb);
        this.edited('moving');
      });
      group.append(
        el('span', { class: 'component' }, el('label', { for: swatch.id, class: 'visually-hidden', text: `${label}, colour picker` }), swatch),
      );
    }
    for (const input of inputs) {
      input.addEventListener('input', () => {
        const values = inputs.map(numberOf);
        store(values);
        if (swatch && values.every((c) => c !== null)) swatch.value = hex(values);
        this.edited('moving');
      });
    }
    group.append(problem);
    return group;
  }

  color(label, path, fallback) {
    return this.triple(label, path, fallback, ['R', 'G', 'B'], { step: 0.05, picker: true });
  }

  // The sections.

  sceneFields() {
    const select = el('select', { id: uid('example') });
    if (this.model) select.append(el('option', { value: '', text: `The model \u201c${this.model.name}\u201d` }));
    for (const { name, label } of EXAMPLES) select.append(el('option', { value: name, text: label }));
    select.value = this.model ? '' : this.example;
    select.addEventListener('input', () => {
      if (!select.value) return;
      this.refocus = true;
      this.onExample(select.value);
    });
    const start = el('div', { class: 'field' }, el('label', { for: select.id, text: 'Start from' }), select);
    const fields = [start];
    if (this.model) fields.push(el('p', { class: 'hint', text: 'Choosing an example removes the model.' }));
    fields.push(this.color('Background', ['background'], DEFAULTS.background));
    return fields;
  }

  /**
   * The precision: a tier by name, or an error budget from which the server
   * picks the cheapest tier whose bound is within it (`{"max_abs_error": E}`).
   * The budget's number is bound to `/precision/max_abs_error`, where the
   * server names a budget no tier can keep.
   */
  precisionFields() {
    const path = ['precision'];
    const current = get(this.scene, path) ?? DEFAULTS.precision;
    const budgeted = typeof current === 'object' && current !== null;
    const select = el('select', { id: uid('choice') });
    for (const tier of TIERS) select.append(el('option', { value: tier, text: tier }));
    select.append(el('option', { value: BUDGET, text: 'an error budget' }));
    select.value = budgeted ? BUDGET : current;
    const budget = el('input', { type: 'number', id: uid('number'), min: 0, step: 'any', inputmode: 'decimal' });
    budget.value = String(budgeted ? current.max_abs_error : DEFAULT_BUDGET);
    const budgetField = this.wrap('Error budget (max |error| per channel)', budget, [...path, 'max_abs_error'], 'number');
    budgetField.hidden = !budgeted;
    select.addEventListener('input', () => {
      const asBudget = select.value === BUDGET;
      budgetField.hidden = !asBudget;
      set(this.scene, path, asBudget ? { max_abs_error: numberOf(budget) } : select.value);
      this.edited('set');
    });
    budget.addEventListener('input', () => {
      set(this.scene, path, { max_abs_error: numberOf(budget) });
      this.edited('moving');
    });
    return [this.wrap('Precision', select, path), budgetField];
  }

  renderingFields() {
    return [
      ...this.precisionFields(),
      this.choice(
        'Shading',
        ['shading'],
        [
          ['per_pixel', 'per pixel'],
          ['per_vertex', 'per vertex (Gouraud)'],
        ],
        DEFAULTS.shading,
      ),
      this.number('Samples per pixel', ['samples'], DEFAULTS.samples, {
        min: 1,
        max: 64,
        step: 1,
        integer: true,
        slider: { min: 1, max: 64, step: 1 },
      }),
      this.checkbox('Shadows', ['shadows'], DEFAULTS.shadows),
      this.choice(
        'Encoding',
        ['encoding'],
        [
          ['linear', 'linear (as GL)'],
          ['srgb', 'sRGB'],
        ],
        DEFAULTS.encoding,
      ),
    ];
  }

  lightModelFields() {
    const model = (field) => ['light_model', field];
    const d = DEFAULTS.light_model;
    return [
      this.color('Global ambient', model('ambient'), d.ambient),
      this.checkbox('Local viewer', model('local_viewer'), d.local_viewer),
      this.checkbox('Two-sided', model('two_side'), d.two_side),
      this.checkbox(
        'Separate specular',
        model('color_control'),
        d.color_control,
        (on) => (on ? 'separate_specular' : 'single'),
        (value) => value === 'separate_specular',
      ),
      this.choice(
        'Specular model',
        model('specular_model'),
        [
          ['blinn_phong', 'Blinn-Phong (GL)'],
          ['phong', 'Phong'],
        ],
        d.specular_model,
      ),
      this.checkbox('Attenuation clamped to 1', model('attenuation_clamp'), d.attenuation_clamp),
      this.checkbox('Normalise normals', model('normalize_normals'), d.normalize_normals),
    ];
  }

  /** The materials the request may name: the scene's, or the model's keys. */
  materialNames() {
    return this.model ? this.model.materials.map((m) => m.key) : Object.keys(this.scene.materials ?? {});
  }

  materialFields() {
    const names = this.materialNames();
    const select = el('select', { id: uid('material') });
    for (const name of names) {
      const label = this.model?.materials.find((m) => m.key === name)?.label ?? name;
      select.append(el('option', { value: name, text: label }));
    }
    select.append(el('option', { value: BACK, text: 'the back of every object (two-sided)' }));
    select.value = this.material ?? BACK;
    select.addEventListener('input', () => {
      this.material = select.value;
      this.rebuild('materials');
      this.form.querySelector('[data-section="materials"] select')?.focus();
    });
    const which = el('div', { class: 'field' }, el('label', { for: select.id, text: 'Edit material' }), select);
    const base = this.material === BACK ? ['back_material'] : ['materials', this.material];
    const d = DEFAULTS.material;
    const fields = [which];
    if (this.model && names.length === 0) {
      fields.push(el('p', { class: 'hint', text: 'The model has no materials: the server lights it with glTF\u2019s default one.' }));
    }
    if (this.material === BACK) {
      fields.push(
        el('p', {
          class: 'hint',
          text: 'Used with two-sided lighting; while absent, each object\u2019s own material lights its back.',
        }),
      );
    } else if (this.model) {
      fields.push(this.ownMaterial());
      if (!this.scene.materials?.[this.material]) return fields;
    }
    fields.push(
      this.color('Ambient', [...base, 'ambient'], d.ambient),
      this.color('Diffuse', [...base, 'diffuse'], d.diffuse),
      this.color('Specular', [...base, 'specular'], d.specular),
      this.color('Emission', [...base, 'emission'], d.emission),
      this.number('Shininess', [...base, 'shininess'], d.shininess, {
        min: 0,
        step: 'any',
        slider: { min: 0, max: 128, step: 1 },
      }),
    );
    return fields;
  }

  /**
   * The choice, for a material of the model, between the server's mapping
   * of its glTF material and a GL material of the person's own, which
   * starts as that mapping.
   */
  ownMaterial() {
    const key = this.material;
    const input = el('input', { type: 'checkbox', id: uid('own') });
    input.checked = Boolean(this.scene.materials?.[key]);
    input.addEventListener('input', () => {
      if (input.checked) {
        const mapped = this.model.materials.find((m) => m.key === key).mapped;
        this.scene.materials = { ...this.scene.materials, [key]: structuredClone(mapped) };
      } else {
        delete this.scene.materials[key];
        if (Object.keys(this.scene.materials).length === 0) delete this.scene.materials;
      }
      this.rebuild('materials');
      this.form.querySelector(`[data-section="materials"] [data-pointer="${CSS.escape(pointer(['materials', key]))}"]`)?.focus();
      this.edited('set');
    });
    const field = this.wrap('A GL material of my own', input, ['materials', key], 'check');
    const hint = input.checked
      ? 'It starts as the server\u2019s mapping of the glTF material.'
      : 'Unchecked: the server maps the glTF material (its base colour, metallic and roughness factors, emission) to a GL one.';
    field.append(el('p', { class: 'hint', text: hint }));
    return field;
  }

  lightFields() {
    const lights = (this.scene.lights ??= []);
    const fields = lights.map((light, i) => this.light(light, i));
    const add = el('button', { type: 'button', class: 'add', text: 'Add a light' });
    add.disabled = lights.length >= MAX_LIGHTS;
    add.addEventListener('click', () => {
      lights.push(newLight());
      this.rebuild('lights');
      this.edited('set');
      this.form.querySelector(`[data-light="${lights.length - 1}"] select`)?.focus();
    });
    if (lights.length === 0) fields.push(el('p', { class: 'hint', text: 'No lights: only emission and the global ambient.' }));
    fields.push(add);
    return fields;
  }

  light(light, i) {
    const path = ['lights', i];
    const kind = lightKind(light);
    const box = el('fieldset', { class: 'light', 'data-light': i, 'data-pointer': pointer(path) });
    box.append(el('legend', { text: `Light ${i}` }), el('output', { class: 'problem', id: uid('problem'), hidden: true }));
    // The kind is no field of the request: choosing one writes the position's w and the cone.
    const kindSelect = el('select', { id: uid('kind') });
    for (const value of ['directional', 'point', 'spot']) kindSelect.append(el('option', { value, text: value }));
    kindSelect.value = kind;
    kindSelect.addEventListener('input', () => {
      setLightKind(light, kindSelect.value);
      this.rebuild('lights');
      this.form.querySelector(`[data-light="${i}"] select`)?.focus();
      this.edited('set');
    });
    box.append(this.wrap('Kind', kindSelect, [...path, 'position', 3]));

    const position = light.position ?? DEFAULTS.light.position;
    const w = position[3];
    box.append(
      this.triple(
        kind === 'directional' ? 'Direction towards the light' : 'Position',
        [...path, 'position'],
        DEFAULTS.light.position,
        ['x', 'y', 'z'],
        {
          step: 0.5,
          read: () => {
            const [x, y, z, ww] = light.position ?? DEFAULTS.light.position;
            return ww === 0 || ww === 1 ? [x, y, z] : [x / ww, y / ww, z / ww];
          },
          write: (xyz) => (light.position = [...xyz, w === 0 ? 0 : 1]),
        },
      ),
      this.color('Ambient', [...path, 'ambient'], DEFAULTS.light.ambient),
      this.color('Diffuse', [...path, 'diffuse'], DEFAULTS.light.diffuse),
      this.color('Specular', [...path, 'specular'], DEFAULTS.light.specular),
    );
    if (kind !== 'directional') {
      box.append(
        this.triple('Attenuation k0, k1, k2', [...path, 'attenuation'], DEFAULTS.light.attenuation, ['k0', 'k1', 'k2'], {
          step: 0.01,
        }),
      );
    }
    if (kind === 'spot') {
      const spot = [...path, 'spot'];
      box.append(
        this.triple('Spot direction', [...spot, 'direction'], DEFAULTS.spot.direction, ['x', 'y', 'z'], { step: 0.1 }),
        this.number('Spot cutoff (degrees)', [...spot, 'cutoff'], DEFAULTS.spot.cutoff, {
          min: 0,
          max: 180,
          slider: { min: 0, max: 90, step: 1 },
        }),
        this.number('Spot exponent', [...spot, 'exponent'], DEFAULTS.spot.exponent, {
          min: 0,
          slider: { min: 0, max: 128, step: 1 },
        }),
      );
    }
    const drop = el('button', { type: 'button', class: 'remove', text: `Remove light ${i}` });
    drop.addEventListener('click', () => {
      this.scene.lights.splice(i, 1);
      this.rebuild('lights');
      this.edited('set');
      this.form.querySelector('[data-section="lights"] button.add')?.focus();
    });
    box.append(drop);
    return box;
  }

  cameraFields() {
    const camera = ['camera'];
    return [
      el('p', {
        class: 'hint',
        text: 'Drag the image to orbit, turn the wheel to zoom; with the image focused, the arrow keys orbit and + and \u2212 zoom.',
      }),
      this.triple('Eye', [...camera, 'eye'], [0, 0, 5], ['x', 'y', 'z'], { step: 0.1 }),
      this.triple('Target', [...camera, 'target'], [0, 0, 0], ['x', 'y', 'z'], { step: 0.1 }),
      this.triple('Up', [...camera, 'up'], [0, 1, 0], ['x', 'y', 'z'], { step: 0.1 }),
      this.number('Field of view (degrees, vertical)', [...camera, 'fov_y'], 45, {
        min: 0,
        max: 180,
        slider: { min: 5, max: 120, step: 1 },
      }),
      this.number('Width (pixels)', [...camera, 'width'], 640, { min: 1, step: 1 }),
      this.number('Height (pixels)', [...camera, 'height'], 360, { min: 1, step: 1 }),
    ];
  }

  // Problems.

  /** Removes every problem shown beside a control. */
  clearProblems() {
    for (const output of this.form.querySelectorAll('.problem')) {
      output.hidden = true;
      output.textContent = '';
    }
    for (const control of this.form.querySelectorAll('[aria-invalid]')) control.removeAttribute('aria-invalid');
  }

  /**
   * Shows `problem` beside the control its pointer names (or the nearest
   * control above it in the request); a problem of no control goes above
   * the form. Returns the element that shows it.
   */
  showProblem(problem) {
    this.clearProblems();
    const ptr = typeof problem.pointer === 'string' ? problem.pointer : '';
    const path = keys(ptr);
    // A material's problem shows in that material's editor.
    if (path[0] === 'materials' && path.length > 1 && path[1] !== this.material && path[1] in (this.scene.materials ?? {})) {
      this.material = path[1];
      this.rebuild('materials');
    } else if (path[0] === 'back_material' && this.material !== BACK) {
      this.material = BACK;
      this.rebuild('materials');
    }
    let control = null;
    for (let n = path.length; n > 0 && !control; n -= 1) {
      control = this.form.querySelector(`[data-pointer="${CSS.escape(pointer(path.slice(0, n)))}"]`);
    }
    const text = `${problem.title ?? 'Problem'} (${problem.status ?? '?'}): ${problem.detail ?? ''}`;
    let output;
    if (control) {
      const holder = control.closest('.field, fieldset, details');
      output = holder.querySelector(':scope > output.problem');
      control.setAttribute('aria-invalid', 'true');
      if (/^(INPUT|SELECT)$/.test(control.tagName)) control.setAttribute('aria-describedby', output.id);
      const details = control.closest('details');
      if (details) details.open = true;
    } else {
      output = this.form.querySelector('#request-problem');
    }
    output.textContent = ptr ? `${text} [at ${ptr}]` : text;
    output.dataset.pointer = ptr;
    output.hidden = false;
    output.scrollIntoView({ block: 'nearest' });
    return output;
  }
}
