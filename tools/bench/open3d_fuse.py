#!/usr/bin/python3
"""Reference fusion with Open3D's ScalableTSDFVolume on a stereo_fusion dataset folder.

Same frames, voxel size and truncation as stereo_fusion; depth = fx * baseline / disparity.
Prints one JSON line with per-frame integration timings and the final extraction time.
Open3D has no incremental meshing: a mesh that is current after every frame costs one full
extract_triangle_mesh() per frame, so that extraction is also timed after every
<extract_every>-th frame (0 = only at the end) to report what a live mesh would cost.
usage: open3d_fuse.py <seq-folder> <out-mesh.ply> <voxel_size_m> <truncation_m> <max_depth_m> [extract_every]
"""
import json
import os
import sys
import time

import cv2
import numpy as np
import open3d as o3d

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "evaluator"))
from sequence_io import read_calibration, read_poses  # noqa: E402


def main():
    seq, out_mesh = sys.argv[1], sys.argv[2]
    voxel, trunc, max_depth = float(sys.argv[3]), float(sys.argv[4]), float(sys.argv[5])
    extract_every = int(sys.argv[6]) if len(sys.argv) > 6 else 0
    calib = read_calibration(os.path.join(seq, "calibration.yaml"))
    poses = read_poses(os.path.join(seq, "poses.txt"))
    disp_files = sorted(os.listdir(os.path.join(seq, "disparity")))
    color_files = sorted(os.listdir(os.path.join(seq, "color")))
    intrinsic = o3d.camera.PinholeCameraIntrinsic(int(calib["width"]), int(calib["height"]), calib["fx"],
                                                  calib["fy"], calib["cx"], calib["cy"])
    volume = o3d.pipelines.integration.ScalableTSDFVolume(
        voxel_length=voxel, sdf_trunc=trunc, color_type=o3d.pipelines.integration.TSDFVolumeColorType.RGB8)
    fb = calib["fx"] * calib["baseline"]
    timings = []
    live_extract = []
    for i, (d_name, c_name) in enumerate(zip(disp_files, color_files)):
        raw = cv2.imread(os.path.join(seq, "disparity", d_name), cv2.IMREAD_UNCHANGED).astype(np.float32) / 256.0
        depth = np.zeros_like(raw)
        valid = raw > 0
        depth[valid] = fb / raw[valid]
        color = cv2.cvtColor(cv2.imread(os.path.join(seq, "color", c_name)), cv2.COLOR_BGR2RGB)
        rgbd = o3d.geometry.RGBDImage.create_from_color_and_depth(
            o3d.geometry.Image(np.ascontiguousarray(color)), o3d.geometry.Image(depth), depth_scale=1.0,
            depth_trunc=max_depth, convert_rgb_to_intensity=False)
        start = time.perf_counter()
        volume.integrate(rgbd, intrinsic, np.linalg.inv(poses[i]))  # extrinsic = T_camera_world
        timings.append((time.perf_counter() - start) * 1000.0)
        if extract_every > 0 and (i + 1) % extract_every == 0:
            start = time.perf_counter()
            volume.extract_triangle_mesh()
            live_extract.append((time.perf_counter() - start) * 1000.0)
    start = time.perf_counter()
    mesh = volume.extract_triangle_mesh()
    extract_ms = (time.perf_counter() - start) * 1000.0
    mesh.compute_vertex_normals()
    o3d.io.write_triangle_mesh(out_mesh, mesh)
    t = np.array(timings)
    print(json.dumps({"frames": len(timings), "integrate_ms": {"mean": float(t.mean()), "p50": float(np.median(t)),
                                                               "p99": float(np.percentile(t, 99))},
                      "extract_ms": extract_ms,
                      "live_extract_ms_p50": float(np.median(live_extract)) if live_extract else None,
                      "triangles": len(mesh.triangles)}))


if __name__ == "__main__":
    main()
