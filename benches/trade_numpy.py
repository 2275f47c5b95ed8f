"""What a Python user would write instead of glint: the GL 2.1 lighting
equation over NumPy arrays (f32), for the scenes of benches/scenes/.

Run by `cargo bench --bench trade`, which passes the vertex count; prints
`<scene file> <vertices per second>` per scene (the median of 7 runs).
"""

import json
import os
import sys
import time

import numpy as np

SCENES = ["one_directional_diffuse", "one_directional", "eight_positional", "eight_spots"]
HERE = os.path.dirname(os.path.abspath(__file__))


def mesh(count):
    """The same bumpy grid as benches/common/mod.rs."""
    side = int(np.ceil(np.sqrt(count)))
    i = np.arange(count)
    u = (i % side) / side
    v = (i // side) / side
    p = np.stack([u * 4 - 2, v * 4 - 2, -3 + 0.2 * np.sin(u * 9)], axis=1)
    n = np.stack([np.sin(u * 7) * 0.5, np.cos(v * 5) * 0.5, np.ones(count)], axis=1)
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    return p.astype(np.float32), n.astype(np.float32)


def rgb(c, default):
    return np.array((c or default)[:3], dtype=np.float32)


def unit(v):
    length = np.linalg.norm(v, axis=-1, keepdims=True)
    return np.divide(v, length, out=np.zeros_like(v), where=length > 0)


def shade(scene, p, n):
    model = scene.get("light_model", {})
    m = scene.get("material", {})
    a_cm = rgb(m.get("ambient"), [0.2, 0.2, 0.2])
    d_cm = rgb(m.get("diffuse"), [0.8, 0.8, 0.8])
    s_cm = rgb(m.get("specular"), [0, 0, 0])
    e_cm = rgb(m.get("emission"), [0, 0, 0])
    shininess = np.float32(m.get("shininess", 0))
    a_cs = rgb(model.get("ambient"), [0.2, 0.2, 0.2])
    local = model.get("local_viewer", False)
    vp_e = unit(-p) if local else np.array([0, 0, 1], dtype=np.float32)
    primary = np.broadcast_to(e_cm + a_cm * a_cs, p.shape).copy()
    secondary = np.zeros_like(p)
    for light in scene.get("lights", []):
        x, y, z, w = light.get("position", [0, 0, 1, 0])
        if w == 0:
            vp = np.broadcast_to(unit(np.array([x, y, z], dtype=np.float32)), p.shape)
            scale = np.ones(len(p), dtype=np.float32)
        else:
            d = np.array([x, y, z], dtype=np.float32) / w - p
            dist = np.linalg.norm(d, axis=1)
            vp = unit(d)
            k0, k1, k2 = light.get("attenuation", [1, 0, 0])
            scale = 1 / (k0 + k1 * dist + k2 * dist * dist)
            spot = light.get("spot")
            if spot and spot.get("cutoff", 180) != 180:
                s = unit(np.array(spot["direction"], dtype=np.float32))
                cos = np.maximum(-(vp @ s), 0)
                inside = cos >= np.cos(np.radians(spot["cutoff"]))
                scale = scale * np.where(inside, cos ** spot.get("exponent", 0), 0)
        n_dot_vp = np.einsum("ij,ij->i", n, vp)
        lit = np.maximum(n_dot_vp, 0)
        a_cli = rgb(light.get("ambient"), [0, 0, 0])
        d_cli = rgb(light.get("diffuse"), [1, 1, 1])
        s_cli = rgb(light.get("specular"), [1, 1, 1])
        primary += scale[:, None] * (a_cm * a_cli + lit[:, None] * (d_cm * d_cli))
        if s_cm.any():
            h = unit(vp + vp_e)
            n_dot_h = np.maximum(np.einsum("ij,ij->i", n, h), 0)
            f = np.where(n_dot_vp > 0, n_dot_h ** shininess, 0)
            secondary += (scale * f)[:, None] * (s_cm * s_cli)
    if model.get("color_control") == "separate_specular":
        color = np.clip(primary, 0, 1) + np.clip(secondary, 0, 1)
    else:
        color = primary + secondary
    return np.clip(color, 0, 1)


def main():
    count = int(sys.argv[1]) if len(sys.argv) > 1 else 1_000_000
    p, n = mesh(count)
    for name in SCENES:
        with open(os.path.join(HERE, "scenes", name + ".json")) as f:
            scene = json.load(f)
        shade(scene, p, n)
        times = []
        for _ in range(7):
            start = time.perf_counter()
            shade(scene, p, n)
            times.append(time.perf_counter() - start)
        times.sort()
        print(name, count / times[3])


if __name__ == "__main__":
    main()
