#!/usr/bin/env python3
"""Renders a bdpm scene in Mitsuba 3 through `bdpm export` and compares it with a bdpm render.

One command for the check of issue 47: the scene is exported (`bdpm export SCENE --to mitsuba`,
docs/scene-format.md "Export to Mitsuba 3"), the exported scene.xml is rendered with Mitsuba's
`ptracer` (against bdpm's `light`, both light tracers) or `path` (against bdpm's `path`), and
the two images are compared:

  - by the statistics of scripts/mitsuba-specular.py (imported from it): the ratio of the
    image means with its standard error, pixels within 4 sigma, and 32 x 32-pixel blocks
    within 4 sigma, the block means' standard errors from the spread of bdpm's per-pass block
    means (OUT.accum.exr) and of Mitsuba's independent runs, since a bdpm pass's pixels share
    its photons;
  - by `bdpm compare BDPM.exr MITSUBA.exr --blocks 32` on the same two images (Mitsuba's
    written with a `stderr` layer from the spread of its runs), which takes pixels as
    independent.

With `ptracer`, pixels whose camera rays first hit a mirror or glass (any of 16 rays a pixel)
are masked out of both, as mitsuba-specular.py does: Mitsuba's light tracer cannot connect to
the camera through a delta surface, and bdpm's `light` adds the direct light seen through it.
Verdict (issue 47's criterion): PASS when the image means agree within 0.5 % and at least 98 %
of the blocks lie within 4 sigma; exit code 0 on PASS, 1 on FAIL, 2 on an error.

Needs (not project dependencies): `pip install mitsuba numpy OpenEXR`; the llvm variant needs
libLLVM (DRJIT_LIBLLVM_PATH, e.g. /usr/lib/x86_64-linux-gnu/libLLVM-19.so, set automatically
when that file exists), else `--variant scalar_rgb`.

A Mitsuba XML scene (SCENE.xml) is checked the other way round: bdpm renders its import of
the file (`bdpm render SCENE.xml`, docs/scene-format.md "Import from Mitsuba 3"), Mitsuba the
file itself, at --resolution (the film's width and height set in a copy, OUT/mitsuba.xml, whose
mesh files Mitsuba finds beside the original) with a `box` pixel filter in place of the file's
(bdpm's pixels are boxes; the import warns about any other filter) and the integrator chosen
here, so that the check measures the import, not the filter or the depth limit.

Usage:
  scripts/mitsuba-check.py SCENE.toml|SCENE.xml [--integrator ptracer|path] [--spp N] [--runs K]
      [--mode M] [--resolution 128] [--passes 16] [--bdpm-spp 4] [--photons N] [--seed 1]
      [--out DIR] [--bdpm BIN] [--threads 2] [--variant llvm_ad_rgb]

--spp is Mitsuba's samples per pixel per run (K runs, --runs); bdpm renders --passes passes
of --bdpm-spp camera samples per pixel (and --photons photons, the scene's by default) in
--mode (`light` against ptracer, `path` against path, by default).
"""
import argparse
import importlib.util
import json
import math
import os
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
_spec = importlib.util.spec_from_file_location(
    "mitsuba_specular", os.path.join(HERE, "mitsuba-specular.py"))
ms = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(ms)

MEAN_TOLERANCE = 0.005
BLOCKS_WITHIN = 0.98


def fail(msg):
    """Exits with a one-line error."""
    print(f"mitsuba-check: {msg}", file=sys.stderr)
    sys.exit(2)


def run(cmd):
    """Runs a command; a failure ends the script with its stderr."""
    res = subprocess.run(cmd, capture_output=True, text=True)
    if res.returncode != 0:
        fail(f"{' '.join(cmd)} failed: {res.stderr.strip()}")
    return res


def write_exr(path, mean, se):
    """A float32 EXR with R, G, B and stderr.R/G/B, as `bdpm compare` reads them."""
    import OpenEXR
    ch = {c: np.ascontiguousarray(mean[:, :, i].astype(np.float32)) for i, c in enumerate("RGB")}
    for i, c in enumerate("RGB"):
        ch[f"stderr.{c}"] = np.ascontiguousarray(se[:, :, i].astype(np.float32))
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with OpenEXR.File(header, ch) as f:
        f.write(path)


def film_copy(xml, out, res):
    """A copy of Mitsuba scene `xml` in `out` whose film is res[0] x res[1] pixels with a box
    filter; Mitsuba looks for its files in the original's directory. Returns its path."""
    import xml.etree.ElementTree as ET
    tree = ET.parse(xml)
    films = tree.getroot().findall("./sensor/film")
    if not films:
        fail(f"{xml}: no <sensor><film> to render at {res[0]}x{res[1]}")
    for film in films:
        for name, value in (("width", res[0]), ("height", res[1])):
            el = film.find(f"./integer[@name='{name}']")
            if el is None:
                el = ET.SubElement(film, "integer", {"name": name})
            el.set("value", str(value))
        for f in film.findall("./rfilter"):
            film.remove(f)
        ET.SubElement(film, "rfilter", {"type": "box"})
    path = os.path.join(out, "mitsuba.xml")
    tree.write(path)
    return path


