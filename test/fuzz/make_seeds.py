#!/usr/bin/python3
"""Writes the seed corpora test/fuzz/corpus/<target>/: tiny valid inputs, one per feature a
target should start from. Pure Python (PNG via zlib), so it runs anywhere:
    test/fuzz/make_seeds.py        (rewrites the seed files; the fuzzer's own finds stay in .fuzz/)
"""
import os
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
SEP = b"\n--8<--\n"  # fuzz_dataset_folder.cpp's kSeparator


def write(target, name, data):
    folder = os.path.join(HERE, "corpus", target)
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, name), "wb") as f:
        f.write(data)


def png(width, height, rows, bit_depth, color_type):
    """rows: bytes per row, already in PNG sample order (big-endian for 16 bit)."""
    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))
    raw = b"".join(b"\x00" + r for r in rows)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, bit_depth, color_type, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def pfm(width, height, values, channels=1, little=True):
    magic = b"Pf" if channels == 1 else b"PF"
    scale = b"-1" if little else b"1"
    fmt = ("<" if little else ">") + "f" * len(values)
    return magic + b"\n%d %d\n" % (width, height) + scale + b"\n" + struct.pack(fmt, *values)


CALIBRATION = b"width: 4\nheight: 3\nfx: 100\nfy: 100\ncx: 1.5\ncy: 1\nbaseline: 0.1\n"
POSES = b"# t tx ty tz qx qy qz qw\n0 0 0 0 0 0 0 1\n1 0.1 0 0 0 0 0.7071068 0.7071068\n"

# PFM reader
write("fuzz_pfm", "grey_little_endian.pfm", pfm(2, 2, [1.0, 2.0, float("nan"), -1.0]))
write("fuzz_pfm", "colour_big_endian.pfm", pfm(1, 2, [1, 2, 3, 4, 5, 6], channels=3, little=False))

# calibration.yaml (the target's folder has a 4x3 disparity)
write("fuzz_calibration", "plain.yaml", CALIBRATION)
write("fuzz_calibration", "opencv_filestorage.yaml",
      b"%YAML:1.0\n---\nwidth: 4\nheight: 3\nfx: 1.0e+02\nfy: 100.\ncx: 1.5\ncy: 1.\nbaseline: 1.0e-01\n")
write("fuzz_calibration", "wrong_size.yaml", CALIBRATION.replace(b"width: 4", b"width: 640"))

# dataset folder: flags | calibration | poses | image A | image B
disparity16 = png(4, 3, [struct.pack(">4H", *(2560 + 256 * u + 64 * v for u in range(4))) for v in range(3)], 16, 0)
colour = png(4, 3, [b"".join(bytes((40 * u, 80 * v, 200)) for u in range(4)) for v in range(3)], 8, 2)
grey = png(4, 3, [bytes(30 * u + 10 * v for u in range(4)) for v in range(3)], 8, 0)
write("fuzz_dataset_folder", "png_disparity_and_colour", b"\x02" + CALIBRATION + SEP + POSES + SEP + disparity16 + SEP + colour)
write("fuzz_dataset_folder", "pfm_disparity", b"\x01" + CALIBRATION + SEP + POSES + SEP +
      pfm(4, 3, [10.0, 11.0, float("inf"), 0.0, 12.0, -3.0, 13.0, 14.0, 1.0, 2.0, 3.0, 4.0]))
# SGBM needs images wider than its 128 disparities
wide_grey = png(144, 3, [bytes((7 * u * u + 31 * v) % 256 for u in range(144)) for v in range(3)], 8, 0)
write("fuzz_dataset_folder", "sgbm_from_right", b"\x06" + CALIBRATION.replace(b"width: 4", b"width: 144")
      + SEP + POSES + SEP + wide_grey + SEP + wide_grey)

# integrate(): flags, frames-1, 5 intrinsics bytes, a 7-byte pose per frame, 768 disparity bytes
def integrate_seed(flags, poses, disparity_byte):
    body = bytes([flags, len(poses) - 1, 128, 128, 128, 100, 128])
    for pose in poses:
        body += bytes(pose)
    body += bytes([disparity_byte]) * (32 * 24)
    return body + b"\x07"  # colour seed

centre = [128, 128, 128, 128, 128, 128, 0]  # identity rotation, zero translation, x 10^0
turned = [128, 140, 128, 135, 128, 120, 0]
far = [128, 140, 128, 255, 128, 120, 7]  # 2e7 m along x: near the edge of the map
for variant in range(4):
    write("fuzz_integrate", "plane_config%d" % variant, integrate_seed(0x04 | variant << 4, [centre, turned], 40))
write("fuzz_integrate", "grey_three_frames", integrate_seed(0x0c, [centre, turned, centre], 80))
write("fuzz_integrate", "far_from_the_origin", integrate_seed(0x04, [far, far], 40))
special = bytearray(integrate_seed(0x00, [centre], 40))
for i, b in enumerate([0, 251, 252, 253, 254, 255]):
    special[14 + i * 97] = b  # invalid and absurd disparities among valid ones
write("fuzz_integrate", "special_disparities", bytes(special))
raw = struct.pack("<5f", 300.0, 300.0, 16.0, 12.0, 0.1) + struct.pack("<12f", 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0)
raw += struct.pack("<768f", *([20.0] * 768))
write("fuzz_integrate", "raw_floats", bytes([0x43, 0]) + raw)

