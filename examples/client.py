"""A Python client of glint, generated from its contract.

Generate the client package `glint_client` from `api/openapi.yaml`:

    pip install openapi-python-client==0.29.1
    openapi-python-client generate --path api/openapi.yaml \
        --config api/openapi-python-client.yaml --meta none --output-path glint_client

Then, with glint serving (`glint serve`) and the package on the path:

    PYTHONPATH=. python examples/client.py [BASE_URL] [OUT.png]

It shades one vertex with GL's defaults, renders a red sphere, and prints
what it read as one line of JSON; with OUT.png it also saves the picture.
"""

import base64
import json
import struct
import sys

from glint_client import Client
from glint_client.api.lighting import render, shade
from glint_client.models import (
    Camera,
    Light,
    Material,
    Problem,
    RenderRequest,
    RenderRequestMaterials,
    SceneObject,
    ShadeRequest,
    Sphere,
    Vertices,
)


def png_size(png: bytes) -> tuple[int, int]:
    """Width and height from a PNG's IHDR chunk, which comes first."""
    if png[:8] != b"\x89PNG\r\n\x1a\n" or png[12:16] != b"IHDR":
        raise ValueError("not a PNG")
    return struct.unpack(">II", png[16:24])


def main(base_url: str, out: str | None) -> None:
    client = Client(base_url=base_url, raise_on_unexpected_status=True)

    # A vertex at the origin facing +z, lit by one light with GL_LIGHT0's
    # defaults (white, along +z), with GL's default material.
    shaded = shade.sync(
        client=client,
        body=ShadeRequest(
            lights=[Light()],
            vertices=Vertices(positions=[[0, 0, 0]], normals=[[0, 0, 1]]),
        ),
    )
    if isinstance(shaded, Problem):
        raise SystemExit(f"shade refused: {shaded.detail}")

    # The generated client reads the JSON form of a render (its PNG is in
    # `png_base64`), so it asks for that form.
    materials = RenderRequestMaterials()
    materials["red"] = Material(diffuse=[1, 0, 0])
    rendered = render.sync(
        client=client.with_headers({"Accept": "application/json"}),
        body=RenderRequest(
            materials=materials,
            lights=[Light(position=[1, 1, 1, 0])],
            camera=Camera(
                eye=[0, 0, 5], target=[0, 0, 0], up=[0, 1, 0], fov_y=45, width=64, height=48
            ),
            objects=[SceneObject(sphere=Sphere(center=[0, 0, 0], radius=1), material="red")],
        ),
    )
    if isinstance(rendered, Problem):
        raise SystemExit(f"render refused: {rendered.detail}")
    png = base64.b64decode(rendered.png_base64)
    width, height = png_size(png)
    if out:
        with open(out, "wb") as f:
            f.write(png)

    print(
        json.dumps(
            {
                "color": shaded.colors[0],
                "precision": shaded.precision.to_dict(),
                "width": width,
                "height": height,
            }
        )
    )


if __name__ == "__main__":
    main(
        sys.argv[1] if len(sys.argv) > 1 else "http://127.0.0.1:8080",
        sys.argv[2] if len(sys.argv) > 2 else None,
    )
