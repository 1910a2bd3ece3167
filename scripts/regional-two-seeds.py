#!/usr/bin/env python3
"""Would a radius (or any variant) chosen per block of pixels keep its gain on a render it was
not chosen on? `bdpm study`'s regional paragraph cross-validates between the even and odd
passes of one run; this checks the same bound across two independent renders per variant
(two seeds, each a `bdpm render --time-budget`): the per-block choice is made on one seed's
renders and judged on the other's, and the other way round.

Per pixel and variant k: V_k the per-pass variance (the EXR's `noise` layer squared, luminance),
n_k passes, t_k wall seconds per pass (preparation included), squared kernel bias
b_k² = (L_k − R)² − V_k/n_k − s_R² against the reference R (its `stderr` layer s_R). At an equal
time T the expected relMSE of variant k is Σ_pixels (b_k² + V_k·t_k/T)/(R² + ε)/P, ε =
0.01·mean(R)². A mix gives block b variant k_b and costs the mean of its blocks' t per pass (a
pass's time spread evenly over the pixels, as the study assumes). The choice minimises, block by
block, b² + c·relV + λ·t over a grid of (c, λ), keeping the best mix by the true figure.

Prints the best single variant's relMSE at T over the mix's: in sample and judged on the other
seed. With TECHNIQUES=X.exr (a `bdpm render --techniques` render of the scene, e.g. 2 passes),
also a rule with three parameters instead of a choice per block: the blocks in three classes
by BDD=1's share of the image (x1_weighted over the total, below 0.3, 0.3–0.6, above 0.6), one
variant per class, the best triple chosen on one seed and judged on the other.
Needs numpy and OpenEXR (`pip install numpy OpenEXR`); a lab script, not part of bdpm.

Usage: [TECHNIQUES=X.exr] scripts/regional-two-seeds.py REFERENCE.exr SECONDS BLOCK DIR LABEL...
  DIR/LABEL-a.exr (+ .json) and DIR/LABEL-b.exr are the two seeds' renders of variant LABEL, e.g.
  for r in 0.25px 0.35px 0.5px 0.7px 1px 1.4px; do for s in a:1 b:2; do
    bdpm render scenes/cornell-glossy.toml --radius $r --time-budget 30 --threads 2 \\
      --seed ${s#*:} --passes 100000 -o DIR/$r-${s%:*}.exr --quiet; done; done
  scripts/regional-two-seeds.py out/ref/glossy-path-4800.exr 30 8 DIR 0.25px 0.35px 0.5px 0.7px 1px 1.4px
"""
import itertools
import json
import os
import sys

import numpy as np
import OpenEXR

LUMINANCE = np.array([0.2126, 0.7152, 0.0722])


def load(path):
    layers = {k: np.asarray(v.pixels) for k, v in OpenEXR.File(path).channels().items()}
    out = {"L": layers["RGB"] @ LUMINANCE}
    if "noise" in layers:
        out["V"] = (layers["noise"] @ LUMINANCE) ** 2
    if "stderr" in layers:
        out["s2"] = (layers["stderr"] @ LUMINANCE) ** 2
    return out


def main():
    ref_path, T, B, directory, labels = sys.argv[1], float(sys.argv[2]), int(sys.argv[3]), sys.argv[4], sys.argv[5:]
    ref = load(ref_path)
    R, var_r = ref["L"], ref["s2"]
    norm = R**2 + 0.01 * R.mean() ** 2
    H, W = R.shape

    def blocks(x):
        return x.reshape(H // B, B, W // B, B).sum(axis=(1, 3)) / (H * W)

    def seed(tag):
        out = []
        for label in labels:
            base = f"{directory}/{label}-{tag}"
            image, run = load(base + ".exr"), json.load(open(base + ".json"))
            n = run["passes_done"]
            t = (run["timing"]["render_s"] + run["timing"]["prepare_s"]) / n
            bias2 = (image["L"] - R) ** 2 - image["V"] / n - var_r
            out.append(dict(n=n, t=t, relv=blocks(image["V"] / norm), bias=blocks(bias2 / norm)))
        return out

    def figure(st, choice):
        t_mix = np.mean([st[k]["t"] for k in choice.ravel()])
        return sum(
            (st[k]["bias"][choice == k] + st[k]["relv"][choice == k] * t_mix / T).sum()
            for k in range(len(labels))
        )

    def single(st):
        return min(figure(st, np.full((H // B, W // B), k)) for k in range(len(labels)))

    def choose(st):
        n_blocks = (H // B) * (W // B)
        best = (np.inf, None)
        for c in np.geomspace(1e-3, 1e2, 61):
            for lam in np.concatenate([[0.0], np.geomspace(1e-5, 1e1, 61)]):
                cost = np.stack([s["bias"] + c * s["relv"] + lam * s["t"] / n_blocks for s in st])
                choice = cost.argmin(axis=0)
                f = figure(st, choice)
                if f < best[0]:
                    best = (f, choice)
        return best[1]

    a, b = seed("a"), seed("b")
    for name, st in (("a", a), ("b", b)):
        print(f"seed {name}: " + ", ".join(
            f"{label} {figure(st, np.full((H // B, W // B), k)):.4e} ({s['n']} passes)"
            for k, (label, s) in enumerate(zip(labels, st))))
    for name, chosen_on, judged_on in (("a", a, b), ("b", b, a)):
        choice = choose(chosen_on)
        shares = ", ".join(f"{label} {(choice == k).mean():.0%}" for k, label in enumerate(labels))
        print(f"chosen on seed {name} ({B}x{B} blocks: {shares}): best single over the mix "
              f"{single(chosen_on) / figure(chosen_on, choice):.3f}x in sample, "
              f"{single(judged_on) / figure(judged_on, choice):.3f}x on the other seed")
    if "TECHNIQUES" not in os.environ:
        return
    layers = {k: np.asarray(v.pixels) for k, v in OpenEXR.File(os.environ["TECHNIQUES"]).channels().items()}
    total = blocks(layers["RGB"] @ LUMINANCE)
    share = blocks(layers["x1_weighted"] @ LUMINANCE) / np.maximum(total, 1e-30)
    classes = np.digitize(share, [0.3, 0.6])
    print("blocks per class of BDD=1's share (<0.3, 0.3-0.6, >0.6):",
          [int((classes == c).sum()) for c in range(3)])
    for name, chosen_on, judged_on in (("a", a, b), ("b", b, a)):
        best = min(itertools.product(range(len(labels)), repeat=3),
                   key=lambda triple: figure(chosen_on, np.array(triple)[classes]))
        choice = np.array(best)[classes]
        print(f"rule chosen on seed {name} ({', '.join(labels[k] for k in best)}): best single over it "
              f"{single(chosen_on) / figure(chosen_on, choice):.3f}x in sample, "
              f"{single(judged_on) / figure(judged_on, choice):.3f}x on the other seed")


if __name__ == "__main__":
    main()
