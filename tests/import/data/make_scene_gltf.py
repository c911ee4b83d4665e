#!/usr/bin/env python3
"""Writes scene.gltf + scene.bin, the hand-made glTF 2.0 test scene of
tests/import: nested node transforms (TRS and matrix), a mesh placed twice,
three metallic-roughness materials and a primitive without one, a perspective
and an orthographic camera, and KHR_lights_punctual point, spot and
directional lights. Every number is exact in binary so the test can compare
the import bit for bit. Run it from this folder; the output is committed."""
import json
import struct

# (name, positions, indices or None, material or None)
prims = [
    ("quad", [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)], [0, 1, 2, 0, 2, 3], 0),
    ("tri", [(0, 0, 1), (1, 0, 1), (0.5, 1, 1.5)], [0, 1, 2], 1),
    ("plain", [(2, 0, 0), (3, 0, 0), (2, 1, 0)], [0, 1, 2], None),
    ("shade", [(0, 0, 0), (0.5, 0, 0), (0, 0.5, 0)], None, 2),
]

buf = bytearray()
views, accessors, gl_prims = [], [], []
for name, pos, idx, mat in prims:
    off = len(buf)
    for p in pos:
        buf += struct.pack("<3f", *p)
    views.append({"buffer": 0, "byteOffset": off, "byteLength": 12 * len(pos), "target": 34962})
    mn = [min(p[i] for p in pos) for i in range(3)]
    mx = [max(p[i] for p in pos) for i in range(3)]
    accessors.append({"bufferView": len(views) - 1, "componentType": 5126, "count": len(pos),
                      "type": "VEC3", "min": mn, "max": mx})
    prim = {"attributes": {"POSITION": len(accessors) - 1}}
    if idx is not None:
        off = len(buf)
        for i in idx:
            buf += struct.pack("<H", i)
        while len(buf) % 4:
            buf += b"\0"
        views.append({"buffer": 0, "byteOffset": off, "byteLength": 2 * len(idx), "target": 34963})
        accessors.append({"bufferView": len(views) - 1, "componentType": 5123, "count": len(idx),
                          "type": "SCALAR"})
        prim["indices"] = len(accessors) - 1
    if mat is not None:
        prim["material"] = mat
    gl_prims.append(prim)

h = 0.70710677  # sin 45 degrees as a float
gltf = {
    "asset": {"version": "2.0", "generator": "tests/import/data/make_scene_gltf.py"},
    "extensionsUsed": ["KHR_lights_punctual"],
    "extensions": {"KHR_lights_punctual": {"lights": [
        {"name": "bulb", "type": "point", "color": [1, 0.5, 0.25], "intensity": 1366, "range": 50},
        {"name": "spot", "type": "spot", "color": [1, 1, 1], "intensity": 683,
         "spot": {"innerConeAngle": 0.25, "outerConeAngle": 0.5}},
        {"name": "sun", "type": "directional", "color": [0.5, 0.5, 0.5], "intensity": 2049},
    ]}},
    "scene": 0,
    "scenes": [{"nodes": [0]}],
    "nodes": [
        {"name": "root", "translation": [1, 2, 3], "children": [1, 2, 3, 4, 5, 6]},
        {"name": "body", "mesh": 0, "rotation": [0, 0.6, 0, 0.8], "scale": [2, 2, 2]},
        {"name": "panel A", "mesh": 1, "translation": [0, 0, -4]},
        {"name": "panel B", "mesh": 1, "matrix": [0.5, 0, 0, 0, 0, 0.5, 0, 0, 0, 0, 0.5, 0, 4, 0, 0, 1]},
        {"name": "cam", "camera": 0, "translation": [0, 1, 10], "rotation": [0, h, 0, h]},
        {"name": "cam2", "camera": 1, "translation": [0, 0, 5]},
        {"name": "lights", "children": [7, 8, 9]},
        {"name": "bulb", "translation": [0, 5, 0], "extensions": {"KHR_lights_punctual": {"light": 0}}},
        {"name": "spot", "translation": [2, 5, 0], "rotation": [-h, 0, 0, h],
         "extensions": {"KHR_lights_punctual": {"light": 1}}},
        {"name": "sun", "extensions": {"KHR_lights_punctual": {"light": 2}}},
    ],
    "cameras": [
        {"name": "cam", "type": "perspective",
         "perspective": {"yfov": 0.5, "aspectRatio": 1.5, "znear": 0.1, "zfar": 100}},
        {"name": "cam2", "type": "orthographic",
         "orthographic": {"xmag": 1, "ymag": 1, "znear": 0.1, "zfar": 100}},
    ],
    "meshes": [
        {"name": "pair", "primitives": gl_prims[0:3]},
        {"name": "shade", "primitives": gl_prims[3:4]},
    ],
    "materials": [
        {"name": "dielectric", "pbrMetallicRoughness": {
            "baseColorFactor": [0.5, 0.25, 1, 1], "metallicFactor": 0, "roughnessFactor": 0.5}},
        {"name": "metal", "pbrMetallicRoughness": {
            "baseColorFactor": [1, 0.5, 0.25, 1], "metallicFactor": 1, "roughnessFactor": 0.25}},
        {"name": "emitter", "pbrMetallicRoughness": {
            "baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0, "roughnessFactor": 1},
         "emissiveFactor": [1, 0.5, 0.25]},
    ],
    "buffers": [{"uri": "scene.bin", "byteLength": len(buf)}],
    "bufferViews": views,
    "accessors": accessors,
}
with open("scene.bin", "wb") as f:
    f.write(buf)
with open("scene.gltf", "w") as f:
    json.dump(gltf, f, indent=1)
    f.write("\n")
