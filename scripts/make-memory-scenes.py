#!/usr/bin/env python3
"""Writes the scenes scripts/memory-check.sh measures (docs/robustness.md, round four):

    python3 scripts/make-memory-scenes.py mesh DIR TRIANGLES
        DIR/mesh.gltf + mesh.bin: a grid of about TRIANGLES triangles (f32 positions and
        normals, u32 indices) filling the back wall of a closed box, and DIR/mesh.toml.
    python3 scripts/make-memory-scenes.py texture DIR SIZE SAMPLERS [--forge]
        DIR/texture.png: a SIZE x SIZE RGB image (a smooth gradient, so it compresses), and
        DIR/quad.gltf: one quad whose SAMPLERS materials each use the image through a sampler
        of its own (SAMPLERS primitives side by side), and DIR/texture.toml. With --forge the
        PNG is 64 x 64 but its header claims SIZE x SIZE (the decoder refuses it once it
        reads the data: a test of the check made from the header alone).

Standard library only (zlib, struct, array), so it runs wherever the scripts do.
"""
import array
import json
import os
import struct
import sys
import zlib

SCENE = """[render]
resolution = [64, 64]
passes = 1
spp = 1
photons = 10000
mode = "{mode}"

[camera]
position = [0.0, 0.0, -3.0]
look_at = [0.0, 0.0, 0.0]
vfov = 50

[[light]]
position = [0.0, 0.5, -1.0]
flux = 5.0

[material.wall]
kd = 0.5

[[shape]]
type = "box"
min = [-1.0, -1.0, -1.0]
max = [1.0, 1.0, 1.5]
facing = "inside"
material = "wall"

[[shape]]
type = "mesh"
file = "{file}"
"""


def gltf_doc(buffer_uri, buffer_len, views, accessors, extra):
    doc = {
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": buffer_len, "uri": buffer_uri}],
        "bufferViews": views,
        "accessors": accessors,
        "nodes": [{"mesh": 0}],
        "scenes": [{"nodes": [0]}],
    }
    doc.update(extra)
    return doc


