#!/usr/bin/python3
"""How well a sequence's frames agree with each other, by depth: each frame's measured points
(every 7th pixel) are moved into an earlier frame (1-3 frames before) with the sequence's poses
and compared with that frame's own measurement at the pixel they land on. Prints, per depth band
of the earlier frame, the median of (depth the earlier, farther view measures) - (depth of the
later, nearer view's point): a systematic error of the poses or the disparities shows as a
median that grows with depth; noise alone gives ~0.

A held-out score (scripts/evaluate.sh --held-out) compares a mesh with such measurements, so
where this median exceeds the tolerance, a mesh that follows the nearer views is scored as
floating in front of the farther ones.

usage: view_consistency.py <seq-folder> [max_depth_m]
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sequence_io import read_calibration, read_disparity, read_poses  # noqa: E402


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    seq = sys.argv[1]
    max_depth = float(sys.argv[2]) if len(sys.argv) > 2 else 25.0
    cal = read_calibration(seq + "/calibration.yaml")
    fx, fy, cx, cy, fb = cal["fx"], cal["fy"], cal["cx"], cal["cy"], cal["fx"] * cal["baseline"]
    width, height = int(cal["width"]), int(cal["height"])
    poses = read_poses(seq + "/poses.txt")
    names = sorted(os.listdir(seq + "/disparity"))

    def depth(i):
        d = read_disparity(seq + "/disparity/" + names[i])
        z = np.where(d > 0, fb / np.maximum(d, 1e-6), 0.0)
        z[(z > max_depth) | ~np.isfinite(z)] = 0.0
        return z

    def pose(i):
        return poses[i][:3, :3], poses[i][:3, 3]

    edges = np.linspace(0.0, max_depth, 6)
    residuals = [[] for _ in range(len(edges) - 1)]
    for j in range(1, len(names)):
        zj = depth(j)
        Rj, tj = pose(j)
        v, u = np.nonzero(zj > 0)
        v, u = v[::7], u[::7]
        z = zj[v, u]
        X = np.stack([(u - cx) / fx * z, (v - cy) / fy * z, z], 1) @ Rj.T + tj
        for i in range(max(0, j - 3), j):
            zi = depth(i)
            Ri, ti = pose(i)
            Xi = (X - ti) @ Ri
            ok = Xi[:, 2] > 0.1
            ui = np.round(Xi[:, 0] / np.where(ok, Xi[:, 2], 1) * fx + cx).astype(int)
            vi = np.round(Xi[:, 1] / np.where(ok, Xi[:, 2], 1) * fy + cy).astype(int)
            ok &= (ui >= 0) & (ui < width) & (vi >= 0) & (vi < height)
            measured = zi[vi[ok], ui[ok]]
            moved = Xi[ok, 2]
            seen = measured > 0
            r = measured[seen] - moved[seen]
            band = np.digitize(measured[seen], edges) - 1
            for k in range(len(edges) - 1):
                sel = (band == k) & (np.abs(r) < 3.0)  # mismatched pixels (other surfaces) left out
                residuals[k].extend(r[sel].tolist())
    for k in range(len(edges) - 1):
        r = np.array(residuals[k])
        if len(r) == 0:
            continue
        mid = 0.5 * (edges[k] + edges[k + 1])
        print(f"depth {edges[k]:5.1f}-{edges[k + 1]:5.1f} m: {len(r):8d} points, median (earlier view - later view) "
              f"{1000 * np.median(r):+7.1f} mm = {np.median(r) * fb / mid ** 2:+.3f} px of disparity")


if __name__ == "__main__":
    main()
