#!/usr/bin/env python3
"""Renders a bdpm TOML scene with mirrors and glass in Mitsuba 3 and in bdpm, and compares them.

The scene is rebuilt in Mitsuba 3 through its Python dict API, triangle for triangle: quads,
boxes and geodesic spheres are expanded exactly as crates/geometry/src/shapes.rs does (the same
icosahedron, subdivision and winding), written as PLY meshes: flat facets, except smooth
spheres (bdpm's default), which carry the sphere's normal at each vertex as bdpm's do. With
`--analytic-spheres` Mitsuba renders its analytic `sphere` instead: the difference between the
geodesic sphere bdpm renders and a true sphere (docs/results.md, "Smooth spheres"). Materials map as

  Lambert (kd, no lobe)   -> `twosided` `diffuse` (reflectance kd)
  type = "mirror"         -> `twosided` `conductor`: specular_reflectance = reflectance, and
                             eta/k when the file gives them (else Mitsuba's 100 % mirror)
  type = "dielectric"     -> `dielectric`, int_ior = ior, ext_ior = 1, reflect_tint and
                             transmit_tint as specular_reflectance / specular_transmittance
  point light, flux Phi   -> `point` with intensity Phi/(4 pi) W/sr
  camera                  -> `perspective`, fov = vfov, fov_axis y, box reconstruction filter

Mitsuba has no counterpart of bdpm's Gaussian lobe (gr > 0): such a scene is refused unless
`--lambert-copy` is given, which writes a copy of the TOML without the lobes (gr and delta
removed, kd kept) into the output directory and renders that copy in both renderers.

What each comparison checks:

  bdpm `light` vs Mitsuba `ptracer` (masked): both are light tracers, unbiased for every path
      whose camera ray first hits a non-delta surface; Mitsuba's ptracer cannot connect to the
      camera through a mirror or glass, so pixels whose camera rays hit a delta surface first
      (any of 16 stratified rays per pixel) are masked out. This checks bdpm's photon tracing
      through mirrors and glass (caustics on diffuse surfaces seen directly, L-S*-D-E) and its
      materials, light and camera against an independent renderer.
  bdpm BDPM modes (`balance` by default) vs Mitsuba `ptracer` (masked): the same pixels, for
      the mixed estimator: what merging photons at x0 and x1 adds, and its bias (the merge
      radius blurs caustic edges, which shows as blocks outside 4 sigma).
  bdpm `path` vs Mitsuba `path` (all pixels): both are path tracers with next-event estimation
      that, with a point light, cannot sample light that reached a diffuse surface through a
      mirror or glass (caustics); they estimate the same partial transport on every pixel,
      including what is seen in mirrors and through glass. This checks bdpm's camera-side
      delta walk (reflection, refraction, Fresnel weights, total internal reflection).

Pixels seen first through glass or in a mirror under full transport (the mirrored caustic of
scenes/mirror-caustic.toml) have no Mitsuba reference here: neither integrator samples them.

Statistics, per comparison: the ratio of the two image means (over the compared pixels) with
its standard error; per-pixel z-scores (bdpm's `stderr` EXR layer, Mitsuba's spread over its
independent runs); per-block z-scores over 32 x 32-pixel blocks (each channel), where the
block means' standard errors come from the spread of per-pass block means (bdpm: the passes of
`--accumulate`'s OUT.accum.exr; Mitsuba: its runs) because the pixels of one bdpm pass share a
photon map and are not independent; and the fraction of pixels and of blocks within 4 sigma.

`--equal-time SECONDS --reference REF.exr`: renders the scene with bdpm's own settings
(`bdpm render --time-budget SECONDS`; the wall time it took, preparation included, is the
budget of the others) and Mitsuba's `ptracer` and `path` for that wall time (4 spp at a time
until it is spent), 2 threads each (--threads), at the reference's resolution (render the
reference at 256^2), and prints rel. RMSE (RMSE over the reference's mean) and relMSE (mean
of (I - R)^2 / (R^2 + 1e-4 R_mean^2)) against the reference, over all pixels and over the
pixels whose camera rays first hit a non-delta surface (ptracer leaves the others black).

Needs (not project dependencies): `pip install mitsuba numpy OpenEXR`; the llvm variant needs
libLLVM (DRJIT_LIBLLVM_PATH; without it the newest /usr/lib/*-linux-gnu/libLLVM-N.so), else
`--variant scalar_rgb`.

Usage:
  scripts/mitsuba-specular.py SCENE.toml [--resolution 128] [--out DIR] [--bdpm BIN]
      [--modes balance] [--passes 16] [--photons N] [--spp N] [--mitsuba-spp N] [--runs 16]
      [--lambert-copy] [--analytic-spheres] [--variant llvm_ad_rgb] [--threads 2]
      [--equal-time SECONDS --reference REF.exr]
"""
import argparse
import json
import math
import os
import re
import subprocess
import sys
import time
import tomllib

