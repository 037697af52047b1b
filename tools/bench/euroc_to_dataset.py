#!/usr/bin/python3
"""Turns raw EuRoC stereo pairs (cam0/, cam1/ with sensor.yaml and data.csv, as in
../shared/data/euroc-v101-stereo-40) into a dataset folder the fuser reads.

  euroc_to_dataset.py EUROC_DIR OUT_DIR [--height-m H]

Rectifies both cameras (cv2.stereoRectify from the EuRoC intrinsics, distortion and T_BS
extrinsics, alpha 0) and writes color/ (left) and right/ as PNG, calibration.yaml of the
rectified left camera and poses.txt. The folder holds no disparity: the fuser computes its own
with SGBM from right/, as on any stereo rig.

EuRoC ships these clips without the body's ground truth, and the MAV stands still while they
were taken, so every frame gets one pose: gravity from the floor — the largest plane of the
first pair's SGBM points in the lower half of the image (RANSAC) — world z up from it, the camera
at its measured height above the floor (or --height-m), world x along the camera's view
direction on the floor. So occupancy grids and slices at world heights read as in a room.
Needs numpy, OpenCV and PyYAML (python3-numpy, python3-opencv, python3-yaml).
"""
import argparse
import os

import cv2
import numpy as np
import yaml


def read_sensor(path):
    with open(path) as f:
        text = f.read().replace('%YAML:1.0', '')
    s = yaml.safe_load(text)
    fu, fv, cu, cv = s['intrinsics']
    k = np.array([[fu, 0, cu], [0, fv, cv], [0, 0, 1]], dtype=np.float64)
    t_bs = np.array(s['T_BS']['data'], dtype=np.float64).reshape(4, 4)
    return k, np.array(s['distortion_coefficients'], dtype=np.float64), t_bs, tuple(s['resolution'])


def read_frames(cam_dir):
    rows = []
    with open(os.path.join(cam_dir, 'data.csv')) as f:
        for line in f:
            if line.startswith('#') or not line.strip():
                continue
            stamp_ns, name = line.strip().split(',')
            rows.append((int(stamp_ns), name.strip()))
    return rows


def sgbm(left, right):
    matcher = cv2.StereoSGBM_create(minDisparity=0, numDisparities=64, blockSize=5, P1=200, P2=800,
                                    disp12MaxDiff=1, uniquenessRatio=10, speckleWindowSize=100,
                                    speckleRange=2, mode=cv2.STEREO_SGBM_MODE_SGBM_3WAY)
    return matcher.compute(left, right).astype(np.float32) / 16.0


