#!/usr/bin/env python3
"""Typical pixel against expectation: for each IMAGE.exr against REF.exr (RGB, the same size),
the luminance summed over the pixels of each quarter of REF's brightness (below its 25th
percentile, 25–50, 50–75, 75–95, above the 95th) over REF's sum there, and the median over
pixels of IMAGE/REF. An unbiased estimator's sums agree with REF's within its noise whatever
its tail; a heavy-tailed one (most samples low, rare ones very high: a path tracer finding a
small hot spot by BDF sampling) shows a median ratio well below 1 beside sums near 1, and
fails a per-pixel 4σ test that trusts its standard error. Needs numpy and OpenEXR; a lab
script, not part of bdpm.

    python3 scripts/median-ratio.py REF.exr IMAGE.exr [IMAGE.exr …]
"""
import sys

import numpy as np
import OpenEXR

LUM = np.array([0.2126, 0.7152, 0.0722])


def read(path):
    return np.asarray(OpenEXR.File(path).parts[0].channels["RGB"].pixels, dtype=np.float64) @ LUM


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    ref = read(sys.argv[1])
    edges = [-np.inf, *np.quantile(ref, [0.25, 0.5, 0.75, 0.95]), np.inf]
    bins = [(ref > edges[i]) & (ref <= edges[i + 1]) for i in range(5)]
    print("sum over the bin / the reference's, bins <25, 25-50, 50-75, 75-95, >95th percentile; "
          "median of IMAGE/REF over pixels")
    for path in sys.argv[2:]:
        img = read(path)
        if img.shape != ref.shape:
            sys.exit(f"{path}: not the reference's size")
        sums = " ".join(f"{img[b].sum() / ref[b].sum():.3f}" for b in bins)
        lit = ref > 0
        print(f"{path}: {sums}  median ratio {np.median(img[lit] / ref[lit]):.3f}")


if __name__ == "__main__":
    main()
