// A TypeScript client of glint, typed from its contract: openapi-typescript
// turns `api/openapi.yaml` into types, openapi-fetch makes the calls with
// them, and the compiler checks every body against the contract.
//
//   npm install openapi-fetch@0.17.0
//   npm install -D openapi-typescript@7.13.0 typescript@5.9.3 @types/node@20
//   npx openapi-typescript api/openapi.yaml -o examples/glint.d.ts \
//       --default-non-nullable false
//
// (`--default-non-nullable false`: a field with a default may be left out
// of a request; the generator would otherwise make it required.)
//
// Then, with glint serving (`glint serve`), run it with a TypeScript runner
// (`npx tsx examples/client.ts [BASE_URL] [OUT.png]`), or compile it with
// `tsc` and run the JavaScript with Node.
//
// It shades one vertex with GL's defaults, renders a red sphere, and prints
// what it read as one line of JSON; with OUT.png it also saves the picture.

import { writeFileSync } from "node:fs";

import createClient from "openapi-fetch";

import type { components, paths } from "./glint";

type ShadeRequest = components["schemas"]["ShadeRequest"];
type ShadeResponse = components["schemas"]["ShadeResponse"];
type RenderRequest = components["schemas"]["RenderRequest"];

/** Width and height from a PNG's IHDR chunk, which comes first. */
function pngSize(png: Uint8Array): { width: number; height: number } {
  const signature = [0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a];
  const ihdr = new TextDecoder().decode(png.subarray(12, 16));
  if (!signature.every((byte, i) => png[i] === byte) || ihdr !== "IHDR") {
    throw new Error("not a PNG");
  }
  const view = new DataView(png.buffer, png.byteOffset, png.byteLength);
  return { width: view.getUint32(16), height: view.getUint32(20) };
}

async function main(baseUrl: string, out?: string): Promise<void> {
  const glint = createClient<paths>({ baseUrl });

  // A vertex at the origin facing +z, lit by one light with GL_LIGHT0's
  // defaults (white, along +z), with GL's default material.
  const shadeRequest: ShadeRequest = {
    lights: [{}],
    vertices: { positions: [[0, 0, 0]], normals: [[0, 0, 1]] },
  };
  const shaded = await glint.POST("/v1/shade", { body: shadeRequest });
  if (shaded.error) {
    throw new Error(`shade refused: ${shaded.error.detail}`);
  }
  // A JSON request's answer is JSON (a glTF model's would be a model).
  const answer = shaded.data as ShadeResponse;

  // The PNG, glint's default answer to a render.
  const renderRequest: RenderRequest = {
    materials: { red: { diffuse: [1, 0, 0] } },
    lights: [{ position: [1, 1, 1, 0] }],
    camera: { eye: [0, 0, 5], target: [0, 0, 0], up: [0, 1, 0], fov_y: 45, width: 64, height: 48 },
    objects: [{ sphere: { center: [0, 0, 0], radius: 1 }, material: "red" }],
  };
  const rendered = await glint.POST("/v1/render", {
    body: renderRequest,
    parseAs: "arrayBuffer",
  });
  if (rendered.error) {
    throw new Error(`render refused: ${rendered.error.detail}`);
  }
  const png = new Uint8Array(rendered.data);
  const { width, height } = pngSize(png);
  if (out) {
    writeFileSync(out, png);
  }

  console.log(
    JSON.stringify({
      color: answer.colors[0],
      precision: answer.precision,
      width,
      height,
    }),
  );
}

const [baseUrl = "http://127.0.0.1:8080", out] = process.argv.slice(2);
main(baseUrl, out).catch((error: unknown) => {
  console.error(error);
  process.exit(1);
});
