"""Reads the COLOR_0 of every primitive of GLB files with pygltflib, a glTF
reader apart from glint's, and prints them as one line of JSON: per file,
a list of {node, primitive, colors}, the colours as floats (normalised
integers divided by their largest value, as glTF defines them).

Usage: python gltf_colors.py FILE...
"""

import json
import struct
import sys

from pygltflib import GLTF2

# componentType: struct format, bytes, largest value of a normalised integer
COMPONENTS = {5121: ("B", 1, 255.0), 5123: ("H", 2, 65535.0), 5126: ("f", 4, None)}
WIDTHS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}


def accessor_values(gltf, blob, index):
    accessor = gltf.accessors[index]
    view = gltf.bufferViews[accessor.bufferView]
    fmt, size, largest = COMPONENTS[accessor.componentType]
    width = WIDTHS[accessor.type]
    start = (view.byteOffset or 0) + (accessor.byteOffset or 0)
    stride = view.byteStride or size * width
    values = []
    for i in range(accessor.count):
        element = struct.unpack_from("<" + fmt * width, blob, start + i * stride)
        if accessor.normalized:
            element = [x / largest for x in element]
        values.append(list(element))
    return values


def main(files):
    out = {}
    for path in files:
        gltf = GLTF2().load(path)
        blob = gltf.binary_blob()
        runs = []
        for n, node in enumerate(gltf.nodes):
            if node.mesh is None:
                continue
            for p, primitive in enumerate(gltf.meshes[node.mesh].primitives):
                color = primitive.attributes.COLOR_0
                if color is None:
                    continue
                runs.append({"node": n, "primitive": p, "colors": accessor_values(gltf, blob, color)})
        out[path] = runs
    print(json.dumps(out))


if __name__ == "__main__":
    main(sys.argv[1:])
