#!/usr/bin/python3
"""Two meshes on the same held-out frames, pixel by pixel: where does one agree with the
measured depth and the other not, and is the other then missing, in front or behind? By depth
band. Reads the rendered depths that `stereo_fusion_evaluate <mesh> <seq> --held-out SPEC
--held-out-depth DIR` writes (DIR/<frame>.tiff), one folder per mesh, and the sequence's
disparities. The scores themselves come from the evaluator; this says where they differ.

usage: compare_held_out.py <seq-folder> <depth-dir A> <depth-dir B> [tolerance_m] [max_depth_m]
"""
import os
import sys

import cv2
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sequence_io import read_calibration, read_disparity  # noqa: E402

BANDS_M = [0, 1, 1.5, 2, 2.5, 3, 5, 10, 15, 20, 30, 1e9]


def main():
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    seq, dir_a, dir_b = sys.argv[1:4]
    tolerance = float(sys.argv[4]) if len(sys.argv) > 4 else 0.04
    max_depth = float(sys.argv[5]) if len(sys.argv) > 5 else 8.0
    cal = read_calibration(seq + "/calibration.yaml")
    fb = cal["fx"] * cal["baseline"]
    names = sorted(os.listdir(seq + "/disparity"))
    frames = sorted(int(f[:-5]) for f in os.listdir(dir_a) if f.endswith(".tiff") and os.path.exists(f"{dir_b}/{f}"))
    if not frames:
        sys.exit("no frame rendered into both folders")
    keys = ["measured", "A agrees", "B agrees", "A floats", "B floats",
            "B only: A missing", "B only: A in front", "B only: A behind",
            "A only: B missing", "A only: B in front", "A only: B behind"]
    total = {k: np.zeros(len(BANDS_M) - 1, np.int64) for k in keys}
    for i in frames:
        d = read_disparity(f"{seq}/disparity/{names[i]}")
        z = np.where(d > 0, fb / np.maximum(d, 1e-9), 0.0)
        measured = (z >= 0.1) & (z <= max_depth)
        band = np.clip(np.digitize(z, BANDS_M) - 1, 0, len(BANDS_M) - 2)
        rendered = {}
        for name, folder in (("A", dir_a), ("B", dir_b)):
            r = cv2.imread(f"{folder}/{i}.tiff", cv2.IMREAD_UNCHANGED)
            has = measured & (r > 0)
            rendered[name] = (r, has, has & (np.abs(r - z) <= tolerance), has & (r < z - tolerance))
        masks = {"measured": measured}
        for name in "AB":
            masks[f"{name} agrees"], masks[f"{name} floats"] = rendered[name][2], rendered[name][3]
        for one, other in (("B", "A"), ("A", "B")):
            r, has, agree, floats = rendered[other]
            only = rendered[one][2] & ~agree
            masks[f"{one} only: {other} missing"] = only & ~has
            masks[f"{one} only: {other} in front"] = only & floats
            masks[f"{one} only: {other} behind"] = only & has & (r > z + tolerance)
        for k in keys:
            total[k] += np.bincount(band[masks[k]], minlength=len(BANDS_M) - 1)
    measured = total["measured"].sum()
    print(f"{len(frames)} frames, {measured} measured pixels, tolerance {tolerance} m; shares of all measured pixels")
    for k in keys[1:]:
        print(f"  {k:22s} {100.0 * total[k].sum() / measured:6.2f} %")
    print("by measured depth:")
    print("  band (m)     measured   A agrees  B agrees  B only   A only")
    for b in range(len(BANDS_M) - 1):
        m = total["measured"][b]
        if m == 0:
            continue
        b_only = sum(total[k][b] for k in keys if k.startswith("B only"))
        a_only = sum(total[k][b] for k in keys if k.startswith("A only"))
        print(f"  {BANDS_M[b]:4.1f}-{min(BANDS_M[b + 1], 99):4.1f}  {100.0 * m / measured:6.1f} %   "
              f"{100.0 * total['A agrees'][b] / m:6.1f} %  {100.0 * total['B agrees'][b] / m:6.1f} %  "
              f"{100.0 * b_only / measured:5.2f} %  {100.0 * a_only / measured:5.2f} %")


if __name__ == "__main__":
    main()
