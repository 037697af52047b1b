#!/usr/bin/python3
"""One held-out frame scored per pixel, as a picture: the mesh is drawn into the frame (its
camera, its pose from poses.txt) and compared with the frame's measured depth. Green: within
the tolerance; red: the mesh floats in front by more than it; blue: the mesh lies behind by more;
grey: measured, no mesh. Prints the same shares by depth band. For looking at what
scripts/evaluate.sh --held-out counts; the scores themselves come from the evaluator.

The mesh is drawn with OpenCV (triangles at their mean depth, far to near, at 4x resolution),
an approximation that is exact enough at the 0.2 m tolerances of outdoor data.

usage: render_held_out.py <mesh.ply> <seq-folder> <frame-index> <out.png> [tolerance_m] [max_depth_m]
"""
import os
import sys

import cv2
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from plyio import read_ply  # noqa: E402
from sequence_io import read_calibration, read_disparity, read_poses  # noqa: E402


def main():
    if len(sys.argv) < 5:
        sys.exit(__doc__)
    mesh_path, seq, index, out = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
    tolerance = float(sys.argv[5]) if len(sys.argv) > 5 else 0.2
    max_depth = float(sys.argv[6]) if len(sys.argv) > 6 else 25.0
    cal = read_calibration(seq + "/calibration.yaml")
    width, height = int(cal["width"]), int(cal["height"])
    fx, fy, cx, cy, fb = cal["fx"], cal["fy"], cal["cx"], cal["cy"], cal["fx"] * cal["baseline"]
    T = read_poses(seq + "/poses.txt")[index]
    R, t = T[:3, :3], T[:3, 3]
    name = sorted(os.listdir(seq + "/disparity"))[index]
    d = read_disparity(seq + "/disparity/" + name)
    z_meas = np.where(d > 0, fb / np.maximum(d, 1e-6), 0.0)
    z_meas[(z_meas > max_depth) | ~np.isfinite(z_meas)] = 0.0

    ply = read_ply(mesh_path)
    vertices = np.stack([ply["vertex"][axis] for axis in ("x", "y", "z")], 1).astype(np.float64)
    triangles = ply["face"]
    Vc = (vertices - t) @ R
    z = Vc[:, 2]
    u = fx * Vc[:, 0] / np.maximum(z, 1e-6) + cx
    v = fy * Vc[:, 1] / np.maximum(z, 1e-6) + cy
    T = np.asarray(triangles)
    zt, ut, vt = z[T], u[T], v[T]
    keep = (zt > 0.1).all(1) & (ut.max(1) > 0) & (ut.min(1) < width) & (vt.max(1) > 0) & (vt.min(1) < height)
    order = np.where(keep)[0]
    order = order[np.argsort(-zt[order].mean(1))]
    scale = 4
    z_mesh = np.full((height * scale, width * scale), np.inf, np.float32)
    for k in order:
        corners = np.stack([ut[k] * scale, vt[k] * scale], 1).round().astype(np.int32)
        cv2.fillConvexPoly(z_mesh, corners, float(zt[k].mean()))
    z_mesh = z_mesh.reshape(height, scale, width, scale)[:, scale // 2, :, scale // 2]

    measured = z_meas > 0
    both = measured & np.isfinite(z_mesh)
    agree = both & (np.abs(z_mesh - z_meas) <= tolerance)
    floating = both & (z_mesh < z_meas - tolerance)
    behind = both & (z_mesh > z_meas + tolerance)
    colour = cv2.imread(seq + "/color/" + sorted(os.listdir(seq + "/color"))[index])
    picture = (0.4 * colour).astype(np.uint8)
    picture[agree] = (0, 200, 0)
    picture[floating] = (0, 0, 255)
    picture[behind] = (255, 100, 0)
    picture[measured & ~np.isfinite(z_mesh)] = (200, 200, 200)
    cv2.imwrite(out, picture)
    print(f"{out}: measured {measured.sum()}, agreeing {agree.sum() / max(1, measured.sum()):.3f}, "
          f"floating / both {floating.sum() / max(1, both.sum()):.3f}")
    edges = np.linspace(0.0, max_depth, 6)
    for a, b in zip(edges[:-1], edges[1:]):
        band = both & (z_meas >= a) & (z_meas < b)
        n = max(1, band.sum())
        gap = (z_mesh - z_meas)[floating & band]
        print(f"  measured {a:5.1f}-{b:5.1f} m: {band.sum():7d} px with mesh, floating {(floating & band).sum() / n:.3f}, "
              f"agreeing {(agree & band).sum() / n:.3f}, behind {(behind & band).sum() / n:.3f}"
              + (f", floating by {-gap.mean():.2f} m on average" if gap.size else ""))


if __name__ == "__main__":
    main()