import numpy as np

BLOCK = 32
SIGMAS = 4.0
# --analytic-spheres: Mitsuba renders its own analytic spheres instead of bdpm's geodesic ones.
ANALYTIC_SPHERES = False


def fail(msg):
    """Exits with a one-line error."""
    print(f"mitsuba-specular: {msg}", file=sys.stderr)
    sys.exit(2)


# ---------------------------------------------------------------- scene geometry (bdpm's)

BOX_FACES = [  # name, outward normal, u, v with u x v = normal (crates/geometry/src/shapes.rs)
    ("+x", (1, 0, 0), (0, 1, 0), (0, 0, 1)),
    ("-x", (-1, 0, 0), (0, 0, 1), (0, 1, 0)),
    ("+y", (0, 1, 0), (0, 0, 1), (1, 0, 0)),
    ("-y", (0, -1, 0), (1, 0, 0), (0, 0, 1)),
    ("+z", (0, 0, 1), (1, 0, 0), (0, 1, 0)),
    ("-z", (0, 0, -1), (0, 1, 0), (1, 0, 0)),
]


def rgb(value, field, path):
    """An RGB value of the TOML (a number or [r, g, b]) as a list of 3 floats."""
    if isinstance(value, (int, float)):
        return [float(value)] * 3
    if isinstance(value, list) and len(value) == 3:
        return [float(v) for v in value]
    fail(f"{path}: {field}: expected a number or [r, g, b], found {value!r}")


def quad_tris(corners):
    """The two triangles (0, 1, 2), (0, 2, 3) of a quad, as bdpm splits it."""
    c = np.asarray(corners, dtype=np.float64)
    return [c[[0, 1, 2]], c[[0, 2, 3]]]


def placement(shape, field, path):
    """The (scale, translate) of a quad or box."""
    scale = shape.get("scale", 1.0)
    scale = np.array(rgb(scale, f"{field}.scale", path))
    translate = np.array(shape.get("translate", [0.0, 0.0, 0.0]), dtype=np.float64)
    return scale, translate


def box_tris(shape, field, path):
    """The triangles of a `box` shape (its `open` faces left out, its `facing` applied)."""
    scale, translate = placement(shape, field, path)
    a = np.array(shape["min"], dtype=np.float64) * scale + translate
    b = np.array(shape["max"], dtype=np.float64) * scale + translate
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    center, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
    opened = set(shape.get("open", []))
    inward = shape.get("facing", "outside") == "inside"
    tris = []
    for name, n, u, v in BOX_FACES:
        if name in opened:
            continue
        n, u, v = (np.array(x, dtype=np.float64) for x in (n, u, v))
        c, uu, vv = center + n * half, u * half, v * half
        quad = [c - uu - vv, c + uu - vv, c + uu + vv, c - uu + vv]
        if inward:
            quad = [quad[0], quad[3], quad[2], quad[1]]
        tris += quad_tris(quad)
    return tris


