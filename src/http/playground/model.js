// The dropped model: a GLB read just far enough to frame it and to name its
// materials, the requests that carry it (multipart/form-data with a
// `request` and a `model` part, as api/openapi.yaml states them) and the
// bake of the lighting being edited. The server reads the model itself:
// the page never refuses a file, so a file that is no GLB gets the
// server's problem, shown as every other problem is.

/** The highest shininess the mapping of a glTF material gives (api/openapi.yaml). */
const MAX_MAPPED_SHININESS = 128;

/** A model the page has read: its file name, its bytes, and its glTF JSON (null when it is no GLB). */
export async function readModel(file) {
  const bytes = new Uint8Array(await file.arrayBuffer());
  let gltf = null;
  try {
    gltf = glbJson(bytes);
  } catch {
    // The server says what is wrong with it, with a pointer.
  }
  return { name: file.name || 'model.glb', bytes, gltf, boundary: boundaryFor(bytes) };
}

/** The JSON chunk of a GLB (glTF 2.0, section 4.4); throws when `bytes` is no GLB. */
export function glbJson(bytes) {
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  if (bytes.length < 20 || view.getUint32(0, true) !== 0x46546c67 || view.getUint32(4, true) !== 2) {
    throw new Error('not a GLB of glTF 2.0');
  }
  const length = view.getUint32(12, true);
  if (view.getUint32(16, true) !== 0x4e4f534a || 20 + length > bytes.length) throw new Error('no JSON chunk');
  return JSON.parse(new TextDecoder().decode(bytes.subarray(20, 20 + length)));
}

/** The model's name without `.glb`, for the baked file's name. */
export function stem(name) {
  return name.replace(/\.glb$/i, '') || 'model';
}

// 4×4 matrices, column-major as glTF writes them.
const IDENTITY = [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1];

function mul(a, b) {
  const c = new Array(16).fill(0);
  for (let col = 0; col < 4; col += 1) {
    for (let row = 0; row < 4; row += 1) {
      for (let k = 0; k < 4; k += 1) c[col * 4 + row] += a[k * 4 + row] * b[col * 4 + k];
    }
  }
  return c;
}

/** A node's local matrix: its `matrix`, or T · R · S (glTF 2.0, section 3.5.2). */
function local(node) {
  if (Array.isArray(node.matrix) && node.matrix.length === 16) return node.matrix;
  const [tx, ty, tz] = node.translation ?? [0, 0, 0];
  const [x, y, z, w] = node.rotation ?? [0, 0, 0, 1];
  const [sx, sy, sz] = node.scale ?? [1, 1, 1];
  return [
    (1 - 2 * (y * y + z * z)) * sx, 2 * (x * y + z * w) * sx, 2 * (x * z - y * w) * sx, 0,
    2 * (x * y - z * w) * sy, (1 - 2 * (x * x + z * z)) * sy, 2 * (y * z + x * w) * sy, 0,
    2 * (x * z + y * w) * sz, 2 * (y * z - x * w) * sz, (1 - 2 * (x * x + y * y)) * sz, 0,
    tx, ty, tz, 1,
  ];
}

const place = (m, [x, y, z]) => [0, 1, 2].map((r) => m[r] * x + m[4 + r] * y + m[8 + r] * z + m[12 + r]);

/**
 * The box, in world space, about the triangles the server renders: the
 * default scene's triangle primitives, each POSITION accessor's `min` and
 * `max` (which glTF requires of POSITION) as its nodes place them. The
 * placed corners of each accessor's box bound its placed positions, so the
 * box may be larger than the model, never smaller. `null` when there is
 * nothing to bound.
 */
export function bounds(gltf) {
  const scene = gltf?.scenes?.[gltf.scene ?? 0];
  if (!scene) return null;
  const min = [Infinity, Infinity, Infinity];
  const max = [-Infinity, -Infinity, -Infinity];
  const nodes = gltf.nodes ?? [];
  const visit = (index, parent, depth) => {
    const node = nodes[index];
    // A cycle is the server's to name; here it only ends the walk.
    if (!node || depth > nodes.length) return;
    const world = mul(parent, local(node));
    for (const primitive of gltf.meshes?.[node.mesh]?.primitives ?? []) {
      if ((primitive.mode ?? 4) !== 4) continue;
      const accessor = gltf.accessors?.[primitive.attributes?.POSITION];
      if (!accessor?.min || !accessor?.max) continue;
      for (let corner = 0; corner < 8; corner += 1) {
        const p = place(world, [0, 1, 2].map((k) => (corner & (1 << k) ? accessor.max[k] : accessor.min[k])));
        p.forEach((c, k) => {
          min[k] = Math.min(min[k], c);
          max[k] = Math.max(max[k], c);
        });
      }
    }
    for (const child of node.children ?? []) visit(child, world, depth + 1);
  };
  for (const root of scene.nodes ?? []) visit(root, IDENTITY, 0);
  return [...min, ...max].every(Number.isFinite) ? { min, max } : null;
}

