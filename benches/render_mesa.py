"""Mesa's llvmpipe drawing the frame that `cargo bench --bench render_mesa`
has glint render: the same triangles, normals, camera, light and material,
one sample per pixel, lit two ways. `vertex`: GL's fixed-function lighting
per vertex (Gouraud), as glint's `per_vertex`. `fragment`: the same
equation (GL 2.1 §2.14.1, for this scene's one positional light, the
infinite viewer, one side) per fragment, in a GLSL 1.20 program that reads
the same fixed-function state, with the interpolated normal normalised, as
glint's `per_pixel`.

Needs Debian's `libosmesa6` and, from PyPI, `PyOpenGL==3.1.10` and
`numpy==2.2.6` (the bench says so and stops when they are missing). The
context is OSMesa's (`PYOPENGL_PLATFORM=osmesa`), so no display is needed.

    python3 benches/render_mesa.py SCENE_DIR

`SCENE_DIR` holds `scene.json` (the GL state) and the arrays
`positions.f32`, `normals.f32`, `indices.u32` (little-endian, packed). The
vertices go to buffer objects once. Then, one command a line on stdin:

- `draw MODE` (`vertex` or `fragment`): clears and draws the frame
  (`glDrawElements`), waits for it (`glFinish`), and prints the
  milliseconds it took;
- `read PATH`: writes the last frame's RGBA8 pixels to PATH, top row
  first, as glint's images are;
- `quit`.
"""

import json
import os
import sys
import time

os.environ.setdefault("PYOPENGL_PLATFORM", "osmesa")

try:
    import numpy as np
    from OpenGL import GL, GLU, arrays, osmesa
    from OpenGL.GL import shaders
except ImportError as missing:  # the bench reads this line and stops
    print(
        f"missing: {missing}; install with `apt-get install libosmesa6` and "
        "`pip install PyOpenGL==3.1.10 numpy==2.2.6`",
        flush=True,
    )
    sys.exit(3)

# The eye-space position and normal, interpolated to each fragment.
VERTEX_SHADER = """
#version 120
varying vec3 eye_position;
varying vec3 eye_normal;
void main() {
    eye_position = vec3(gl_ModelViewMatrix * gl_Vertex);
    eye_normal = gl_NormalMatrix * gl_Normal;
    gl_Position = ftransform();
}
"""

# GL 2.1's lighting equation (§2.14.1) at each fragment for light 0 with a
# position, no spot cone, the infinite viewer, the front material and one
# colour: what the fixed-function pipeline computes at each vertex, with
# the same built-in state, and the normal normalised (GL_NORMALIZE).
FRAGMENT_SHADER = """
#version 120
varying vec3 eye_position;
varying vec3 eye_normal;
void main() {
    vec3 n = normalize(eye_normal);
    gl_LightSourceParameters light = gl_LightSource[0];
    vec3 towards = light.position.xyz / light.position.w - eye_position;
    float d = length(towards);
    vec3 vp = towards / d;
    float attenuation = 1.0 / (light.constantAttenuation
        + light.linearAttenuation * d + light.quadraticAttenuation * d * d);
    float diffuse = max(dot(n, vp), 0.0);
    vec3 h = normalize(vp + vec3(0.0, 0.0, 1.0));
    float specular = diffuse > 0.0
        ? pow(max(dot(n, h), 0.0), gl_FrontMaterial.shininess) : 0.0;
    vec3 color = gl_FrontMaterial.emission.rgb
        + gl_FrontMaterial.ambient.rgb * gl_LightModel.ambient.rgb
        + attenuation * (gl_FrontMaterial.ambient.rgb * light.ambient.rgb
            + diffuse * gl_FrontMaterial.diffuse.rgb * light.diffuse.rgb
            + specular * gl_FrontMaterial.specular.rgb * light.specular.rgb);
    gl_FragColor = vec4(color, gl_FrontMaterial.diffuse.a);
}
"""