def icosahedron():
    """The unit icosahedron of crates/geometry/src/shapes.rs: vertices and faces, same order."""
    t = (1.0 + math.sqrt(5.0)) / 2.0
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
         (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
         (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
         (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    return np.array(v, dtype=np.float64), f


def sphere_tris(shape):
    """A geodesic sphere's triangles, as TriangleMesh::push_geodesic_sphere builds them."""
    center = np.array(shape.get("center", [0.0, 0.0, 0.0]), dtype=np.float64)
    radius = float(shape["radius"])
    n = max(int(shape.get("subdivisions", 16)), 1)
    inward = shape.get("facing", "outside") == "inside"
    ico, faces = icosahedron()
    tris = []
    for fa, fb, fc in faces:
        a, b, c = ico[fa], ico[fb], ico[fc]
        grid = {}
        for i in range(n + 1):
            for j in range(n + 1 - i):
                p = a * (n - i - j) / n + b * i / n + c * j / n
                grid[i, j] = center + radius * p / np.linalg.norm(p)
        for i in range(n):
            for j in range(n - i):
                tris.append(orient(center, grid[i, j], grid[i + 1, j], grid[i, j + 1], inward))
                if i + j + 1 < n:
                    tris.append(
                        orient(center, grid[i + 1, j], grid[i + 1, j + 1], grid[i, j + 1], inward))
    return tris


def orient(center, p0, p1, p2, inward):
    """A sphere triangle wound to face away from (or towards) the centre."""
    outward = np.dot(np.cross(p1 - p0, p2 - p0), p0 + p1 + p2 - 3 * center) > 0
    return np.array([p0, p1, p2] if outward != inward else [p0, p2, p1])


def scene_triangles(scene, path, analytic_spheres=False):
    """{(material name, smooth): (T, 3, 3) array of triangles} for the scene's shapes, and the
    list of spheres left analytic. `smooth` groups hold smooth spheres (the default, as bdpm
    renders them: vertex normals along the sphere's own normal)."""
    out, spheres = {}, []
    for k, shape in enumerate(scene.get("shape", [])):
        field = f"shape[{k}]"
        kind = shape.get("type")
        smooth = False
        if kind == "quad":
            scale, translate = placement(shape, field, path)
            corners = np.array(shape["vertices"], dtype=np.float64) * scale + translate
            tris = quad_tris(corners)
        elif kind == "box":
            tris = box_tris(shape, field, path)
        elif kind == "sphere" and analytic_spheres:
            spheres.append(shape)
            continue
        elif kind == "sphere":
            tris = sphere_tris(shape)
            smooth = bool(shape.get("smooth", True))
        else:
            fail(f"{path}: {field}.type: '{kind}' is not rebuilt in Mitsuba "
                 "(quad, box and sphere are)")
        out.setdefault((shape["material"], smooth), []).extend(
            [(t, sphere_normals(shape, t) if smooth else None) for t in tris])
    return {k: v for k, v in out.items()}, spheres


def sphere_normals(shape, tri):
    """The sphere's own unit normals at a triangle's vertices, on its front side."""
    center = np.array(shape.get("center", [0.0, 0.0, 0.0]), dtype=np.float64)
    sign = -1.0 if shape.get("facing", "outside") == "inside" else 1.0
    d = tri - center
    return sign * d / np.linalg.norm(d, axis=1, keepdims=True)


def write_ply(filename, tris, normals=None):
    """Writes triangles as a binary PLY mesh (3 vertices a triangle), with per-vertex normals
    if given ((T, 3, 3) like `tris`)."""
    verts = tris.reshape(-1, 3).astype("<f4")
    props = "property float x\nproperty float y\nproperty float z\n"
    if normals is not None:
        verts = np.hstack([verts, normals.reshape(-1, 3).astype("<f4")])
        props += "property float nx\nproperty float ny\nproperty float nz\n"
    faces = np.empty((len(tris), 4), dtype="<i4")
    faces[:, 0] = 3
    faces[:, 1:] = np.arange(3 * len(tris), dtype="<i4").reshape(-1, 3)
    header = (f"ply\nformat binary_little_endian 1.0\nelement vertex {len(tris) * 3}\n"
              f"{props}"
              f"element face {len(tris)}\nproperty list uchar int vertex_indices\nend_header\n")
    face_bytes = b"".join(
        np.uint8(3).tobytes() + row[1:].tobytes() for row in faces)
    with open(filename, "wb") as f:
        f.write(header.encode())
        f.write(np.ascontiguousarray(verts).tobytes())
        f.write(face_bytes)


# ---------------------------------------------------------------- the Mitsuba scene

def mitsuba_bsdf(name, mat, path):
    """The Mitsuba BSDF dict for a bdpm material, or an error for a Gaussian lobe."""
    kind = mat.get("type", "smooth")
    if kind == "mirror":
        bsdf = {"type": "conductor",
                "specular_reflectance": {"type": "rgb",
                                         "value": rgb(mat.get("reflectance", 1.0),
                                                      f"material.{name}.reflectance", path)}}
        if "eta" in mat:
            bsdf["eta"] = {"type": "rgb", "value": rgb(mat["eta"], f"material.{name}.eta", path)}
            bsdf["k"] = {"type": "rgb", "value": rgb(mat["k"], f"material.{name}.k", path)}
        return {"type": "twosided", "bsdf": bsdf}
    if kind == "dielectric":
        return {"type": "dielectric", "int_ior": float(mat["ior"]), "ext_ior": 1.0,
                "specular_reflectance": {"type": "rgb", "value": rgb(
                    mat.get("reflect_tint", 1.0), f"material.{name}.reflect_tint", path)},
                "specular_transmittance": {"type": "rgb", "value": rgb(
                    mat.get("transmit_tint", 1.0), f"material.{name}.transmit_tint", path)}}
    if any(g > 0 for g in rgb(mat.get("gr", 0.0), f"material.{name}.gr", path)):
        fail(f"{path}: material.{name}.gr: Mitsuba has no counterpart of the Gaussian lobe; "
             "use --lambert-copy to compare the scene without its lobes")
    return {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": {
        "type": "rgb", "value": rgb(mat["kd"], f"material.{name}.kd", path)}}}


def mitsuba_scene(mi, scene, path, res, meshdir, integrator, spp):
    """The Mitsuba scene dict of a bdpm scene at res x res pixels."""
    cam = scene["camera"]
    d = {"type": "scene",
         "integrator": {"type": integrator, "max_depth": -1},
         "sensor": {"type": "perspective", "fov": float(cam["vfov"]), "fov_axis": "y",
                    "near_clip": 1e-4, "far_clip": 1e4,
                    "to_world": mi.ScalarTransform4f().look_at(
                        origin=cam["position"], target=cam["look_at"],
                        up=cam.get("up", [0.0, 1.0, 0.0])),
                    "film": {"type": "hdrfilm", "width": res[0], "height": res[1],
                             "rfilter": {"type": "box"}, "pixel_format": "rgb",
                             "component_format": "float32"},
                    "sampler": {"type": "independent", "sample_count": spp}}}
    if integrator == "ptracer":
        d["integrator"]["samples_per_pass"] = spp
    for k, light in enumerate(scene.get("light", [])):
        flux = rgb(light["flux"], f"light[{k}].flux", path)
        d[f"light{k}"] = {"type": "point", "position": light["position"],
                          "intensity": {"type": "rgb", "value": [f / (4 * math.pi) for f in flux]}}
    materials = scene.get("material", {})
    groups, spheres = scene_triangles(scene, path, ANALYTIC_SPHERES)
    for (m, smooth), items in groups.items():
        if m not in materials:
            fail(f"{path}: unknown material '{m}'")
        tris = np.array([t for t, _ in items])
        normals = np.array([n for _, n in items]) if smooth else None
        tag = re.sub(r'[^A-Za-z0-9_-]', '_', m) + ("-smooth" if smooth else "")
        ply = os.path.join(meshdir, f"mesh-{tag}.ply")
        write_ply(ply, tris, normals)
        d[f"shape-{tag}"] = {"type": "ply", "filename": ply, "face_normals": not smooth,
                             "bsdf": mitsuba_bsdf(m, materials[m], path)}
    for k, sp in enumerate(spheres):
        d[f"sphere-{k}"] = {"type": "sphere", "center": sp.get("center", [0.0, 0.0, 0.0]),
                            "radius": float(sp["radius"]),
                            "flip_normals": sp.get("facing", "outside") == "inside",
                            "bsdf": mitsuba_bsdf(sp["material"], materials[sp["material"]], path)}
    return d


def delta_mask(mi, dr, msc, res, sub=4):
    """Per pixel: True where every one of sub x sub stratified camera rays first hits a
    non-delta surface or nothing (the pixels Mitsuba's ptracer can render)."""
    w, h = res
    ys, xs, sy, sx = np.meshgrid(np.arange(h), np.arange(w), np.arange(sub), np.arange(sub),
                                 indexing="ij")
    u = (xs + (sx + 0.5) / sub) / w
    v = (ys + (sy + 0.5) / sub) / h
    sensor = msc.sensors()[0]
    pos = mi.Point2f(u.ravel().astype(np.float32), v.ravel().astype(np.float32))
    ray, _ = sensor.sample_ray(0.0, 0.5, pos, mi.Point2f(0.5, 0.5))
    si = msc.ray_intersect(ray)
    flags = si.bsdf().flags()
    is_delta = mi.has_flag(flags, mi.BSDFFlags.Delta) & si.is_valid()
    delta = np.array(is_delta, dtype=bool).reshape(h, w, sub * sub)
    return ~delta.any(axis=2)


def render_mitsuba(mi, scene, path, res, meshdir, integrator, spp, runs, threads):
    """`runs` independent Mitsuba renders of spp samples each: (runs, H, W, 3) and seconds."""
    msc = mi.load_dict(mitsuba_scene(mi, scene, path, res, meshdir, integrator, spp))
    imgs, t0 = [], time.time()
    for r in range(runs):
        img = mi.render(msc, spp=spp, seed=1000 * r + 17)
        imgs.append(np.array(img, dtype=np.float64)[:, :, :3])
    return np.stack(imgs), time.time() - t0, msc


# ---------------------------------------------------------------- bdpm renders and EXR files

def read_exr(path):
    """{channel name: (H, W) array} of an EXR file (u32 channels as uint32)."""
    import OpenEXR
    with OpenEXR.File(path, separate_channels=True) as f:
        return {name: np.array(ch.pixels) for name, ch in f.channels().items()}


def bdpm_render(args, toml, mode, res, outdir):
    """Runs `bdpm render` with --accumulate; returns (mean, stderr, per-pass images, seconds)."""
    out = os.path.join(outdir, f"bdpm-{mode}.exr")
    cmd = [args.bdpm, "render", toml, "--mode", mode, "--resolution", f"{res[0]}x{res[1]}",
           "--passes", str(args.passes), "--spp", str(args.spp), "--threads", str(args.threads),
           "--seed", str(args.seed), "--accumulate", "--quiet", "-o", out]
    if args.photons:
        cmd += ["--photons", str(args.photons)]
    t0 = time.time()
    res_run = subprocess.run(cmd, capture_output=True, text=True)
    if res_run.returncode != 0:
        fail(f"{' '.join(cmd)} failed: {res_run.stderr.strip()}")
    secs = time.time() - t0
    ch = read_exr(out)
    mean = np.stack([ch[c] for c in ("R", "G", "B")], axis=-1).astype(np.float64)
    se = np.stack([ch[f"stderr.{c}"] for c in ("R", "G", "B")], axis=-1).astype(np.float64)
    return mean, se, accum_passes(out.replace(".exr", ".accum.exr")), secs


def accum_passes(path):
    """The per-pass images (P, H, W, 3) of a bdpm OUT.accum.exr (f64 as u32 hi/lo halves)."""
    ch = read_exr(path)
    passes = sorted({n.split(".")[-3] for n in ch if re.search(r"\.(R|G|B)\.hi$", n)})
    out = []
    for p in passes:
        prefix = next(n[: -len("R.hi")] for n in ch if n.endswith(f"{p}.R.hi"))
        img = []
        for c in ("R", "G", "B"):
            hi = ch[f"{prefix}{c}.hi"].astype(np.uint64)
            lo = ch[f"{prefix}{c}.lo"].astype(np.uint64)
            img.append(((hi << np.uint64(32)) | lo).view(np.float64))
        out.append(np.stack(img, axis=-1))
    return np.stack(out)


# ---------------------------------------------------------------- statistics

def block_means(imgs, mask):
    """Per-image means over each 32 x 32 block's masked pixels: (N, By, Bx, 3), and the
    blocks with at least a quarter of their pixels in the mask."""
    n, h, w, _ = imgs.shape
    by, bx = h // BLOCK, w // BLOCK
    m = mask[: by * BLOCK, : bx * BLOCK].reshape(by, BLOCK, bx, BLOCK).astype(np.float64)
    cnt = m.sum(axis=(1, 3))
    x = imgs[:, : by * BLOCK, : bx * BLOCK].reshape(n, by, BLOCK, bx, BLOCK, 3)
    s = (x * m[None, :, :, :, :, None]).sum(axis=(2, 4))
    return s / np.maximum(cnt, 1)[None, :, :, None], cnt >= BLOCK * BLOCK / 4


def compare(name, b_mean, b_se, b_passes, m_runs, mask):
    """The statistics of one comparison (bdpm first, Mitsuba second) over the masked pixels."""
    k = len(m_runs)
    if not mask.any():
        return {"comparison": name, "pixels": 0}
    m_mean = m_runs.mean(axis=0)
    m_se = m_runs.std(axis=0, ddof=1) / math.sqrt(k)
    sel = mask[:, :, None] & np.ones(3, dtype=bool)
    # Image means and their standard errors, from the spread of per-pass / per-run means.
    b_img = np.array([p[sel].mean() for p in b_passes])
    m_img = np.array([r[sel].mean() for r in m_runs])
    bm, mm = b_img.mean(), m_img.mean()
    bs, ms = b_img.std(ddof=1) / math.sqrt(len(b_img)), m_img.std(ddof=1) / math.sqrt(k)
    ratio = bm / mm
    ratio_se = ratio * math.sqrt((bs / bm) ** 2 + (ms / mm) ** 2)
    both = np.sqrt(b_se ** 2 + m_se ** 2)
    ok = sel & (both > 0)
    z_px = (b_mean - m_mean)[ok] / both[ok]
    bb, keep = block_means(b_passes, mask)
    mb, _ = block_means(m_runs, mask)
    d = bb.mean(axis=0) - mb.mean(axis=0)
    s = np.sqrt(bb.var(axis=0, ddof=1) / len(bb) + mb.var(axis=0, ddof=1) / k)
    zb = (d / np.where(s > 0, s, np.inf))[keep]
    return {"comparison": name, "pixels": int(mask.sum()), "mean_ratio": ratio,
            "mean_ratio_se": ratio_se,
            "pixels_within_4sigma": float((np.abs(z_px) <= SIGMAS).mean()) if z_px.size else None,
            "blocks": int(zb.size), "blocks_within_4sigma":
                float((np.abs(zb) <= SIGMAS).mean()) if zb.size else None,
            "block_z_worst": float(np.abs(zb).max()) if zb.size else None,
            "block_z_rms": float(np.sqrt((zb ** 2).mean())) if zb.size else None}


def print_row(r):
    """One comparison as a line."""
    if r["pixels"] == 0:
        print(f"{r['comparison']:<28} no pixels: the camera sees a mirror or glass first "
              "everywhere")
        return
    f = lambda v, fmt: "-" if v is None else format(v, fmt)
    print(f"{r['comparison']:<28} pixels {r['pixels']:6d}  mean ratio "
          f"{r['mean_ratio']:.4f} ± {r['mean_ratio_se']:.4f}  pixels within 4σ "
          f"{f(r['pixels_within_4sigma'], '.4f')}  blocks within 4σ "
          f"{f(r['blocks_within_4sigma'], '.3f')} of {r['blocks']} (block×channel)  "
          f"worst |z| {f(r['block_z_worst'], '.2f')}  rms z {f(r['block_z_rms'], '.2f')}")


# ---------------------------------------------------------------- driver

def lambert_copy(path, outdir):
    """A copy of the TOML with every material's Gaussian lobe (gr, delta) removed."""
    lines, section, out = open(path).read().splitlines(), "", []
    for line in lines:
        m = re.match(r"\s*\[+\s*([^\]]+?)\s*\]+", line)
        if m:
            section = m.group(1)
        if section.startswith("material.") and re.match(r"\s*(gr|delta)\s*=", line):
            continue
        out.append(line)
    dst = os.path.join(outdir, "lambert-" + os.path.basename(path))
    with open(dst, "w") as f:
        f.write("\n".join(out) + "\n")
    return dst


def save_png(mi, img, filename):
    """An sRGB 8-bit PNG preview of a linear image."""
    bmp = mi.Bitmap(np.ascontiguousarray(img.astype(np.float32)))
    bmp.convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.UInt8, srgb_gamma=True).write(filename)


