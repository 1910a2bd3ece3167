#!/usr/bin/env python3
"""Summarises the studies of scripts/sampler-study.sh as the table of docs/results.md
("Stratified camera samples"): per scene, resolution, radius and mode, stratified against
independent samples from the same study (same run, passes in turn, CPU clock).
Usage: scripts/sampler-table.py OUT_DIR"""
import glob, os, sys

def rows(path):
    out = {}
    for line in open(path):
        if not line.startswith("| ") or line.startswith("| mode"):
            continue
        f = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(f) < 13:
            continue
        out[f[0]] = dict(cpu=float(f[4]), v=float(f[5]), relv=float(f[6]),
                         rrmse=float(f[7].rstrip("%")))
    return out

print("| scene | size | r | mode | CPU s/pass ind. → strat. | mean V strat./ind. | relV strat./ind. "
      "| rel. RMSE after the passes, ind. → strat. | efficiency strat./ind. (mean V) | (relV) |")
print("|---|---|---|---|---|---:|---:|---|---:|---:|")
for path in sorted(glob.glob(os.path.join(sys.argv[1], "*", "study.md")),
                   key=lambda p: (p.split("/")[-2].rsplit("-", 2)[0], int(p.split("/")[-2].rsplit("-", 2)[1]), p)):
    name = path.split("/")[-2]
    scene, size, r = name.rsplit("-", 2)
    r = "1.75 mm (scene)" if r == "rscene" else f"{float(r[1:]) * 1000:g} mm"
    rs = rows(path)
    for mode in ["balance", "optimal-path"]:
        ind, st = rs.get(f"{mode}:sampler=independent"), rs.get(f"{mode}:sampler=stratified")
        if not ind or not st:
            continue
        eff = lambda a, b, k: (b["cpu"] * b[k]) / (a["cpu"] * a[k])
        print(f"| {scene.replace('cornell-', '')} | {size}² | {r} | {mode} | {ind['cpu']:.2f} → {st['cpu']:.2f} "
              f"| {st['v'] / ind['v']:.3f} | {st['relv'] / ind['relv']:.3f} | {ind['rrmse']:.2f} % → {st['rrmse']:.2f} % "
              f"| {eff(st, ind, 'v'):.2f} | {eff(st, ind, 'relv'):.2f} |")
