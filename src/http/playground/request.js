// The request being edited: a body of POST /v1/render, as the example
// scenes give it and the controls change it. A field the person has not
// touched stays absent, so the server's defaults (GL's) apply, and an
// example sent unchanged is the file of examples/ as it is.

import { stem } from './model.js';

/** GL's initial values, as api/openapi.yaml states them: what a control
 * shows while its field is absent. */
export const DEFAULTS = {
  light_model: {
    ambient: [0.2, 0.2, 0.2],
    local_viewer: false,
    two_side: false,
    color_control: 'single',
    specular_model: 'blinn_phong',
    attenuation_clamp: false,
    normalize_normals: true,
  },
  material: {
    ambient: [0.2, 0.2, 0.2],
    diffuse: [0.8, 0.8, 0.8],
    specular: [0, 0, 0],
    emission: [0, 0, 0],
    shininess: 0,
  },
  // GL_LIGHT0's values; glint gives them to every light.
  light: {
    position: [0, 0, 1, 0],
    ambient: [0, 0, 0],
    diffuse: [1, 1, 1],
    specular: [1, 1, 1],
    attenuation: [1, 0, 0],
  },
  spot: { direction: [0, 0, -1], exponent: 0, cutoff: 180 },
  background: [0, 0, 0],
  shading: 'per_pixel',
  samples: 1,
  shadows: false,
  precision: 'accurate',
  encoding: 'linear',
};

/** The scenes of examples/, served beside this page. */
export const EXAMPLES = [
  { name: 'spheres', label: 'Spheres: 20 spheres, 4 lights, a spot, shadows' },
  { name: 'mesh', label: 'Mesh: a gold sphere mesh, Gouraud shaded' },
  { name: 'triangle', label: 'Triangle: the shade example, seen from its eye' },
];

/** The precision tiers and their evaluators. */
export const TIERS = ['reference', 'accurate', 'fast'];

/** Most lights a request may have (the contract's bound). */
export const MAX_LIGHTS = 64;

/** An example as a render request. */
export async function loadExample(name, signal) {
  const response = await fetch(`/playground/${encodeURIComponent(name)}.json`, { signal });
  if (!response.ok) {
    throw new Error(`the example ${name} did not load (${response.status})`);
  }
  const body = await response.json();
  return 'vertices' in body ? fromShade(body) : body;
}

/**
 * A /v1/shade request as a scene to render: its vertices become one mesh,
 * seen from GL's eye (the origin, looking down -z) unless it has a view, and
 * lit per vertex as the shade endpoint lights them.
 */
export function fromShade(shade) {
  const positions = shade.vertices.positions;
  const triangles = Math.floor(positions.length / 3);
  const view = shade.view ?? { eye: [0, 0, 0], target: [0, 0, -1], up: [0, 1, 0] };
  const scene = {
    materials: { material: shade.material ?? {} },
    lights: shade.lights ?? [],
    camera: {
      eye: view.eye,
      target: view.target,
      up: view.up ?? [0, 1, 0],
      fov_y: 45,
      width: 480,
      height: 360,
    },
    objects: [
      {
        mesh: {
          positions,
          normals: shade.vertices.normals,
          indices: Array.from({ length: triangles * 3 }, (_, i) => i),
        },
        material: 'material',
      },
    ],
    shading: 'per_vertex',
  };
  if (shade.light_model) scene.light_model = shade.light_model;
  if (shade.back_material) scene.back_material = shade.back_material;
  if (shade.precision) scene.precision = shade.precision;
  return scene;
}

/** The value at `path` (a list of keys and indices), or undefined. */
export function get(object, path) {
  let value = object;
  for (const key of path) {
    if (value === undefined || value === null) return undefined;
    value = value[key];
  }
  return value;
}

/** Sets the value at `path`, making the objects on the way. */
export function set(object, path, value) {
  let parent = object;
  for (const key of path.slice(0, -1)) {
    if (parent[key] === undefined || parent[key] === null) parent[key] = {};
    parent = parent[key];
  }
  parent[path[path.length - 1]] = value;
}

/** The JSON Pointer (RFC 6901) of `path`, as the server's problems name fields. */
export function pointer(path) {
  return path
    .map((key) => '/' + String(key).replaceAll('~', '~0').replaceAll('/', '~1'))
    .join('');
}

/** The keys of a JSON Pointer. */
export function keys(ptr) {
  if (!ptr) return [];
  return ptr
    .slice(1)
    .split('/')
    .map((key) => key.replaceAll('~1', '/').replaceAll('~0', '~'));
}

/** The light's kind: a position with w = 0 is directional, a cone makes a spot. */
export function lightKind(light) {
  const position = light.position ?? DEFAULTS.light.position;
  if (position[3] === 0) return 'directional';
  const cutoff = light.spot?.cutoff ?? DEFAULTS.spot.cutoff;
  return cutoff === 180 ? 'point' : 'spot';
}

