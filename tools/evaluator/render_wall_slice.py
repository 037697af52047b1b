#!/usr/bin/python3
"""A horizontal slice through meshes beside their ground truth: where a second skin behind a wall is.

Draws, seen from above, the vertices of each mesh whose height lies in [z - h, z + h] (white)
over the ground truth's (red), inside the box [x0, x1] x [y0, y1], one panel per mesh side by
side, each titled with its label.
usage: render_wall_slice.py <gt_mesh.ply> <out.png> <z> <h> <x0> <x1> <y0> <y1> <label=mesh.ply> ...
"""
import os
import sys

import cv2
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from plyio import read_ply  # noqa: E402

PX_PER_M = 600


def band(path, z, h, box):
    v = read_ply(path)['vertex']
    x, y, zz = (np.asarray(v[k], dtype=np.float64) for k in ('x', 'y', 'z'))
    keep = (np.abs(zz - z) <= h) & (x >= box[0]) & (x <= box[1]) & (y >= box[2]) & (y <= box[3])
    return x[keep], y[keep]


def main():
    if len(sys.argv) < 10:
        sys.exit(__doc__)
    gt, out = sys.argv[1], sys.argv[2]
    z, h = float(sys.argv[3]), float(sys.argv[4])
    box = [float(a) for a in sys.argv[5:9]]
    meshes = [a.split('=', 1) for a in sys.argv[9:]]
    w = int((box[1] - box[0]) * PX_PER_M)
    hgt = int((box[3] - box[2]) * PX_PER_M)
    gx, gy = band(gt, z, h, box)
    panels = []
    for label, path in meshes:
        img = np.zeros((hgt + 40, w, 3), np.uint8)

        def plot(xs, ys, colour):
            u = ((xs - box[0]) * PX_PER_M).astype(int)
            v = 40 + ((box[3] - ys) * PX_PER_M).astype(int)
            ok = (u >= 0) & (u < w) & (v >= 40) & (v < hgt + 40)
            for du in (0, 1):
                for dv in (0, 1):
                    img[np.minimum(v[ok] + dv, hgt + 39), np.minimum(u[ok] + du, w - 1)] = colour

        plot(gx, gy, (60, 60, 200))
        mx, my = band(path, z, h, box)
        plot(mx, my, (255, 255, 255))
        cv2.putText(img, label, (8, 28), cv2.FONT_HERSHEY_SIMPLEX, 0.7, (255, 255, 255), 2)
        # a 10 cm scale bar
        cv2.line(img, (w - 8 - int(0.1 * PX_PER_M), 30), (w - 8, 30), (0, 200, 255), 2)
        panels.append(img)
        panels.append(np.full((hgt + 40, 4, 3), 60, np.uint8))
    cv2.imwrite(out, np.hstack(panels[:-1]))


if __name__ == '__main__':
    main()
