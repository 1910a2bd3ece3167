#!/usr/bin/env python3
"""Renders a bdpm scene with Mitsuba 3's `path` or `ptracer` integrator for a time budget, for an equal-time
figure (scripts/figure-boxes.sh): exports the scene (`bdpm export --to mitsuba`), renders it in
rounds of --spp samples per pixel with fresh seeds until the budget is spent (the first round
always), and writes the mean of the rounds as OUT.exr (R, G, B) with OUT.json beside it in the
shape of a bdpm run report's timing ({"timing": {"prepare_s": load time, "render_s": render
time}}), which `bdpm figure` reads as the image's time.

  scripts/mitsuba-equal-time.py SCENE.toml -o OUT.exr [--seconds 10] [--resolution 128]
                                [--spp 4] [--variant llvm_ad_rgb] [--threads 2] [--bdpm PATH]
                                [--integrator path|ptracer] [--seed S]
"""
import argparse
import importlib.util
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

# Mitsuba's set-up (variant, threads, libLLVM) is mitsuba-specular.py's, shared as in
# mitsuba-check.py.
_spec = importlib.util.spec_from_file_location(
    "mitsuba_specular", os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                     "mitsuba-specular.py"))
_ms = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_ms)
setup_mitsuba = _ms.setup_mitsuba


def fail(msg):
    print(f"mitsuba-equal-time: {msg}", file=sys.stderr)
    sys.exit(2)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene")
    ap.add_argument("-o", "--out", required=True)
    ap.add_argument("--seconds", type=float, default=10.0)
    ap.add_argument("--resolution", type=int, default=128)
    ap.add_argument("--spp", type=int, default=4)
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--bdpm", default="target/release/bdpm")
    ap.add_argument("--integrator", choices=["path", "ptracer"], default="path")
    ap.add_argument("--seed", type=int, default=0,
                    help="independent runs for different seeds (0: the seeds of earlier runs)")
    args = ap.parse_args()
    if not (args.seconds > 0 and args.spp >= 1 and args.resolution >= 1):
        fail("--seconds must be positive, --spp and --resolution at least 1")
    export = tempfile.mkdtemp(prefix="mitsuba-equal-time-")
    res = subprocess.run([args.bdpm, "export", args.scene, "--to", "mitsuba", "-o", export,
                          "--resolution", f"{args.resolution}x{args.resolution}", "--quiet"],
                         capture_output=True, text=True)
    if res.returncode != 0:
        fail(f"bdpm export failed: {res.stderr.strip()}")
    mi, _ = setup_mitsuba(args)
    import OpenEXR
    t0 = time.time()
    scene = mi.load_file(os.path.join(export, "scene.xml"), spp=args.spp)
    integ = mi.load_dict({"type": args.integrator, "max_depth": -1})
    # Loading is the preparation; the first round, which compiles the LLVM kernels, counts
    # as render time. The budget is of render time, as bdpm's --time-budget is.
    prepare_s = time.time() - t0
    t1 = time.time()
    total, rounds = None, 0
    while rounds == 0 or time.time() - t1 < args.seconds:
        seed = (1000003 * args.seed + 7919 * rounds + 3) % 2**32
        img = np.array(mi.render(scene, integrator=integ, spp=args.spp, seed=seed),
                       dtype=np.float64)[:, :, :3]
        total = img if total is None else total + img
        rounds += 1
    render_s = time.time() - t1
    mean = total / rounds
    ch = {c: np.ascontiguousarray(mean[:, :, i].astype(np.float32)) for i, c in enumerate("RGB")}
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with OpenEXR.File(header, ch) as f:
        f.write(args.out)
    report = {"renderer": f"Mitsuba {mi.__version__} ({args.variant}), {args.integrator}, max_depth -1",
              "spp": rounds * args.spp, "rounds": rounds,
              "timing": {"prepare_s": prepare_s, "render_s": render_s}}
    with open(os.path.splitext(args.out)[0] + ".json", "w") as f:
        json.dump(report, f, indent=2)
    print(f"wrote {args.out}: {rounds * args.spp} spp in {prepare_s + render_s:.1f} s")


if __name__ == "__main__":
    main()
