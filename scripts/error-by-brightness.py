#!/usr/bin/env python3
"""Where an image's squared error lies: for each IMAGE.exr against REF.exr (both RGB, the same
size), its rel. RMSE (√(mean squared error over pixels and channels) / the reference's mean)
and the share of the summed squared error in the pixels whose reference luminance lies below
the 50th percentile, 50–90, 90–99, 99–99.9 and above the 99.9th. A few bright pixels holding
most of the error (an emitter's edge seen directly, a highlight) show in the last columns.
Needs numpy and OpenEXR (`pip install numpy OpenEXR`); a lab script, not part of bdpm.

    python3 scripts/error-by-brightness.py REF.exr IMAGE.exr [IMAGE.exr …]
"""
import sys

import Imath
import numpy as np
import OpenEXR


def read(path):
    f = OpenEXR.InputFile(path)
    dw = f.header()["dataWindow"]
    w, h = dw.max.x - dw.min.x + 1, dw.max.y - dw.min.y + 1
    pt = Imath.PixelType(Imath.PixelType.FLOAT)
    return np.stack([np.frombuffer(f.channel(c, pt), dtype=np.float32).reshape(h, w)
                     for c in "RGB"], -1).astype(np.float64)


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    ref = read(sys.argv[1])
    lum = ref @ np.array([0.2126, 0.7152, 0.0722])
    q = np.quantile(lum, [0.5, 0.9, 0.99, 0.999])
    edges = [-np.inf, *q, np.inf]
    print(f"reference luminance at the 50th, 90th, 99th, 99.9th percentile: "
          f"{', '.join(f'{v:.4g}' for v in q)} (max {lum.max():.4g})")
    for path in sys.argv[2:]:
        img = read(path)
        if img.shape != ref.shape:
            sys.exit(f"{path}: {img.shape[1]}x{img.shape[0]}, the reference is "
                     f"{ref.shape[1]}x{ref.shape[0]}")
        err = ((img - ref) ** 2).sum(-1)
        rel = np.sqrt(err.mean() / 3) / ref.mean()
        shares = [err[(lum > a) & (lum <= b)].sum() / err.sum() for a, b in zip(edges, edges[1:])]
        print(f"{path}: rel. RMSE {100 * rel:.3f} %; share of the squared error by reference "
              f"luminance <50 %, 50–90, 90–99, 99–99.9, >99.9: "
              f"{' '.join(f'{s:.2f}' for s in shares)}")


main()
