#!/usr/bin/env python3
"""A per-pixel merge-radius scale from a technique split, for the scratch build of
docs/results/pixel-radius-scale.patch (docs/results.md, "A sharper glossy reference"): per
8 x 8 block, BDD=1's share of the image (x1_weighted over the total luminance) puts the block
in one of three classes (below 0.3, 0.3-0.6, above 0.6) and every pixel of it gets that class's
scale of the scene's radius. Writes width x height little-endian f32, row-major, for
BDPM_RADIUS_SCALE_MAP (with BDPM_RADIUS_SCALE_WIDTH=width). Needs numpy and OpenEXR.

Usage: scripts/radius-classes.py TECHNIQUES.exr OUT.f32 [LOW MID HIGH]   (default 0.5 1 1.4)
  TECHNIQUES.exr from e.g. `bdpm render scenes/cornell-glossy.toml --passes 2 --techniques
  --seed 99 -o TECHNIQUES.exr` (a seed the renders it is used for do not use).
"""
import sys

import numpy as np
import OpenEXR

LUMINANCE = np.array([0.2126, 0.7152, 0.0722])
BLOCK = 8


def main():
    src, out = sys.argv[1], sys.argv[2]
    scales = np.array([float(a) for a in sys.argv[3:6]] or [0.5, 1.0, 1.4], dtype=np.float32)
    layers = {k: np.asarray(v.pixels) for k, v in OpenEXR.File(src).channels().items()}
    total, x1 = layers["RGB"] @ LUMINANCE, layers["x1_weighted"] @ LUMINANCE
    h, w = total.shape

    def blocks(a):
        return a.reshape(h // BLOCK, BLOCK, w // BLOCK, BLOCK).sum(axis=(1, 3))

    classes = np.digitize(blocks(x1) / np.maximum(blocks(total), 1e-30), [0.3, 0.6])
    scale = np.kron(scales[classes], np.ones((BLOCK, BLOCK), dtype=np.float32))
    scale.astype("<f4").tofile(out)
    print(f"{w}x{h}: blocks per class {[int((classes == c).sum()) for c in range(3)]}, scales {[round(float(s), 3) for s in scales]}")


if __name__ == "__main__":
    main()
