#!/usr/bin/env python3
"""Writes scenes/gltf/EmissiveRoom/: a small closed room in glTF 2.0 lit only by emissive
materials (issue 46, item 5), which scenes/emissive-room.toml renders.

    python3 scripts/make-emissive-room.py            # writes the four files below
    python3 scripts/make-emissive-room.py --check    # exits 1 if the files differ from it

Python's standard library only (json, struct, zlib): anyone can regenerate the files.

  EmissiveRoom.gltf  the JSON: nodes, meshes, materials, one texture
  EmissiveRoom.bin   the buffer: float32 positions, normals and texture coordinates, uint16
                     indices, little-endian
  sign.png           the sign's emissive texture: 64 x 16 texels, 8-bit sRGB RGB
  README.md          what the files are, and their licence (the project's: MIT OR Apache-2.0)

The room spans x in [-1, 1], y in [0, 2], z in [-1, 1] metres (glTF's y up), walls facing
inwards: white floor, ceiling, back and front walls (baseColorFactor 0.7), a red left and a
green right wall, and a white block on the floor. Its light comes from two emitters:

  panel  a 0.5 m x 0.5 m square 1 cm below the ceiling, facing down (one-sided): emissiveFactor
         [1.0, 0.9, 0.75] x KHR_materials_emissive_strength 10, so Le = [10, 9, 7.5] W/(m^2 sr)
  sign   a 1.2 m x 0.3 m sign 1 cm in front of the back wall, facing the room: emissiveFactor
         [1, 1, 1] x emissiveStrength 6 x emissiveTexture (sign.png: the letters "bdpm" in
         orange on a dark blue ground with a cyan rule above and below, sampled with
         clamp-to-edge), so Le = 6 x the texel's linear (sRGB-decoded) value

Every material sets metallicFactor 0 (a glTF material without it is a rough metal, which bdpm
renders as Lambert with a warning) and roughnessFactor 1.
"""
import json
import os
import struct
import sys
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "..", "scenes", "gltf", "EmissiveRoom")

PANEL_FACTOR = [1.0, 0.9, 0.75]
PANEL_STRENGTH = 10.0
SIGN_STRENGTH = 6.0
SIGN_SIZE = (64, 16)  # texels: width, height

# A 5 x 7 bitmap of each letter of the sign, rows from the top ('#' lit).
FONT = {
    "b": ["#....", "#....", "####.", "#...#", "#...#", "#...#", "####."],
    "d": ["....#", "....#", ".####", "#...#", "#...#", "#...#", ".####"],
    "p": ["####.", "#...#", "#...#", "####.", "#....", "#....", "#...."],
    "m": [".....", "##.#.", "#.#.#", "#.#.#", "#.#.#", "#.#.#", "#.#.#"],
}
GROUND = (10, 12, 40)  # sRGB codes
INK = (255, 150, 30)
RULE = (40, 200, 220)


def sign_texels():
    """The sign's texels, row-major from the top, as sRGB codes (r, g, b)."""
    w, h = SIGN_SIZE
    img = [[GROUND for _ in range(w)] for _ in range(h)]
    for x in range(w):
        img[0][x] = RULE
        img[h - 1][x] = RULE
    # Letters at twice their size: 10 x 14 texels each, 4 texels apart, centred.
    scale, gap = 2, 4
    width = len("bdpm") * 5 * scale + (len("bdpm") - 1) * gap
    x0, y0 = (w - width) // 2, 1
    for k, ch in enumerate("bdpm"):
        left = x0 + k * (5 * scale + gap)
        for row, bits in enumerate(FONT[ch]):
            for col, bit in enumerate(bits):
                if bit != "#":
                    continue
                for dy in range(scale):
                    for dx in range(scale):
                        img[y0 + row * scale + dy][left + col * scale + dx] = INK
    return img


def png(img):
    """An 8-bit RGB PNG of `img` (rows of (r, g, b)), filter 0 on every row."""
    h, w = len(img), len(img[0])
    raw = b"".join(b"\x00" + bytes(c for px in row for c in px) for row in img)

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
        + chunk(b"IDAT", zlib.compress(raw, 9))
        + chunk(b"IEND", b"")
    )