def main():
    folder = sys.argv[1]
    with open(os.path.join(folder, "scene.json")) as f:
        scene = json.load(f)
    positions = np.fromfile(os.path.join(folder, "positions.f32"), dtype="<f4")
    normals = np.fromfile(os.path.join(folder, "normals.f32"), dtype="<f4")
    indices = np.fromfile(os.path.join(folder, "indices.u32"), dtype="<u4")
    width, height = scene["width"], scene["height"]
    if scene["local_viewer"]:
        raise SystemExit("the per-fragment program lights for the infinite viewer only")

    context = osmesa.OSMesaCreateContextExt(osmesa.OSMESA_RGBA, 24, 0, 0, None)
    if not context:
        raise SystemExit("OSMesa gave no context")
    framebuffer = arrays.GLubyteArray.zeros((height, width, 4))
    if not osmesa.OSMesaMakeCurrent(context, framebuffer, GL.GL_UNSIGNED_BYTE, width, height):
        raise SystemExit("OSMesa could not make its context current")
    print(
        f"renderer: {GL.glGetString(GL.GL_RENDERER).decode()}; "
        f"{GL.glGetString(GL.GL_VERSION).decode()}",
        file=sys.stderr,
    )

    GL.glViewport(0, 0, width, height)
    GL.glMatrixMode(GL.GL_PROJECTION)
    GL.glLoadIdentity()
    GLU.gluPerspective(scene["fov_y"], width / height, scene["near"], scene["far"])
    GL.glMatrixMode(GL.GL_MODELVIEW)
    GL.glLoadIdentity()
    GLU.gluLookAt(*scene["eye"], *scene["target"], *scene["up"])

    GL.glEnable(GL.GL_DEPTH_TEST)
    GL.glDepthFunc(GL.GL_LESS)
    GL.glDisable(GL.GL_CULL_FACE)
    GL.glShadeModel(GL.GL_SMOOTH)
    GL.glEnable(GL.GL_LIGHTING)
    GL.glLightModelfv(GL.GL_LIGHT_MODEL_AMBIENT, scene["light_model_ambient"])
    GL.glLightModeli(GL.GL_LIGHT_MODEL_LOCAL_VIEWER, int(scene["local_viewer"]))
    GL.glLightModeli(GL.GL_LIGHT_MODEL_TWO_SIDE, 0)
    GL.glEnable(GL.GL_NORMALIZE)
    light = scene["light"]
    GL.glEnable(GL.GL_LIGHT0)
    # With the modelview at the camera: the position is in world space.
    GL.glLightfv(GL.GL_LIGHT0, GL.GL_POSITION, light["position"])
    for name, value in (
        ("ambient", GL.GL_AMBIENT),
        ("diffuse", GL.GL_DIFFUSE),
        ("specular", GL.GL_SPECULAR),
    ):
        GL.glLightfv(GL.GL_LIGHT0, value, light[name])
    for value, k in zip(
        (GL.GL_CONSTANT_ATTENUATION, GL.GL_LINEAR_ATTENUATION, GL.GL_QUADRATIC_ATTENUATION),
        light["attenuation"],
    ):
        GL.glLightf(GL.GL_LIGHT0, value, k)
    material = scene["material"]
    for name, value in (
        ("ambient", GL.GL_AMBIENT),
        ("diffuse", GL.GL_DIFFUSE),
        ("specular", GL.GL_SPECULAR),
        ("emission", GL.GL_EMISSION),
    ):
        GL.glMaterialfv(GL.GL_FRONT_AND_BACK, value, material[name])
    GL.glMaterialf(GL.GL_FRONT_AND_BACK, GL.GL_SHININESS, material["shininess"])
    GL.glClearColor(*scene["background"])

    buffers = GL.glGenBuffers(3)
    GL.glBindBuffer(GL.GL_ARRAY_BUFFER, buffers[0])
    GL.glBufferData(GL.GL_ARRAY_BUFFER, positions.nbytes, positions, GL.GL_STATIC_DRAW)
    GL.glEnableClientState(GL.GL_VERTEX_ARRAY)
    GL.glVertexPointer(3, GL.GL_FLOAT, 0, None)
    GL.glBindBuffer(GL.GL_ARRAY_BUFFER, buffers[1])
    GL.glBufferData(GL.GL_ARRAY_BUFFER, normals.nbytes, normals, GL.GL_STATIC_DRAW)
    GL.glEnableClientState(GL.GL_NORMAL_ARRAY)
    GL.glNormalPointer(GL.GL_FLOAT, 0, None)
    GL.glBindBuffer(GL.GL_ELEMENT_ARRAY_BUFFER, buffers[2])
    GL.glBufferData(GL.GL_ELEMENT_ARRAY_BUFFER, indices.nbytes, indices, GL.GL_STATIC_DRAW)
    count = len(indices)
    programs = {
        "vertex": 0,
        "fragment": shaders.compileProgram(
            shaders.compileShader(VERTEX_SHADER, GL.GL_VERTEX_SHADER),
            shaders.compileShader(FRAGMENT_SHADER, GL.GL_FRAGMENT_SHADER),
        ),
    }

    def draw(mode):
        GL.glUseProgram(programs[mode])
        GL.glClear(GL.GL_COLOR_BUFFER_BIT | GL.GL_DEPTH_BUFFER_BIT)
        GL.glDrawElements(GL.GL_TRIANGLES, count, GL.GL_UNSIGNED_INT, None)
        GL.glFinish()

    # The bench's untimed rounds warm llvmpipe (its shaders compiled, its
    # caches filled) in the same turns as glint.
    print("ready", flush=True)

    for line in sys.stdin:
        command = line.split()
        if not command:
            continue
        if command[0] == "draw":
            started = time.perf_counter()
            draw(command[1])
            print(f"{(time.perf_counter() - started) * 1e3:.4f}", flush=True)
        elif command[0] == "read":
            pixels = GL.glReadPixels(0, 0, width, height, GL.GL_RGBA, GL.GL_UNSIGNED_BYTE)
            image = np.frombuffer(pixels, dtype=np.uint8).reshape(height, width, 4)
            # GL's rows run from the bottom.
            image[::-1].tofile(command[1])
            print("read", flush=True)
        elif command[0] == "quit":
            break
    osmesa.OSMesaDestroyContext(context)


if __name__ == "__main__":
    main()