def render_mitsuba(mi, xml, integrator, spp, runs, search=None):
    """`runs` independent Mitsuba renders of the scene file `xml` (its files looked up in
    `search` too): (runs, H, W, 3), the scene and seconds."""
    if search:
        mi.file_resolver().prepend(search)
    scene = mi.load_file(xml)
    integ = {"type": integrator, "max_depth": -1}
    if integrator == "ptracer":
        integ["samples_per_pass"] = spp
    integ = mi.load_dict(integ)
    imgs, t0 = [], time.time()
    for r in range(runs):
        img = mi.render(scene, integrator=integ, spp=spp, seed=1000 * r + 17)
        imgs.append(np.array(img, dtype=np.float64)[:, :, :3])
    return np.stack(imgs), scene, time.time() - t0


def main():
    """Exports, renders both, compares, prints and writes OUT/check.json."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("scene")
    ap.add_argument("--integrator", choices=["ptracer", "path"], default="ptracer")
    ap.add_argument("--spp", type=int, default=64, help="Mitsuba spp per run")
    ap.add_argument("--runs", type=int, default=16, help="independent Mitsuba runs")
    ap.add_argument("--mode", default=None, help="bdpm mode (light for ptracer, path for path)")
    ap.add_argument("--resolution", type=int, default=128)
    ap.add_argument("--passes", type=int, default=16)
    ap.add_argument("--bdpm-spp", type=int, default=4, dest="bdpm_spp")
    ap.add_argument("--photons", type=int, default=None)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--out", default=None)
    ap.add_argument("--bdpm", default="target/release/bdpm")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--variant", default="llvm_ad_rgb")
    args = ap.parse_args()
    mode = args.mode or ("light" if args.integrator == "ptracer" else "path")
    if not os.path.isfile(args.bdpm):
        fail(f"--bdpm: {args.bdpm} is not a file (build it: cargo build --release)")
    name = os.path.splitext(os.path.basename(args.scene))[0]
    out = args.out or os.path.join("out", "mitsuba-check", name)
    os.makedirs(out, exist_ok=True)
    res = (args.resolution, args.resolution)
    if args.scene.endswith(".xml"):
        # Mitsuba's own file: no export; bdpm reads it through its import.
        report = {"warnings": [], "imported": args.scene}
        xml, search = film_copy(args.scene, out, res), os.path.dirname(os.path.abspath(args.scene))
    else:
        export = os.path.join(out, "export")
        run([args.bdpm, "export", args.scene, "--to", "mitsuba", "-o", export, "--resolution",
             f"{res[0]}x{res[1]}", "--quiet"])
        with open(os.path.join(export, "export.json")) as f:
            report = json.load(f)
        for w in report["warnings"]:
            print(f"export warning: {w}")
        xml, search = os.path.join(export, "scene.xml"), None
    mi, dr = ms.setup_mitsuba(args)
    runs, msc, t_m = render_mitsuba(mi, xml, args.integrator, args.spp, args.runs, search)
    mask = (ms.delta_mask(mi, dr, msc, res) if args.integrator == "ptracer"
            else np.ones(res[::-1], dtype=bool))
    # bdpm_render reads these names from its args.
    args.spp, spp_m = args.bdpm_spp, args.spp
    t0 = time.time()
    mean, se, passes, _ = ms.bdpm_render(args, args.scene, mode, res, out)
    t_b = time.time() - t0
    row = ms.compare(f"bdpm {mode} / mi {args.integrator}", mean, se, passes, runs, mask)
    ms.print_row(row)
    # The same two images (masked alike) through `bdpm compare`.
    m_mean = runs.mean(axis=0)
    m_se = runs.std(axis=0, ddof=1) / math.sqrt(len(runs))
    keep = mask[:, :, None]
    b_exr, m_exr = os.path.join(out, f"bdpm-{mode}-masked.exr"), os.path.join(out, "mitsuba.exr")
    write_exr(b_exr, mean * keep, se * keep)
    write_exr(m_exr, m_mean * keep, m_se * keep)
    cmp = run([args.bdpm, "compare", b_exr, m_exr, "--blocks", "32", "--sigmas", "4"])
    print("bdpm compare:\n  " + cmp.stdout.strip().replace("\n", "\n  "))
    ok = bool(row["pixels"] > 0 and abs(row["mean_ratio"] - 1) <= MEAN_TOLERANCE
          and (row["blocks_within_4sigma"] or 0) >= BLOCKS_WITHIN)
    print(f"{'PASS' if ok else 'FAIL'}: image mean ratio {row.get('mean_ratio', float('nan')):.4f} "
          f"(|1 - ratio| <= {MEAN_TOLERANCE}), blocks within 4 sigma "
          f"{row.get('blocks_within_4sigma') or 0:.3f} (>= {BLOCKS_WITHIN}); "
          f"Mitsuba {args.runs} x {spp_m} spp {t_m:.1f} s, bdpm {t_b:.1f} s")
    ms.save_png(mi, np.concatenate([mean, m_mean], axis=1)
                / max(np.percentile(m_mean.mean(axis=2), 99), 1e-30),
                os.path.join(out, "preview.png"))
    with open(os.path.join(out, "check.json"), "w") as f:
        json.dump({"scene": args.scene, "args": vars(args), "row": row, "pass": bool(ok),
                   "bdpm_compare": cmp.stdout, "export": report,
                   "masked_pixels": int((~mask).sum()),
                   "timing": {"mitsuba_s": t_m, "bdpm_s": t_b}}, f, indent=1)
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