def sub(a, b):
    return [a[i] - b[i] for i in range(3)]


def add(*vs):
    return [sum(v[i] for v in vs) for i in range(3)]


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def quad(corner, e1, e2, uv=None):
    """A rectangle c, c+e1, c+e1+e2, c+e2: counter-clockwise seen from the side e1 x e2
    points to (glTF's front face), its normal that way. Returns (positions, normals, uvs,
    indices) with indices local to the quad."""
    p = [corner, add(corner, e1), add(corner, e1, e2), add(corner, e2)]
    n = cross(e1, e2)
    length = sum(c * c for c in n) ** 0.5
    n = [c / length for c in n]
    return p, [n] * 4, uv, [0, 1, 2, 0, 2, 3]


def mesh_of(quads):
    """Joins quads into one primitive's arrays."""
    pos, nor, uvs, idx = [], [], [], []
    for p, n, uv, ind in quads:
        base = len(pos)
        pos += p
        nor += n
        if uv is not None:
            uvs += uv
        idx += [base + i for i in ind]
    return pos, nor, (uvs or None), idx


def room_meshes():
    """name -> (positions, normals, uvs or None, indices)."""
    X, Y, Z = [2.0, 0, 0], [0, 2.0, 0], [0, 0, 2.0]
    block_min, size = [0.2, 0.0, -0.6], [0.5, 0.6, 0.5]
    bx, by, bz = [size[0], 0, 0], [0, size[1], 0], [0, 0, size[2]]
    b0, b1 = block_min, add(block_min, [size[0], size[1], size[2]])
    # Outward faces, each (corner, e1, e2) with e1 x e2 pointing out of the block; no bottom
    # face (it stands on the floor).
    block = [
        quad(b0, bz, by),  # x = min, normal -x (z x y = -x)
        quad([b1[0], b0[1], b0[2]], by, bz),  # x = max, normal +x
        quad([b0[0], b1[1], b0[2]], bz, bx),  # y = max, normal +y
        quad(b0, by, bx),  # z = min, normal -z (y x x = -z)
        quad([b0[0], b0[1], b1[2]], bx, by),  # z = max, normal +z
    ]
    sign_uv = [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]]
    return {
        "white walls": mesh_of([
            quad([-1, 0, -1], Z, X),  # floor, normal +y
            quad([-1, 2, -1], X, Z),  # ceiling, normal -y
            quad([-1, 0, -1], X, Y),  # back wall, normal +z
            quad([-1, 0, 1], Y, X),  # front wall, normal -z
        ]),
        "red wall": mesh_of([quad([-1, 0, -1], Y, Z)]),  # x = -1, normal +x
        "green wall": mesh_of([quad([1, 0, -1], Z, Y)]),  # x = +1, normal -x
        "block": mesh_of(block),
        "panel": mesh_of([quad([-0.25, 1.99, -0.25], [0.5, 0, 0], [0, 0, 0.5])]),  # normal -y
        "sign": mesh_of([quad([-0.6, 1.2, -0.99], [1.2, 0, 0], [0, 0.3, 0], sign_uv)]),
    }


MATERIALS = {
    "white walls": {"base": [0.7, 0.7, 0.7]},
    "red wall": {"base": [0.6, 0.1, 0.1]},
    "green wall": {"base": [0.1, 0.5, 0.1]},
    "block": {"base": [0.7, 0.7, 0.6]},
    "panel": {"base": [0.8, 0.8, 0.8], "emissive": PANEL_FACTOR, "strength": PANEL_STRENGTH},
    "sign": {"base": [0.05, 0.05, 0.05], "emissive": [1.0, 1.0, 1.0],
             "strength": SIGN_STRENGTH, "texture": 0},
}