/** Where the orbit starts: in front of the model, to the right and above (glTF's +z is its front, +y its up). */
const FRONT = (() => {
  const d = [0.6, 0.45, 1];
  const n = Math.hypot(...d);
  return d.map((c) => c / n);
})();

const significant = (c) => Number(c.toPrecision(6));

/**
 * `camera` (its size and field of view kept) turned to frame `box`: aimed
 * at its centre, from the distance at which the sphere about the box fits
 * the narrower of the two fields of view, with a little room about it.
 * The page always sends the whole camera, as its orbit moves the eye about
 * the target; a model's own camera is therefore not used.
 */
export function frame(camera, box) {
  const center = [0, 1, 2].map((k) => (box.min[k] + box.max[k]) / 2);
  const radius = Math.max(1e-3, Math.hypot(...[0, 1, 2].map((k) => box.max[k] - box.min[k])) / 2);
  const fovY = ((camera.fov_y ?? 45) * Math.PI) / 180;
  const aspect = (camera.width ?? 640) / (camera.height ?? 360);
  const half = Math.min(fovY / 2, Math.atan(Math.tan(fovY / 2) * aspect));
  const distance = (radius / Math.sin(half)) * 1.05;
  return {
    ...camera,
    eye: center.map((c, k) => significant(c + FRONT[k] * distance)),
    target: center.map(significant),
    up: [0, 1, 0],
  };
}

/**
 * The model's materials: each one's key in the request's `materials` (the
 * `#<index>` form, which no two materials share, unlike names), a label, and
 * the GL material api/openapi.yaml says the server maps it to while the
 * request names none: diffuse = ambient = baseColorFactor, specular =
 * mix(0.04, baseColorFactor, metallicFactor) · (1 − roughnessFactor),
 * shininess = 2/roughness⁴ − 2 up to 128, emission = emissiveFactor times
 * its strength; an unlit material is its base colour as emission. It is
 * where a GL material of the person's own starts, so that taking one
 * changes nothing until a value is changed.
 */
export function modelMaterials(gltf) {
  return (gltf?.materials ?? []).map((material, index) => ({
    key: `#${index}`,
    label: material?.name ? `${material.name} (#${index})` : `#${index}`,
    mapped: mapped(material ?? {}),
  }));
}

function mapped(material) {
  const pbr = material.pbrMetallicRoughness ?? {};
  const base = pbr.baseColorFactor ?? [1, 1, 1, 1];
  const rgb = base.slice(0, 3);
  const alpha = base[3] ?? 1;
  if (material.extensions?.KHR_materials_unlit) {
    return {
      ambient: [0, 0, 0, alpha],
      diffuse: [0, 0, 0, alpha],
      specular: [0, 0, 0, 1],
      emission: [...rgb, 1],
      shininess: 0,
    };
  }
  const metallic = pbr.metallicFactor ?? 1;
  const roughness = pbr.roughnessFactor ?? 1;
  const strength = material.extensions?.KHR_materials_emissive_strength?.emissiveStrength ?? 1;
  const emissive = material.emissiveFactor ?? [0, 0, 0];
  return {
    ambient: [...rgb, alpha],
    diffuse: [...rgb, alpha],
    specular: [...rgb.map((c) => (0.04 + (c - 0.04) * metallic) * (1 - roughness)), 1],
    emission: [...emissive.map((c) => c * strength), 1],
    shininess: roughness > 0 ? Math.min(MAX_MAPPED_SHININESS, 2 / roughness ** 4 - 2) : MAX_MAPPED_SHININESS,
  };
}

/** The fields of a render request that a model's render takes as they are. */
const CARRIED = ['light_model', 'back_material', 'lights', 'background', 'samples', 'shadows', 'precision', 'encoding'];

/**
 * The render request of a model, from the scene being edited: its light
 * model, lights, back material and render options; no objects (the model
 * is the scene) and no materials (the model's own, until the person gives
 * one of theirs); lit per vertex, as a bake is; seen by `scene`'s camera
 * turned to frame the model, when the model can be read.
 */
export function modelScene(scene, model) {
  const body = {};
  for (const key of CARRIED) if (scene[key] !== undefined) body[key] = structuredClone(scene[key]);
  const camera = scene.camera ?? { eye: [0, 0, 5], target: [0, 0, 0], up: [0, 1, 0], fov_y: 45, width: 640, height: 360 };
  const box = bounds(model.gltf);
  body.camera = box ? frame(camera, box) : { ...camera };
  body.shading = 'per_vertex';
  return body;
}

