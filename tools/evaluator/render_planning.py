#!/usr/bin/env python3
"""Pictures of the planning layer a fuser run wrote (for the docs and by hand).

  render_planning.py OUT [--height Z] [--scale K] [--prefix P] [--marks SCORE.json]

Writes P_esdf_slice.png: the ESDF's cells whose centre lies nearest to height Z (world z), free
cells coloured by their distance (blue near an obstacle, red at the max distance), occupied
cells black, unknown grey; and P_occupancy.png: OUT/occupancy.pgm as map_server reads it
(black occupied, white free, grey unknown), both scaled up K times. x grows to the right,
y upwards (the map_server convention). --marks takes stereo_fusion_evaluate_esdf's --json: its
phantom occupied cells near the slice and the occupancy map's false obstacle pixels are drawn
red. Needs numpy and OpenCV (python3-numpy, python3-opencv).
"""
import argparse
import json
import os
import sys

import cv2
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from plyio import read_ply  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('out')
    ap.add_argument('--height', type=float, default=1.0, help='slice height in metres (world z)')
    ap.add_argument('--scale', type=int, default=4)
    ap.add_argument('--prefix', default=None, help='output prefix (default OUT/planning)')
    ap.add_argument('--marks', default=None, help="stereo_fusion_evaluate_esdf --json output")
    a = ap.parse_args()
    prefix = a.prefix or os.path.join(a.out, 'planning')
    v = read_ply(os.path.join(a.out, 'esdf.ply'))['vertex']
    x, y, z, d = (np.asarray(v[k], dtype=np.float64) for k in ('x', 'y', 'z', 'distance'))
    # The cell edge: the smallest spacing between distinct centres along x.
    ux = np.unique(np.round(x, 5))
    cell = float(np.min(np.diff(ux))) if len(ux) > 1 else 0.08
    zs = np.unique(np.round(z, 5))
    zslice = zs[np.argmin(np.abs(zs - a.height))]
    sel = np.abs(z - zslice) < cell / 4
    ix = np.round((x - x.min()) / cell).astype(int)
    iy = np.round((y - y.min()) / cell).astype(int)
    w, h = ix.max() + 1, iy.max() + 1
    img = np.full((h, w, 3), 170, np.uint8)
    dmax = float(np.max(np.abs(d)))
    free = sel & (d > 0)
    level = np.clip(255.0 * d[free] / dmax, 0, 255).astype(np.uint8)
    colours = cv2.applyColorMap(level.reshape(-1, 1), cv2.COLORMAP_JET).reshape(-1, 3)
    img[h - 1 - iy[free], ix[free]] = colours
    occ = sel & (d < 0)
    img[h - 1 - iy[occ], ix[occ]] = 0
    marks = json.load(open(a.marks))['planning'] if a.marks else None
    if marks:
        for px, py, pz in marks['phantom_occupied'].get('centres', []):
            if abs(pz - zslice) < cell / 4:
                img[h - 1 - int(round((py - y.min()) / cell)), int(round((px - x.min()) / cell))] = (0, 0, 255)
    img = cv2.resize(img, (w * a.scale, h * a.scale), interpolation=cv2.INTER_NEAREST)
    cv2.imwrite(prefix + '_esdf_slice.png', img)
    grid = cv2.imread(os.path.join(a.out, 'occupancy.pgm'), cv2.IMREAD_UNCHANGED)
    if grid is not None:
        grid = cv2.cvtColor(grid, cv2.COLOR_GRAY2BGR)
        if marks and 'occupancy' in marks:
            for gx, gy in marks['occupancy'].get('false_pixels', []):
                grid[grid.shape[0] - 1 - gy, gx] = (0, 0, 255)
        grid = cv2.resize(grid, (grid.shape[1] * a.scale, grid.shape[0] * a.scale), interpolation=cv2.INTER_NEAREST)
        cv2.imwrite(prefix + '_occupancy.png', grid)
    print('slice at z = %.3f m (cell %.3f m, %d cells; max distance %.2f m): %s_esdf_slice.png, %s_occupancy.png'
          % (zslice, cell, int(sel.sum()), dmax, prefix, prefix))


if __name__ == '__main__':
    main()