def build():
    """(gltf JSON text, bin bytes, png bytes, README text)."""
    meshes = room_meshes()
    buf = bytearray()
    views, accessors = [], []

    def view(data, target):
        while len(buf) % 4:
            buf.append(0)
        views.append({"buffer": 0, "byteOffset": len(buf), "byteLength": len(data),
                      "target": target})
        buf.extend(data)
        return len(views) - 1

    def floats(rows, kind):
        data = b"".join(struct.pack("<" + "f" * len(r), *r) for r in rows)
        acc = {"bufferView": view(data, 34962), "componentType": 5126, "count": len(rows),
               "type": kind}
        if kind == "VEC3":
            acc["min"] = [min(r[i] for r in rows) for i in range(3)]
            acc["max"] = [max(r[i] for r in rows) for i in range(3)]
        accessors.append(acc)
        return len(accessors) - 1

    def indices(idx):
        data = struct.pack("<" + "H" * len(idx), *idx)
        accessors.append({"bufferView": view(data, 34963), "componentType": 5123,
                          "count": len(idx), "type": "SCALAR"})
        return len(accessors) - 1

    names = list(MATERIALS)
    materials, primitives = [], []
    for m, name in enumerate(names):
        spec = MATERIALS[name]
        mat = {"name": name, "pbrMetallicRoughness": {
            "baseColorFactor": spec["base"] + [1.0], "metallicFactor": 0.0,
            "roughnessFactor": 1.0}}
        if "emissive" in spec:
            mat["emissiveFactor"] = spec["emissive"]
            mat["extensions"] = {"KHR_materials_emissive_strength": {
                "emissiveStrength": spec["strength"]}}
        if "texture" in spec:
            mat["emissiveTexture"] = {"index": spec["texture"]}
        materials.append(mat)
        pos, nor, uvs, idx = meshes[name]
        attributes = {"POSITION": floats(pos, "VEC3"), "NORMAL": floats(nor, "VEC3")}
        if uvs is not None:
            attributes["TEXCOORD_0"] = floats(uvs, "VEC2")
        primitives.append({"attributes": attributes, "indices": indices(idx), "material": m})
    doc = {
        "asset": {"version": "2.0",
                  "generator": "bdpm scripts/make-emissive-room.py",
                  "copyright": "bdpm contributors, MIT OR Apache-2.0"},
        "extensionsUsed": ["KHR_materials_emissive_strength"],
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "room", "mesh": 0}],
        "meshes": [{"name": "room", "primitives": primitives}],
        "materials": materials,
        "textures": [{"sampler": 0, "source": 0}],
        "samplers": [{"wrapS": 33071, "wrapT": 33071}],
        "images": [{"uri": "sign.png"}],
        "buffers": [{"uri": "EmissiveRoom.bin", "byteLength": len(buf)}],
        "bufferViews": views,
        "accessors": accessors,
    }
    text = json.dumps(doc, indent=1) + "\n"
    return text, bytes(buf), png(sign_texels()), README


README = """# EmissiveRoom

A small closed room lit only by emissive glTF materials: a ceiling panel (`emissiveFactor` x
`KHR_materials_emissive_strength`) and a sign with an `emissiveTexture` (`sign.png`). Written
by `python3 scripts/make-emissive-room.py` (edit the script, not these files); rendered by
`scenes/emissive-room.toml`. The script's docstring gives the geometry and every number.

Licence: the project's own, MIT OR Apache-2.0 (LICENSE-MIT, LICENSE-APACHE at the root).
"""


def main():
    files = dict(zip(["EmissiveRoom.gltf", "EmissiveRoom.bin", "sign.png", "README.md"],
                     build()))
    check = "--check" in sys.argv[1:]
    stale = []
    os.makedirs(OUT, exist_ok=True)
    for name, data in files.items():
        data = data.encode() if isinstance(data, str) else data
        path = os.path.join(OUT, name)
        if check:
            try:
                with open(path, "rb") as f:
                    same = f.read() == data
            except OSError:
                same = False
            if not same:
                stale.append(path)
        else:
            with open(path, "wb") as f:
                f.write(data)
    if stale:
        print("differs from the script: " + ", ".join(stale), file=sys.stderr)
        sys.exit(1)


if __name__ == "__main__":
    main()
