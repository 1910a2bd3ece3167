#!/usr/bin/env python3
"""Writes scenes/cornell-box.toml from Mitsuba 3's own Cornell box (mitsuba.cornell_box()):
the same rectangles and cubes (each transformed by its to_world, as quads), reflectances,
area emitter and camera. Run: python3 scripts/mitsuba-cornell-box.py > scenes/cornell-box.toml
(pip mitsuba 3.9.1; the scalar_rgb variant)."""
import mitsuba as mi

mi.set_variant("scalar_rgb")
d = mi.cornell_box()


def point(t, p):
    v = t @ mi.ScalarPoint3f(*p)
    return [round(float(c), 6) + 0.0 for c in v]


def quad(t, corners, material):
    vs = ", ".join("[%s]" % ", ".join(repr(c) for c in point(t, p)) for p in corners)
    return f'[[shape]]\ntype = "quad"\nvertices = [{vs}]\nmaterial = "{material}"\n'


RECT = [(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)]
# The cube [-1, 1]³'s faces, corners counter-clockwise seen from outside (front = outward).
CUBE = [
    [(1, -1, -1), (1, 1, -1), (1, 1, 1), (1, -1, 1)],
    [(-1, -1, -1), (-1, -1, 1), (-1, 1, 1), (-1, 1, -1)],
    [(-1, 1, -1), (-1, 1, 1), (1, 1, 1), (1, 1, -1)],
    [(-1, -1, -1), (1, -1, -1), (1, -1, 1), (-1, -1, 1)],
    [(-1, -1, 1), (1, -1, 1), (1, 1, 1), (-1, 1, 1)],
    [(-1, -1, -1), (-1, 1, -1), (1, 1, -1), (1, -1, -1)],
]

sensor = d["sensor"]
cam = sensor["to_world"]
pos = point(cam, (0, 0, 0))
look = point(cam, (0, 0, 1))
up = [round(float(c), 6) + 0.0 for c in cam @ mi.ScalarVector3f(0, 1, 0)]
film = sensor["film"]
out = [
    "# cornell-box: the Cornell box exactly as Mitsuba 3 ships it (mitsuba.cornell_box(), pip",
    "# mitsuba 3.9.1), written by scripts/mitsuba-cornell-box.py: its rectangles and cubes as quads",
    "# (each transformed by its to_world), its diffuse reflectances, its area light (Le on the front",
    "# side of the 0.46 m x 0.38 m rectangle under the ceiling; the light's own BSDF is its white)",
    "# and its camera. Differences: bdpm's pixel filter is a box (a pixel's samples are uniform over",
    "# it) where Mitsuba's film defaults to a Gaussian, and bdpm's paths are unbounded where",
    "# mitsuba.cornell_box()'s integrator stops at max_depth 8.",
    "",
    "[render]",
    f"resolution = [{film['width']}, {film['height']}]",
    'output = "out/cornell-box.exr"',
    "",
    "[camera]",
    f"position = {pos}",
    f"look_at = {look}",
    f"up = {up}",
    f"vfov = {sensor['fov']}",
    "",
]
for name in ["white", "red", "green"]:
    r = [float(c) for c in d[name]["reflectance"]["value"]]
    out += [f"[material.{name}]", f"kd = {r}", ""]
le = [float(c) for c in d["light"]["emitter"]["radiance"]["value"]]
out += ["[material.light]", "kd = %s" % [float(c) for c in d["white"]["reflectance"]["value"]],
        f"emission = {le}", ""]
for key in ["floor", "ceiling", "back", "green-wall", "red-wall", "light"]:
    s = d[key]
    material = "light" if key == "light" else s["bsdf"]["id"]
    out.append(f"# {key}")
    out.append(quad(s["to_world"], RECT, material))
for key in ["small-box", "large-box"]:
    s = d[key]
    for face in CUBE:
        out.append(f"# {key}")
        out.append(quad(s["to_world"], face, s["bsdf"]["id"]))
print("\n".join(out).rstrip())