def setup_mitsuba(args):
    """Imports Mitsuba with the chosen variant and thread count."""
    if args.variant.startswith("llvm") and "DRJIT_LIBLLVM_PATH" not in os.environ:
        # The distribution's newest libLLVM (Debian ships it versioned: libLLVM-19.so, -15.so).
        import glob
        import re
        found = glob.glob("/usr/lib/*-linux-gnu/libLLVM-*.so") + glob.glob("/usr/lib/libLLVM-*.so")
        key = lambda p: [int(n) for n in re.findall(r"\d+", os.path.basename(p))]
        if found:
            os.environ["DRJIT_LIBLLVM_PATH"] = max(found, key=key)
    import drjit as dr
    import mitsuba as mi
    mi.set_variant(args.variant)
    dr.set_thread_count(args.threads)
    return mi, dr


def run_compare(args, mi, dr, toml, scene):
    """Renders both renderers at --resolution and prints and writes the comparisons."""
    res = (args.resolution, args.resolution)
    spp_m = args.mitsuba_spp
    path_runs, t_path, msc = render_mitsuba(mi, scene, toml, res, args.out, "path", spp_m,
                                            args.runs, args.threads)
    pt_runs, t_pt, _ = render_mitsuba(mi, scene, toml, res, args.out, "ptracer", spp_m,
                                      args.runs, args.threads)
    mask = delta_mask(mi, dr, msc, res)
    rows, timing = [], {"mitsuba_path_s": t_path, "mitsuba_ptracer_s": t_pt}
    allpx = np.ones(mask.shape, dtype=bool)
    means = {}
    for mode in ["light", "path"] + args.modes:
        mean, se, passes, secs = bdpm_render(args, toml, mode, res, args.out)
        means[mode] = mean
        timing[f"bdpm_{mode}_s"] = secs
        if mode == "path":
            rows.append(compare("bdpm path / mi path", mean, se, passes, path_runs, allpx))
        else:
            rows.append(compare(f"bdpm {mode} / mi ptracer", mean, se, passes, pt_runs, mask))
        save_png(mi, mean, os.path.join(args.out, f"bdpm-{mode}.png"))
        print_row(rows[-1])
    save_png(mi, path_runs.mean(axis=0), os.path.join(args.out, "mitsuba-path.png"))
    save_png(mi, pt_runs.mean(axis=0), os.path.join(args.out, "mitsuba-ptracer.png"))
    # One strip at one exposure: bdpm's first BDPM mode | Mitsuba ptracer | bdpm path |
    # Mitsuba path.
    strip = [means[(args.modes or ["light"])[0]], pt_runs.mean(axis=0), means["path"],
             path_runs.mean(axis=0)]
    scale = 1.0 / max(np.percentile(strip[0].mean(axis=2), 99), 1e-30)
    save_png(mi, np.concatenate(strip, axis=1) * scale, os.path.join(args.out, "preview.png"))
    print(f"masked (delta first): {int((~mask).sum())} of {mask.size} pixels; times {timing}")
    with open(os.path.join(args.out, "compare.json"), "w") as f:
        json.dump({"scene": toml, "args": vars(args), "rows": rows, "timing": timing,
                   "masked_pixels": int((~mask).sum())}, f, indent=1)