def mesh(out, triangles):
    # An n x n grid of quads on z = 0.9, x, y in [-0.9, 0.9]: 2 n^2 triangles.
    n = max(1, int((triangles / 2) ** 0.5))
    pos = array.array("f")
    nor = array.array("f")
    for j in range(n + 1):
        y = -0.9 + 1.8 * j / n
        for i in range(n + 1):
            pos.extend((-0.9 + 1.8 * i / n, y, 0.9))
            nor.extend((0.0, 0.0, -1.0))
    idx = array.array("I")
    w = n + 1
    for j in range(n):
        row = j * w
        for i in range(n):
            a = row + i
            idx.extend((a, a + w, a + 1, a + 1, a + w, a + w + 1))
    if sys.byteorder != "little":
        for a in (pos, nor, idx):
            a.byteswap()
    blobs = [pos.tobytes(), nor.tobytes(), idx.tobytes()]
    views, offset = [], 0
    for b in blobs:
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": len(b)})
        offset += len(b)
    verts = (n + 1) ** 2
    accessors = [
        {"bufferView": 0, "componentType": 5126, "count": verts, "type": "VEC3",
         "min": [-0.9, -0.9, 0.9], "max": [0.9, 0.9, 0.9]},
        {"bufferView": 1, "componentType": 5126, "count": verts, "type": "VEC3"},
        {"bufferView": 2, "componentType": 5125, "count": len(idx), "type": "SCALAR"},
    ]
    extra = {"meshes": [{"primitives": [
        {"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2}]}]}
    with open(os.path.join(out, "mesh.bin"), "wb") as f:
        for b in blobs:
            f.write(b)
    with open(os.path.join(out, "mesh.gltf"), "w") as f:
        json.dump(gltf_doc("mesh.bin", offset, views, accessors, extra), f)
    with open(os.path.join(out, "mesh.toml"), "w") as f:
        f.write(SCENE.format(mode="balance", file="mesh.gltf"))
    print(f"{out}/mesh.gltf: {2 * n * n} triangles, {verts} vertices")


def png(path, width, height, rows):
    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))
    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    z = zlib.compressobj(9)
    data = b"".join(z.compress(b"\0" + r) for r in rows) + z.flush()
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", data)
                + chunk(b"IEND", b""))


def texture(out, size, samplers, forge):
    real = 64 if forge else size
    row = bytes(b for x in range(real) for b in (x * 255 // max(1, real - 1), 128, 64))
    rows = (row for _ in range(real))
    png(os.path.join(out, "texture.png"), real, real, rows)
    if forge:
        # Rewrite IHDR's size (and its CRC) to claim size x size.
        with open(os.path.join(out, "texture.png"), "r+b") as f:
            b = bytearray(f.read())
            b[16:24] = struct.pack(">II", size, size)
            b[29:33] = struct.pack(">I", zlib.crc32(bytes(b[12:29])) & 0xFFFFFFFF)
            f.seek(0)
            f.write(b)
    # samplers quads side by side across x in [-0.9, 0.9] at z = 0.9, each its own material.
    pos = array.array("f")
    uv = array.array("f")
    idx = array.array("I")
    for k in range(samplers):
        x0 = -0.9 + 1.8 * k / samplers
        x1 = -0.9 + 1.8 * (k + 1) / samplers
        pos.extend((x0, 0.9, 0.9, x0, -0.9, 0.9, x1, -0.9, 0.9, x1, 0.9, 0.9))
        uv.extend((0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0, 0.0))
        idx.extend((0, 1, 2, 0, 2, 3))
    if sys.byteorder != "little":
        for a in (pos, uv, idx):
            a.byteswap()
    blobs = [pos.tobytes(), uv.tobytes(), idx.tobytes()]
    views, offset = [], 0
    for b in blobs:
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": len(b)})
        offset += len(b)
    accessors, prims = [], []
    for k in range(samplers):
        accessors += [
            {"bufferView": 0, "byteOffset": 48 * k, "componentType": 5126, "count": 4,
             "type": "VEC3", "min": [-0.9, -0.9, 0.9], "max": [0.9, 0.9, 0.9]},
            {"bufferView": 1, "byteOffset": 32 * k, "componentType": 5126, "count": 4,
             "type": "VEC2"},
            {"bufferView": 2, "byteOffset": 24 * k, "componentType": 5125, "count": 6,
             "type": "SCALAR"},
        ]
        prims.append({"attributes": {"POSITION": 3 * k, "TEXCOORD_0": 3 * k + 1},
                      "indices": 3 * k + 2, "material": k})
    wraps = [33071, 33648, 10497]
    extra = {
        "images": [{"uri": "texture.png"}],
        "samplers": [{"wrapS": wraps[k % 3], "wrapT": wraps[(k // 3) % 3]}
                     for k in range(samplers)],
        "textures": [{"source": 0, "sampler": k} for k in range(samplers)],
        "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": k}}}
                      for k in range(samplers)],
        "meshes": [{"primitives": prims}],
    }
    with open(os.path.join(out, "quad.bin"), "wb") as f:
        for b in blobs:
            f.write(b)
    with open(os.path.join(out, "quad.gltf"), "w") as f:
        json.dump(gltf_doc("quad.bin", offset, views, accessors, extra), f)
    with open(os.path.join(out, "texture.toml"), "w") as f:
        f.write(SCENE.format(mode="balance", file="quad.gltf"))
    print(f"{out}/texture.png: {size}x{size}{' (forged header)' if forge else ''}, "
          f"{samplers} samplers")


def main():
    args = sys.argv[1:]
    if len(args) >= 3 and args[0] == "mesh":
        os.makedirs(args[1], exist_ok=True)
        mesh(args[1], int(args[2]))
    elif len(args) >= 4 and args[0] == "texture":
        os.makedirs(args[1], exist_ok=True)
        texture(args[1], int(args[2]), int(args[3]), "--forge" in args[4:])
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main()
