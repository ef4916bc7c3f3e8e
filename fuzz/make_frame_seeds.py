#!/usr/bin/python3
"""Writes the seed inputs of fuzz_frame_cloud (fuzz/corpus/frame_cloud/); the input layout is
described at the top of fuzz_frame_cloud.cpp. Run again only to change the seeds."""

import os
import random
import struct

out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "corpus", "frame_cloud")
random.seed(3)
texture = bytes(random.randrange(256) for _ in range(600))


def frame(name, w, h, flags, shift, target, intrinsics, payload):
    guess = bytes(6 * [128])  # the identity
    data = bytes([w - 8, h - 8, flags, shift[0], shift[1], target]) + intrinsics + guess + payload
    with open(os.path.join(out, name), "wb") as f:
        f.write(data)


os.makedirs(out, exist_ok=True)
# 40x32 BGR, slanted-plane float depth through depthToMeters, intrinsics from single bytes.
frame("bgr_plane", 40, 32, 1, (5, 4), 60, bytes([100, 100, 128, 128]), texture)
# 48x48 RGB, 16-bit depth.
frame("rgb_depth16", 48, 48, 0 | 4, (6, 3), 80, bytes([90, 95, 120, 140]), texture[::-1])
# 24x24 grey, float depth from the bytes put into the frame as is (NaN, Inf, negative).
frame("gray_raw_float", 24, 24, 2 | 8 | 16, (2, 6), 30, bytes([80, 80, 128, 128]),
      texture[:100] + struct.pack("<4f", float("nan"), float("inf"), -1.0, 2.0) * 8)
# Raw intrinsics: fx 0, fy NaN (an unusable camera).
frame("bad_intrinsics", 16, 16, 1 | 32, (4, 4), 10,
      struct.pack("<5d", 0.0, float("nan"), 8.0, 8.0, 5000.0), texture[:64])
# Raw intrinsics: a tiny focal length puts the points kilometres away.
frame("tiny_focal", 32, 32, 0 | 32, (5, 5), 40, struct.pack("<5d", 1e-3, 1e-3, 16.0, 16.0, 1.0),
      texture)