def rel_errors(img, ref):
    """(rel. RMSE, relMSE) of an image against a reference (luminance-free, all channels)."""
    err2 = (img - ref) ** 2
    mean = ref.mean()
    return math.sqrt(err2.mean()) / mean, float((err2 / (ref ** 2 + 1e-4 * mean ** 2)).mean())


def run_equal_time(args, mi, dr, toml, scene):
    """bdpm (the file's settings) and Mitsuba's ptracer and path for the same wall time, at
    the reference's resolution; errors over all pixels and over those whose camera rays
    first hit a non-delta surface (where ptracer can converge)."""
    ch = read_exr(args.reference)
    ref = np.stack([ch[c] for c in ("R", "G", "B")], axis=-1).astype(np.float64)
    res = (ref.shape[1], ref.shape[0])
    out = os.path.join(args.out, "equal-time-bdpm.exr")
    cmd = [args.bdpm, "render", toml, "--resolution", f"{res[0]}x{res[1]}", "--threads",
           str(args.threads), "--time-budget", str(args.equal_time), "--passes", "100000",
           "--quiet", "-o", out]
    t0 = time.time()
    run = subprocess.run(cmd, capture_output=True, text=True)
    if run.returncode != 0:
        fail(f"{' '.join(cmd)} failed: {run.stderr.strip()}")
    t_b = time.time() - t0
    ch = read_exr(out)
    img = np.stack([ch[c] for c in ("R", "G", "B")], axis=-1).astype(np.float64)
    mask = None
    report = lambda what, im: print(
        f"{what:<36} all pixels: rel. RMSE %.4f relMSE %.3g; non-delta-first pixels: "
        "rel. RMSE %.4f relMSE %.3g" % (rel_errors(im, ref) + rel_errors(im[mask], ref[mask])))
    for integ in ("ptracer", "path"):
        msc = mi.load_dict(mitsuba_scene(mi, scene, toml, res, args.out, integ, 4))
        if mask is None:
            mask = delta_mask(mi, dr, msc, res)
            report(f"bdpm (file settings) {t_b:.1f} s", img)
        acc, n, t0 = np.zeros_like(ref), 0, time.time()
        while time.time() - t0 < t_b:
            acc += np.array(mi.render(msc, spp=4, seed=n), dtype=np.float64)[:, :, :3]
            n += 1
        report(f"mitsuba {integ} {4 * n} spp {time.time() - t0:.1f} s", acc / n)


