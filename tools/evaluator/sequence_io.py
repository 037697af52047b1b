"""Reading a dataset folder (doc/dataset_format.md) from Python: calibration.yaml, poses.txt and
disparity images, for the evaluator's scripts and the Open3D reference fusion."""
import os

import cv2
import numpy as np


def read_calibration(path):
    """calibration.yaml as a dict of floats (width, height, fx, fy, cx, cy, baseline)."""
    calib = {}
    with open(path) as f:
        for line in f:
            if ":" in line and not line.lstrip().startswith(("#", "%")):
                key, value = line.split(":", 1)
                calib[key.strip()] = float(value.split("#")[0])
    return calib


def rotation(qx, qy, qz, qw):
    """The rotation matrix of a unit quaternion."""
    x, y, z, w = qx, qy, qz, qw
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def read_poses(path):
    """poses.txt ("timestamp tx ty tz qx qy qz qw" per frame) as 4×4 T_world_camera matrices."""
    poses = []
    with open(path) as f:
        for line in f:
            if not line.strip() or line.lstrip().startswith("#"):
                continue
            _, tx, ty, tz, qx, qy, qz, qw = map(float, line.split())
            T = np.eye(4)
            T[:3, :3] = rotation(qx, qy, qz, qw)
            T[:3, 3] = [tx, ty, tz]
            poses.append(T)
    return poses


def read_disparity(path):
    """A disparity image in pixels: KITTI uint16 PNG (value / 256) or float PFM; 0 or less = none."""
    d = cv2.imread(path, cv2.IMREAD_UNCHANGED).astype(np.float32)
    return d / 256.0 if path.endswith(".png") else d
