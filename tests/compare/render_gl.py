"""A port's renderer, written apart from glint: NumPy traces a /v1/render
request of spheres and planes (one sample at each pixel's centre, lit per
pixel, no shadows) and lights every hit with section 2.14.1 of the GL 2.1
specification, with the deviations named on the command line switched on.

    python render_gl.py REQUEST.json OUT.png [DEVIATION ...]

writes an 8-bit RGB PNG, each channel round(255 * clamp(c)), as GL writes
an 8-bit framebuffer. Every field the request uses must be given: this
renderer knows no defaults. Deviations: phong_specular ((r.v)^s where GL
takes (n.h)^s), emission_missing.

    python render_gl.py --read HEATMAP.png X Y

prints the PNG's width, height, mode and the RGB of pixel (X, Y) as JSON.
"""

import json
import sys

import numpy as np
from PIL import Image


def unit(v):
    length = np.linalg.norm(v, axis=-1, keepdims=True)
    return np.where(length > 0, v / np.where(length > 0, length, 1), v)


def dot(a, b):
    return np.sum(a * b, axis=-1)


def rays(camera):
    """Unit directions through every pixel's centre, row by row."""
    eye, target, up = (np.array(camera[k], float) for k in ("eye", "target", "up"))
    width, height = camera["width"], camera["height"]
    w = unit(target - eye)
    u = unit(np.cross(w, up))
    v = np.cross(u, w)
    tan_half = np.tan(np.radians(camera["fov_y"]) / 2)
    aspect = width / height
    xs, ys = np.meshgrid(np.arange(width) + 0.5, np.arange(height) + 0.5)
    sx = 2 * xs / width - 1
    sy = 1 - 2 * ys / height
    d = w + (sx * aspect * tan_half)[..., None] * u + (sy * tan_half)[..., None] * v
    return eye, unit(d)


def intersect(eye, d, obj):
    """Distance along each ray to the object (inf for a miss), and its
    normal at the hit."""
    if "sphere" in obj:
        c = np.array(obj["sphere"]["center"], float)
        r = obj["sphere"]["radius"]
        oc = eye - c
        b = dot(d, oc)
        disc = b * b - (dot(oc, oc) - r * r)
        root = np.sqrt(np.maximum(disc, 0))
        near, far = -b - root, -b + root
        t = np.where(near > 1e-9, near, np.where(far > 1e-9, far, np.inf))
        t = np.where(disc >= 0, t, np.inf)
        normal = lambda p: (p - c) / r
    else:
        p0 = np.array(obj["plane"]["point"], float)
        n = unit(np.array(obj["plane"]["normal"], float))
        denom = dot(d, n)
        safe = np.where(denom != 0, denom, 1)
        t = np.where(denom != 0, dot(p0 - eye, n) / safe, np.inf)
        t = np.where(t > 1e-9, t, np.inf)
        normal = lambda p: np.broadcast_to(n, p.shape)
    return t, normal


def light(request, material, p, n, deviations):
    """Equation 2.1 at points p with unit normals n, an infinite viewer."""
    model = request["light_model"]
    camera = request["camera"]
    vp_e = unit(np.array(camera["eye"], float) - np.array(camera["target"], float))
    rgb = lambda c: np.array(c[:3], float)
    a_cm, d_cm, s_cm, e_cm = (rgb(material[k]) for k in ("ambient", "diffuse", "specular", "emission"))
    color = np.zeros(p.shape)
    if "emission_missing" not in deviations:
        color += e_cm
    color += a_cm * rgb(model["ambient"])
    for li in request["lights"]:
        position = np.array(li["position"], float)
        if position[3] == 0:
            vp = np.broadcast_to(unit(position[:3]), p.shape)
            att = np.ones(p.shape[:-1])
        else:
            to_light = position[:3] - p
            dist = np.linalg.norm(to_light, axis=-1)
            k0, k1, k2 = li["attenuation"]
            att = 1 / (k0 + k1 * dist + k2 * dist * dist)
            vp = unit(to_light)
        n_vp = dot(n, vp)
        if "phong_specular" in deviations:
            r = 2 * n_vp[..., None] * n - vp
            base = dot(r, vp_e)
        else:
            base = dot(n, unit(vp + vp_e))
        power = np.maximum(base, 0) ** material["shininess"]
        gate = (n_vp > 0).astype(float)
        terms = (
            a_cm * rgb(li["ambient"])
            + np.maximum(n_vp, 0)[..., None] * d_cm * rgb(li["diffuse"])
            + (gate * power)[..., None] * s_cm * rgb(li["specular"])
        )
        color += att[..., None] * terms
    return np.clip(color, 0, 1)


def render(request, deviations):
    camera = request["camera"]
    eye, d = rays(camera)
    best = np.full(d.shape[:-1], np.inf)
    which = np.full(d.shape[:-1], -1)
    normals = []
    for i, obj in enumerate(request["objects"]):
        t, normal = intersect(eye, d, obj)
        closer = t < best
        best = np.where(closer, t, best)
        which = np.where(closer, i, which)
        normals.append(normal)
    image = np.broadcast_to(np.array(request["background"][:3], float), d.shape).copy()
    for i, obj in enumerate(request["objects"]):
        hit = which == i
        p = eye + best[hit][..., None] * d[hit]
        material = request["materials"][obj["material"]]
        image[hit] = light(request, material, p, normals[i](p), deviations)
    return np.floor(255 * image + 0.5).astype(np.uint8)


def main(argv):
    if argv[1] == "--read":
        picture = Image.open(argv[2])
        x, y = int(argv[3]), int(argv[4])
        print(json.dumps({
            "width": picture.width,
            "height": picture.height,
            "mode": picture.mode,
            "pixel": list(picture.convert("RGB").getpixel((x, y))),
        }))
        return
    with open(argv[1]) as f:
        request = json.load(f)
    Image.fromarray(render(request, argv[3:]), "RGB").save(argv[2])


if __name__ == "__main__":
    main(sys.argv)