/** Turns `light` into a light of `kind`, keeping what it can. */
export function setLightKind(light, kind) {
  const [x, y, z, w] = light.position ?? DEFAULTS.light.position;
  const place = w === 0 || w === undefined ? [x, y, z] : [x / w, y / w, z / w];
  light.position = [...place, kind === 'directional' ? 0 : 1];
  if (kind === 'spot') {
    const spot = light.spot ?? {};
    // Pointed at the origin, where the examples' scenes are.
    const norm = Math.hypot(...place) || 1;
    spot.direction ??= place.map((c) => round(-c / norm));
    if ((spot.cutoff ?? 180) === 180) spot.cutoff = 30;
    light.spot = spot;
  } else if (light.spot) {
    delete light.spot;
  }
}

/** A light for "Add a light": a white point light above and in front. */
export function newLight() {
  return { position: [2, 4, 4, 1] };
}

/** The request of a small image of the same view, for while a control moves. */
export function previewOf(scene, pixels = 16384) {
  const { width, height } = scene.camera;
  const scale = Math.min(1, Math.sqrt(pixels / (width * height)));
  const body = { ...scene };
  body.camera = {
    ...scene.camera,
    width: Math.max(1, Math.round(width * scale)),
    height: Math.max(1, Math.round(height * scale)),
  };
  delete body.samples;
  return body;
}

/** The request that explains pixel (x, y): only that pixel is traced. */
export function probeOf(scene, x, y) {
  return { ...scene, region: { x, y, width: 1, height: 1 }, probes: [[x, y]] };
}

/** The same request in another precision tier. */
export function withTier(scene, tier) {
  return { ...scene, precision: tier };
}

/** `word` as a POSIX shell word. */
function quote(word) {
  return `'${word.replaceAll("'", `'\\''`)}'`;
}

/** A file name as curl's `-F name=@file` reads it: in double quotes when it has a character that ends or escapes one. */
function formFile(name) {
  return /[",;\\]/.test(name) ? `"${name.replaceAll('\\', '\\\\').replaceAll('"', '\\"')}"` : name;
}

/** The file an answer of type `accept` is written to, when it is not text. */
function outputOf(accept, model) {
  if (accept === 'image/png') return 'render.png';
  if (accept === 'model/gltf-binary') return `${stem(model ?? 'model.glb')}-baked.glb`;
  return null;
}

/**
 * A curl command a person can paste that sends the same request (a PNG or
 * a baked model goes to a file). With `model`, the name of the GLB the
 * person chose, the request is the form the page sent: the JSON as the
 * `request` part, read from the here-document on stdin, and the file of
 * that name in the current directory as the `model` part.
 */
export function toCurl(url, body, accept, model = null) {
  const output = outputOf(accept, model);
  const head = [`curl -s ${quote(url)}`, `-H ${quote(`accept: ${accept}`)}`, ...(output ? [`-o ${quote(output)}`] : [])];
  if (!model) {
    return [head[0], `-H ${quote('content-type: application/json')}`, ...head.slice(1), `--data-binary ${quote(JSON.stringify(body))}`].join(
      ' \\\n  ',
    );
  }
  // The JSON is one line, so it never is the here-document's end marker.
  return (
    [
      ...head,
      `-F ${quote('request=<-;type=application/json')}`,
      `-F ${quote(`model=@${formFile(model)};type=model/gltf-binary`)}`,
    ].join(' \\\n  ') + ` <<'JSON'\n${JSON.stringify(body)}\nJSON`
  );
}

// Vectors, for the camera.
const sub = (a, b) => a.map((c, i) => c - b[i]);
const add = (a, b) => a.map((c, i) => c + b[i]);
const scale = (a, s) => a.map((c) => c * s);
const dot = (a, b) => a.reduce((sum, c, i) => sum + c * b[i], 0);
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const length = (a) => Math.hypot(...a);
const unit = (a) => scale(a, 1 / (length(a) || 1));
const round = (c) => Math.round(c * 1e4) / 1e4;

/** `v` turned by `angle` radians about the unit axis `k` (Rodrigues' formula). */
function rotate(v, k, angle) {
  const cos = Math.cos(angle);
  const sin = Math.sin(angle);
  return add(add(scale(v, cos), scale(cross(k, v), sin)), scale(k, dot(k, v) * (1 - cos)));
}

/**
 * The camera moved on its sphere about the target: `yaw` radians about the
 * up direction, `pitch` radians towards it (stopping short of the pole, where
 * the up direction would be parallel to the view).
 */
export function orbit(camera, yaw, pitch) {
  const up = unit(camera.up);
  let offset = rotate(sub(camera.eye, camera.target), up, yaw);
  const polar = Math.acos(Math.max(-1, Math.min(1, dot(unit(offset), up))));
  const turned = Math.max(0.02, Math.min(Math.PI - 0.02, polar - pitch));
  const axis = cross(up, offset);
  if (length(axis) > 0) offset = rotate(offset, unit(axis), turned - polar);
  return { ...camera, eye: add(camera.target, offset).map(round) };
}

/** The camera moved towards the target (`factor` < 1) or away from it. */
export function zoom(camera, factor) {
  const offset = sub(camera.eye, camera.target);
  const distance = length(offset);
  const wanted = Math.max(1e-3, Math.min(1e6, distance * factor));
  return { ...camera, eye: add(camera.target, scale(offset, wanted / distance)).map(round) };
}