def floor_plane(points, rng, iterations=2000, tolerance_m=0.02):
    """RANSAC: the plane n·p = d (|n| = 1, n towards the camera at the origin) with most inliers."""
    best, best_count = None, 0
    for _ in range(iterations):
        a, b, c = points[rng.choice(len(points), 3, replace=False)]
        n = np.cross(b - a, c - a)
        if np.linalg.norm(n) < 1e-9:
            continue
        n /= np.linalg.norm(n)
        d = n @ a
        count = int(np.sum(np.abs(points @ n - d) < tolerance_m))
        if count > best_count:
            best, best_count = (n, d), count
    n, d = best
    inliers = points[np.abs(points @ n - d) < tolerance_m]
    # Refit on the inliers (least squares through their centroid).
    centroid = inliers.mean(axis=0)
    n = np.linalg.svd(inliers - centroid, full_matrices=False)[2][2]
    d = n @ centroid
    if d > 0:  # the camera (origin) on the positive side: n·0 − d > 0
        n, d = -n, -d
    return n, d, len(inliers)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('euroc')
    ap.add_argument('out')
    ap.add_argument('--height-m', type=float, default=None,
                    help='camera height above the floor (default: measured from the floor plane)')
    a = ap.parse_args()

    k0, d0, t_b0, size = read_sensor(os.path.join(a.euroc, 'cam0', 'sensor.yaml'))
    k1, d1, t_b1, _ = read_sensor(os.path.join(a.euroc, 'cam1', 'sensor.yaml'))
    t_10 = np.linalg.inv(t_b1) @ t_b0  # cam0 → cam1: X1 = R X0 + T, as stereoRectify wants
    r0, r1, p0, p1, _, _, _ = cv2.stereoRectify(k0, d0, k1, d1, size, t_10[:3, :3], t_10[:3, 3],
                                                flags=cv2.CALIB_ZERO_DISPARITY, alpha=0)
    maps = [cv2.initUndistortRectifyMap(k, d, r, p, size, cv2.CV_32FC1)
            for k, d, r, p in ((k0, d0, r0, p0), (k1, d1, r1, p1))]
    fx, fy, cx, cy = p0[0, 0], p0[1, 1], p0[0, 2], p0[1, 2]
    baseline = -p1[0, 3] / p1[0, 0]

    frames0, frames1 = read_frames(os.path.join(a.euroc, 'cam0')), read_frames(os.path.join(a.euroc, 'cam1'))
    by_stamp1 = dict(frames1)
    for sub in ('color', 'right'):
        os.makedirs(os.path.join(a.out, sub), exist_ok=True)
    stamps, first = [], None
    for i, (stamp, name) in enumerate(frames0):
        if stamp not in by_stamp1:
            continue
        raw = [cv2.imread(os.path.join(a.euroc, cam, 'data', n), cv2.IMREAD_GRAYSCALE)
               for cam, n in (('cam0', name), ('cam1', by_stamp1[stamp]))]
        rect = [cv2.remap(img, mx, my, cv2.INTER_LINEAR) for img, (mx, my) in zip(raw, maps)]
        n = len(stamps)
        cv2.imwrite(os.path.join(a.out, 'color', '%06d.png' % n), rect[0])
        cv2.imwrite(os.path.join(a.out, 'right', '%06d.png' % n), rect[1])
        stamps.append(stamp)
        if first is None:
            first = rect

    with open(os.path.join(a.out, 'calibration.yaml'), 'w') as f:
        f.write('width: %d\nheight: %d\nfx: %.6f\nfy: %.6f\ncx: %.6f\ncy: %.6f\nbaseline: %.9f\n'
                % (size[0], size[1], fx, fy, cx, cy, baseline))

    # Gravity from the floor in the first pair.
    disparity = sgbm(*first)
    h, w = disparity.shape
    v, u = np.mgrid[0:h, 0:w]
    lower = (disparity > 1.0) & (v > h // 2)
    z = fx * baseline / disparity[lower]
    points = np.stack([(u[lower] - cx) * z / fx, (v[lower] - cy) * z / fy, z], axis=1)
    points = points[z < 6.0]
    normal, offset, inliers = floor_plane(points, np.random.default_rng(0))
    height = -offset if a.height_m is None else a.height_m
    up = normal  # camera frame: towards the camera from the floor
    forward = np.array([0.0, 0.0, 1.0]) - up * up[2]
    forward /= np.linalg.norm(forward)
    left = np.cross(up, forward)
    r_world_cam = np.stack([forward, left, up])  # rows: world axes in camera coordinates
    q = quaternion(r_world_cam)
    with open(os.path.join(a.out, 'poses.txt'), 'w') as f:
        f.write('# t tx ty tz qx qy qz qw (T_world_camera; one pose: the MAV stands still)\n')
        for stamp in stamps:
            f.write('%.9f 0 0 %.6f %.9f %.9f %.9f %.9f\n' % ((stamp - stamps[0]) * 1e-9, height, *q))
    tilt = np.degrees(np.arccos(min(1.0, abs(up[1]))))
    print('%d pairs rectified: fx %.2f px, baseline %.4f m; floor plane from %d of %d points: '
          'camera %.3f m above it, optical axis %.1f° below the horizon, y axis %.1f° off vertical'
          % (len(stamps), fx, baseline, inliers, len(points), height,
             np.degrees(np.arcsin(-up[2])), tilt))


def quaternion(r):
    """(qx, qy, qz, qw) of the rotation matrix r (camera → world), via OpenCV's axis-angle."""
    rvec = cv2.Rodrigues(np.asarray(r, dtype=np.float64))[0].ravel()
    angle = np.linalg.norm(rvec)
    axis = rvec / angle if angle > 0 else np.zeros(3)
    return [*(axis * np.sin(angle / 2)), np.cos(angle / 2)]

if __name__ == '__main__':
    main()