/**
 * The `request` part of a bake (POST /v1/shade) of the same lighting as
 * `scene`, a model's render request: its light model, lights and
 * materials, and its camera as the view, so that the baked colours are
 * the ones the per-vertex render shows (the same viewer for the specular
 * terms) rather than those of the model's own camera.
 */
export function bakeOf(scene) {
  const body = {};
  for (const key of ['light_model', 'materials', 'back_material', 'lights', 'precision']) {
    if (scene[key] !== undefined) body[key] = scene[key];
  }
  const { eye, target, up } = scene.camera;
  body.view = { eye, target, up };
  return body;
}

const encoder = new TextEncoder();

/** A boundary found nowhere in `bytes`, for the forms that carry them. */
export function boundaryFor(bytes) {
  for (;;) {
    const boundary = `glint-${crypto.randomUUID()}`;
    if (indexOf(bytes, encoder.encode(boundary)) < 0) return boundary;
  }
}

function indexOf(bytes, pattern) {
  const first = pattern[0];
  for (let i = bytes.indexOf(first); i >= 0 && i + pattern.length <= bytes.length; i = bytes.indexOf(first, i + 1)) {
    let k = 1;
    while (k < pattern.length && bytes[i + k] === pattern[k]) k += 1;
    if (k === pattern.length) return i;
  }
  return -1;
}

/** A form field's file name as HTML's form encoding writes it: quotes and line breaks escaped. */
const quoted = (name) => name.replaceAll('"', '%22').replaceAll('\r', '%0D').replaceAll('\n', '%0A');

/**
 * The `multipart/form-data` body (RFC 7578) of `request` (JSON) and one
 * file part, `{ name, type, filename, bytes }`, delimited by `boundary` (a
 * string found nowhere in the file): `{ type, body }`. It is built as bytes,
 * not with `FormData`, so that each part says its type and the whole body
 * is there for whoever looks at the request (the browser's developer tools
 * show a `FormData` file only as its name).
 */
export function fileForm(request, file, boundary) {
  const json = JSON.stringify(request);
  const head = (name, type, filename) =>
    encoder.encode(
      `--${boundary}\r\nContent-Disposition: form-data; name="${name}"` +
        (filename ? `; filename="${quoted(filename)}"` : '') +
        `\r\nContent-Type: ${type}\r\n\r\n`,
    );
  const parts = [
    head('request', 'application/json'),
    encoder.encode(`${json}\r\n`),
    head(file.name, file.type, file.filename),
    file.bytes,
    encoder.encode(`\r\n--${boundary}--\r\n`),
  ];
  const body = new Uint8Array(parts.reduce((n, p) => n + p.length, 0));
  let at = 0;
  for (const part of parts) {
    body.set(part, at);
    at += part.length;
  }
  return { type: `multipart/form-data; boundary=${boundary}`, body };
}

/** The form of `request` with `model` as its `model` part. */
export function modelForm(request, model) {
  return fileForm(request, { name: 'model', type: 'model/gltf-binary', filename: model.name, bytes: model.bytes }, model.boundary);
}

/**
 * Bakes `model` with the lighting of `scene` (POST /v1/shade, the baked
 * GLB asked for): `{ ok: true, blob, warnings }` with the warnings the
 * server put in its `extras.glint`, or `{ ok: false, problem }`.
 */
export async function bake(scene, model, { signal, announce }) {
  const url = new URL('/v1/shade', location.href).href;
  const request = bakeOf(scene);
  const accept = 'model/gltf-binary';
  announce({ url, body: request, accept, purpose: 'bake', model: model.name });
  const form = modelForm(request, model);
  const response = await fetch(url, { method: 'POST', headers: { 'content-type': form.type, accept }, body: form.body, signal });
  if (!response.ok) return { ok: false, problem: await problemOf(response) };
  const bytes = new Uint8Array(await response.arrayBuffer());
  let warnings = [];
  try {
    warnings = glbJson(bytes).extras?.glint?.warnings ?? [];
  } catch {
    warnings = [{ code: 'unreadable', detail: 'the baked model could not be read back by the page' }];
  }
  return { ok: true, blob: new Blob([bytes], { type: accept }), warnings };
}

/** An answer's problem+json, or one made of its status when it has none. */
export async function problemOf(response) {
  const type = response.headers.get('content-type') ?? '';
  return type.includes('json')
    ? response.json()
    : { title: response.statusText, status: response.status, detail: await response.text() };
}