# toStereoFrame() + integrate(): flags, the broken field's index, the colour encoding, then the
# fields fuzz_ros_frame.cpp reads (plausible K: 4 bytes; disparity header: 5 bytes; 192
# disparity bytes; the colour byte; a raw u32 when bit 4; the pose: 2 bytes).
def ros_frame_seed(flags, broken=0, encoding=0, k=(128, 128, 128, 128), disparity_byte=20, raw32=b""):
    body = bytes([flags, broken, encoding]) + bytes(k)
    if flags & 64:
        body += bytes([16, 12])
    body += bytes([128, 128, 64, 255, 16]) + bytes([disparity_byte]) * (16 * 12) + b"\x50"
    return body + raw32 + bytes([128, 128])

write("fuzz_ros_frame", "plausible_rgb8", ros_frame_seed(0x00))
write("fuzz_ros_frame", "k_only_mono8", ros_frame_seed(0x22, encoding=4))
write("fuzz_ros_frame", "big_endian_disparity", ros_frame_seed(0x08))
write("fuzz_ros_frame", "unknown_encoding", ros_frame_seed(0x20, encoding=6))
write("fuzz_ros_frame", "info_size_from_bytes", ros_frame_seed(0x40))
# a disparity width whose 4-byte row overflows 32 bits: the step check must not wrap
write("fuzz_ros_frame", "huge_disparity_width", ros_frame_seed(0x10, broken=0, raw32=struct.pack("<I", 0x40000001)))
write("fuzz_ros_frame", "huge_image_step", ros_frame_seed(0x10, broken=5, raw32=struct.pack("<I", 0xFFFFFFFF)))
# the principal point far outside the image (a 1e9 px cx stalled the lookup once)
raw_k = struct.pack("<4f", 30.0, 30.0, 1e9, 6.0)
write("fuzz_ros_frame", "absurd_principal_point", bytes([0x01, 0, 0]) + raw_k + bytes([128, 128, 64, 255, 16])
      + bytes([20]) * (16 * 12) + b"\x50" + bytes([128, 128]))

# toCameraPoses() + submitTrajectory(): flags, poses, per pose: stamp byte, 3 position bytes,
# 3 axis-angle bytes and a norm byte (or raw floats with bits 0-1).
def trajectory_seed(flags, poses):
    body = bytes([flags, len(poses)])
    for pose in poses:
        body += bytes(pose)
    return body

identity = [128, 128, 128, 128, 128, 128, 128, 128]
shifted = [128, 140, 128, 128, 128, 133, 128, 128]
write("fuzz_ros_trajectory", "identity_at_the_frames", trajectory_seed(0x00, [identity, identity, identity]))
write("fuzz_ros_trajectory", "a_small_correction", trajectory_seed(0x00, [identity, shifted, shifted]))
write("fuzz_ros_trajectory", "with_a_clear", trajectory_seed(0x08, [identity, shifted, shifted]))
write("fuzz_ros_trajectory", "stamps_anywhere", trajectory_seed(0x04, [[30] + identity[1:], [250] + shifted[1:]]))
write("fuzz_ros_trajectory", "empty_path", trajectory_seed(0x00, []))
zero_q = bytes([0x01, 1, 128, 128, 128, 128]) + struct.pack("<4f", 0.0, 0.0, 0.0, 0.0)
write("fuzz_ros_trajectory", "zero_quaternion", zero_q)
long_q = bytes([0x01, 1, 128, 128, 128, 128]) + struct.pack("<4f", 0.0, 0.0, 0.0, 2.0)
write("fuzz_ros_trajectory", "quaternion_of_norm_two", long_q)

# Map file, version 3 (io/MapFile.h): one block stored at 2³ and a seen-free section of two
# planning blocks at 8 cm. fuzz_map_file also replays every input with its checksums and
# payload size recomputed (the crafted class), so mutated keys reach the range checks.
def map_file_v3(blocks, free_cell_m, free_blocks):
    payload = b""
    for (x, y, z), sdfs in blocks:
        payload += struct.pack("<iiiQBBBB", x, y, z, len(sdfs), 0b100, 0, 0, 0)
        payload += b"".join(struct.pack("<ffBBBB", s, 1.0 + i, 100, 120, 140, 0) for i, s in enumerate(sdfs))
    payload += struct.pack("<dQ", free_cell_m, len(free_blocks))
    for (x, y, z), bits in free_blocks:
        payload += struct.pack("<iiiI", x, y, z, 0) + struct.pack("<8Q", *bits)
    head = struct.pack("<8sIIddddQQQ", b"SFUSEMAP", 3, 80, 0.02, 4.0, 2.0, 4.0, 9, len(blocks), len(payload))
    head += struct.pack("<I", zlib.crc32(payload))
    return head + struct.pack("<I", zlib.crc32(head)) + payload


level2 = [-0.05, -0.03, -0.01, 0.01, 0.03, 0.05, 0.07, 0.09]
write("fuzz_map_file", "one_block_seen_free_v3.sfmap",
      map_file_v3([((3, -2, 7), level2)], 0.08,
                  [((0, -1, 3), [0xFFFFFFFFFFFFFFFF] * 8), ((1, -1, 3), [0x0F0F0F0F0F0F0F0F] + [0] * 7)]))
