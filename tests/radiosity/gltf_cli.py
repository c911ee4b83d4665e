#!/usr/bin/env python3
"""`testbed render --method radiosity --mesh-out FILE.gltf|.glb` checked with
Python's json, base64 and struct only (independent of the writer):

1. The .gltf is strict JSON (no NaN/Infinity), asset.version "2.0", a
   generator naming testbed, provenance in asset.extras (the scene's SHA-256
   and the options), KHR_materials_unlit used and on the material; every
   accessor/bufferView lies inside the buffer and is aligned as the spec
   requires; the data URI decodes to exactly buffer.byteLength bytes.
2. Its mesh against the PLY of the same run options (the solution is
   deterministic): vertex and triangle counts, positions and normals equal,
   COLOR_0 = the PLY's radiance times its display scale clamped to [0, 1]
   and, sRGB-encoded, its 8 bits within one step; the triangles are
   (c0 c1 c2), (c0 c2 c3) of each PLY face; POSITION min/max equal to the
   data's; indices in range.
3. The .glb: header (magic, version 2, total length), a JSON chunk padded
   with spaces, a BIN chunk padded with zeros, buffer 0 without a uri, and
   the same JSON content and binary data as the .gltf.
4. Errors: an unknown extension and an unwritable folder give a clear
   message, a non-zero status and no file.
"""
import base64
import hashlib
import json
import math
import os
import shutil
import struct
import subprocess
import sys

TESTBED = os.environ["TESTBED"]
SRC = os.environ["TB_SOURCE_DIR"]
TMP = os.path.join(os.environ.get("TB_TEST_TMPDIR", "/tmp"), "radiosity_gltf_cli.%d" % os.getpid())
SCENE = os.path.join(SRC, "scenes", "cornell-box-rgb.mid")
OPTS = ["--max-edge", "100", "--samples", "4", "--threshold", "0.05", "--threads", "2"]

failures = []


def check(cond, what):
    if not cond:
        failures.append(what)
        print("FAIL:", what)
    return cond


def run(*args, ok=True):
    r = subprocess.run([TESTBED, "render", "--method", "radiosity"] + list(args), capture_output=True, text=True)
    if ok and r.returncode != 0:
        print(r.stdout, r.stderr)
        sys.exit("FAIL: testbed render %s exited %d" % (" ".join(args), r.returncode))
    return r


def read_ply(path):
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    head = data[:end].decode()
    nv = nf = None
    scale = None
    for line in head.splitlines():
        w = line.split()
        if w[:2] == ["element", "vertex"]:
            nv = int(w[2])
        elif w[:2] == ["element", "face"]:
            nf = int(w[2])
        elif "8-bit sRGB times" in line:
            scale = float(line.split("8-bit sRGB times")[1].split()[0])
    off = end
    verts = []
    for _ in range(nv):
        f = struct.unpack_from("<9f", data, off)
        c = struct.unpack_from("<3B", data, off + 36)
        verts.append((f, c))
        off += 39
    faces = []
    for _ in range(nf):
        (n,) = struct.unpack_from("<B", data, off)
        idx = struct.unpack_from("<%dI" % n, data, off + 1)
        faces.append(idx)
        off += 1 + 4 * n + 4
    check(off == len(data), "PLY: %d bytes read of %d" % (off, len(data)))
    return verts, faces, scale


def srgb_encode(x):
    return 12.92 * x if x <= 0.0031308 else 1.055 * x ** (1 / 2.4) - 0.055


def f32(x):
    return struct.unpack("<f", struct.pack("<f", x))[0]


def no_constants(name):
    raise ValueError("non-JSON number " + name)


COMPONENT = {5126: ("f", 4), 5125: ("I", 4), 5123: ("H", 2), 5121: ("B", 1)}
NCOMP = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}


