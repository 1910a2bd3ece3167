#!/usr/bin/env python3
"""Per-pass variance of renders, no reference error in it: for each EXR written by `bdpm render`,
the luminance of its `noise` layer squared (V, each pixel's per-pass variance) against a
reference render's mean (luminance): the mean over pixels of V/ref² (relV; pixels where ref is
above 10⁻³ of the image mean) and ΣV/Σref² (weighted to the bright pixels). Given exactly two
renders, also both over the pixels whose means differ between them (where two builds or
settings did something different). Needs `pip install OpenEXR`.

    python3 scripts/per-pass-variance.py REF.exr A.exr [B.exr …]
"""
import sys, array, OpenEXR, Imath
def read(path, prefix=''):
    f = OpenEXR.InputFile(path)
    dw = f.header()['dataWindow']; n = (dw.max.x - dw.min.x + 1) * (dw.max.y - dw.min.y + 1)
    pt = Imath.PixelType(Imath.PixelType.FLOAT)
    c = [array.array('f', f.channel(prefix + ch, pt)) for ch in 'RGB']
    return [0.2126 * c[0][i] + 0.7152 * c[1][i] + 0.0722 * c[2][i] for i in range(n)]
ref = read(sys.argv[1])
m = sum(ref) / len(ref)
for p in sys.argv[2:]:
    v = [x * x for x in read(p, 'noise.')]
    keep = [i for i in range(len(ref)) if ref[i] > 1e-3 * m]
    rel = sum(v[i] / ref[i] ** 2 for i in keep) / len(keep)
    tot = sum(v) / sum(r * r for r in ref)
    print(f"{p}: relV {rel:.4e}, ΣV/Σref² {tot:.4e}")
# With A and B given as the last two: the same over the pixels whose means differ (where
# some sample took a triangle in solid angle).
if len(sys.argv) == 4:
    a, b = read(sys.argv[2]), read(sys.argv[3])
    mask = [i for i in range(len(ref)) if a[i] != b[i] and ref[i] > 1e-3 * m]
    if not mask:
        print("A and B have the same means in every pixel")
    for p in sys.argv[2:] if mask else []:
        v = [x * x for x in read(p, 'noise.')]
        rel = sum(v[i] / ref[i] ** 2 for i in mask) / len(mask)
        tot = sum(v[i] for i in mask) / sum(ref[i] ** 2 for i in mask)
        print(f"{p}: over the {len(mask)} pixels that differ: relV {rel:.4e}, ΣV/Σref² {tot:.4e}")