def main():
    """Parses the arguments and runs the comparison or the equal-time mode."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("scene")
    ap.add_argument("--resolution", type=int, default=128)
    ap.add_argument("--out", default=None)
    ap.add_argument("--bdpm", default="target/release/bdpm")
    ap.add_argument("--modes", default="balance")
    ap.add_argument("--passes", type=int, default=16)
    ap.add_argument("--photons", type=int, default=None)
    ap.add_argument("--spp", type=int, default=4, help="bdpm camera samples per pixel per pass")
    ap.add_argument("--mitsuba-spp", type=int, default=64, help="Mitsuba spp per run")
    ap.add_argument("--runs", type=int, default=16, help="independent Mitsuba runs")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--lambert-copy", action="store_true")
    ap.add_argument("--analytic-spheres", action="store_true",
                    help="Mitsuba renders analytic spheres, not bdpm's geodesic ones")
    ap.add_argument("--equal-time", type=float, default=None)
    ap.add_argument("--reference", default=None)
    args = ap.parse_args()
    global ANALYTIC_SPHERES
    ANALYTIC_SPHERES = args.analytic_spheres
    args.modes = [m for m in args.modes.split(",") if m]
    if args.equal_time is not None and not args.reference:
        fail("--equal-time needs --reference REF.exr")
    if not os.path.isfile(args.bdpm):
        fail(f"--bdpm: {args.bdpm} is not a file (build it: cargo build --release)")
    name = os.path.splitext(os.path.basename(args.scene))[0]
    args.out = args.out or os.path.join("out", "mitsuba", name)
    os.makedirs(args.out, exist_ok=True)
    toml = lambert_copy(args.scene, args.out) if args.lambert_copy else args.scene
    try:
        with open(toml, "rb") as f:
            scene = tomllib.load(f)
    except (OSError, tomllib.TOMLDecodeError) as e:
        fail(f"{toml}: {e}")
    for name, mat in scene.get("material", {}).items():
        mitsuba_bsdf(name, mat, toml)  # refuses lobes before any rendering
    mi, dr = setup_mitsuba(args)
    if args.equal_time is not None:
        run_equal_time(args, mi, dr, toml, scene)
    else:
        run_compare(args, mi, dr, toml, scene)


if __name__ == "__main__":
    main()