def accessor(doc, buf, i):
    a = doc["accessors"][i]
    bv = doc["bufferViews"][a["bufferView"]]
    fmt, size = COMPONENT[a["componentType"]]
    n = NCOMP[a["type"]]
    stride = bv.get("byteStride", size * n)
    start = bv.get("byteOffset", 0) + a.get("byteOffset", 0)
    check(start % size == 0, "accessor %d: offset %d not a multiple of %d" % (i, start, size))
    if bv.get("target") == 34962:
        check(start % 4 == 0 and stride % 4 == 0, "accessor %d: vertex attribute not 4-byte aligned" % i)
    last = start + stride * (a["count"] - 1) + size * n
    check(last <= bv.get("byteOffset", 0) + bv["byteLength"], "accessor %d runs past its bufferView" % i)
    check(bv.get("byteOffset", 0) + bv["byteLength"] <= len(buf), "bufferView of accessor %d runs past the buffer" % i)
    return [struct.unpack_from("<%d%s" % (n, fmt), buf, start + k * stride) for k in range(a["count"])]


def check_gltf(doc, buf, verts, faces, scale, scene_sha, label):
    check(doc["asset"]["version"] == "2.0", label + ": asset.version")
    check(doc["asset"].get("generator", "").startswith("testbed "), label + ": asset.generator")
    extras = doc["asset"].get("extras", {})
    prov = extras.get("provenance") or {}
    check(prov.get("scene_sha256") == scene_sha, label + ": provenance scene_sha256")
    check("max_edge=100" in prov.get("options", ""), label + ": provenance options")
    check(abs(extras.get("display_scale", 0) - scale) <= 1e-8 * scale, label + ": display_scale vs the PLY's")
    check("KHR_materials_unlit" in doc.get("extensionsUsed", []), label + ": extensionsUsed")
    prim = doc["meshes"][doc["nodes"][doc["scenes"][doc.get("scene", 0)]["nodes"][0]]["mesh"]]["primitives"][0]
    check(prim.get("mode", 4) == 4, label + ": triangles")
    check("KHR_materials_unlit" in doc["materials"][prim["material"]].get("extensions", {}), label + ": unlit")
    attrs = prim["attributes"]
    for k in ("POSITION", "NORMAL", "COLOR_0"):
        check(k in attrs, label + ": attribute " + k)
    for k in attrs:
        check(k in ("POSITION", "NORMAL", "COLOR_0", "TEXCOORD_0") or k.startswith("_"),
              label + ": application-specific attribute %s must start with _" % k)
    pos = accessor(doc, buf, attrs["POSITION"])
    nrm = accessor(doc, buf, attrs["NORMAL"])
    col = accessor(doc, buf, attrs["COLOR_0"])
    idx = [i[0] for i in accessor(doc, buf, prim["indices"])]
    check(len(pos) == len(verts) == len(nrm) == len(col), label + ": %d vertices, PLY %d" % (len(pos), len(verts)))
    # POSITION min/max: required, and exactly the data's (as float32)
    pa = doc["accessors"][attrs["POSITION"]]
    for c in range(3):
        lo = min(p[c] for p in pos)
        hi = max(p[c] for p in pos)
        check(f32(pa["min"][c]) == lo and f32(pa["max"][c]) == hi,
              label + ": POSITION min/max %s %s, data %g %g" % (pa["min"][c], pa["max"][c], lo, hi))
    bad = 0
    for i, ((f, c8), p, n, c) in enumerate(zip(verts, pos, nrm, col)):
        if tuple(p) != tuple(f[0:3]) or tuple(n) != tuple(f[3:6]):
            bad += 1
            continue
        check(abs(math.sqrt(sum(x * x for x in n)) - 1) < 1e-5, label + ": normal %d not unit" % i)
        for k in range(3):
            want = min(max(f[6 + k] * scale, 0.0), 1.0)
            if not (abs(c[k] - want) <= 2e-6 * max(want, 1e-3) and abs(255 * srgb_encode(c[k]) - c8[k]) <= 0.501):
                bad += 1
    check(bad == 0, label + ": %d vertex mismatches against the PLY" % bad)
    tris = []
    for fc in faces:
        for k in range(len(fc) - 2):
            tris += [fc[0], fc[1 + k], fc[2 + k]]
    check(idx == tris, label + ": triangles are not the PLY faces' (c0 c1 c2), (c0 c2 c3)")
    check(max(idx) < len(pos), label + ": index out of range")
    coloured = sum(1 for c in col if abs(c[0] - c[1]) > 0.05 or abs(c[1] - c[2]) > 0.05)
    check(coloured > len(col) // 10, label + ": only %d coloured vertices" % coloured)


def main():
    shutil.rmtree(TMP, ignore_errors=True)
    os.makedirs(TMP)
    ply, gltf, glb = (os.path.join(TMP, "a." + e) for e in ("ply", "gltf", "glb"))
    run(SCENE, *OPTS, "--mesh-out", ply)
    run(SCENE, *OPTS, "--mesh-out", gltf)
    run(SCENE, *OPTS, "--mesh-out", glb)
    verts, faces, scale = read_ply(ply)
    scene_sha = hashlib.sha256(open(SCENE, "rb").read()).hexdigest()

    # 1, 2: .gltf
    text = open(gltf, "rb").read().decode("utf-8")
    doc = json.loads(text, parse_constant=no_constants)
    check(len(doc["buffers"]) == 1, ".gltf: one buffer")
    uri = doc["buffers"][0]["uri"]
    prefix = "data:application/octet-stream;base64,"
    check(uri.startswith(prefix), ".gltf: data URI")
    buf = base64.b64decode(uri[len(prefix):], validate=True)
    check(len(buf) == doc["buffers"][0]["byteLength"], ".gltf: byteLength %d, data %d" %
          (doc["buffers"][0]["byteLength"], len(buf)))
    check_gltf(doc, buf, verts, faces, scale, scene_sha, ".gltf")

    # 3: .glb
    data = open(glb, "rb").read()
    magic, version, length = struct.unpack_from("<III", data, 0)
    check(magic == 0x46546C67 and version == 2 and length == len(data), ".glb: header")
    jlen, jtype = struct.unpack_from("<II", data, 12)
    check(jtype == 0x4E4F534A and jlen % 4 == 0, ".glb: JSON chunk")
    jbytes = data[20:20 + jlen]
    tail = jbytes[jbytes.rindex(b"}") + 1:]
    check(set(tail) <= set(b" \n") and set(tail[-3:].lstrip(b"\n")) <= {0x20}, ".glb: JSON padded with spaces")
    gdoc = json.loads(jbytes.decode("utf-8"), parse_constant=no_constants)
    boff = 20 + jlen
    blen, btype = struct.unpack_from("<II", data, boff)
    check(btype == 0x004E4942 and blen % 4 == 0 and boff + 8 + blen == len(data), ".glb: BIN chunk")
    gbuf = data[boff + 8:boff + 8 + blen]
    check("uri" not in gdoc["buffers"][0], ".glb: buffer 0 has no uri")
    check(gdoc["buffers"][0]["byteLength"] <= blen <= gdoc["buffers"][0]["byteLength"] + 3, ".glb: BIN length")
    check(set(gbuf[gdoc["buffers"][0]["byteLength"]:]) <= {0}, ".glb: BIN padded with zeros")
    check(gbuf[:gdoc["buffers"][0]["byteLength"]] == buf, ".glb: the same binary data as the .gltf")
    for d in (doc, gdoc):
        d["buffers"][0].pop("uri", None)
        d["asset"]["extras"]["provenance"].pop("time_utc", None)
        d["asset"]["extras"]["provenance"].pop("command_line", None)
    check(doc == gdoc, ".glb: the same JSON as the .gltf (but the uri, time and command line)")
    check_gltf(gdoc, gbuf, verts, faces, scale, scene_sha, ".glb")

    # 4: errors leave no file
    for path, want in ((os.path.join(TMP, "x.obj"), "unknown mesh format"),
                       (os.path.join(TMP, "missing", "x.gltf"), "missing/x.gltf"),
                       (os.path.join(TMP, "missing", "x.glb"), "missing/x.glb")):
        r = run(SCENE, *OPTS, "--mesh-out", path, ok=False)
        check(r.returncode != 0 and want in r.stderr, "error for %s: %d %s" % (path, r.returncode, r.stderr))
        check(not os.path.exists(path), "a file was left at " + path)
    check(sorted(os.listdir(TMP)) == ["a.glb", "a.gltf", "a.ply"], "stray files: %s" % os.listdir(TMP))

    if failures:
        sys.exit("%d failures" % len(failures))
    shutil.rmtree(TMP)
    print("OK: %d vertices, %d faces" % (len(verts), len(faces)))


main()
