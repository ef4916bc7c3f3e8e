#!/usr/bin/python3
"""The TUM bag path end to end: acvo_synth TUM folder -> scripts/tum_to_bag -> tum_bag.launch
(rosbag play --clock, record:=...) -> recorded TUM trajectory compared with the ground truth.

Run by rostest (tum_bag.test), which provides the master. The estimate starts at identity in
acvo_odom, so it is compared with the ground truth relative to the first estimated frame.
"""
import os
import subprocess
import sys
import tempfile
import unittest

import numpy as np
import rosbag
import roslib.packages
import rostest

FRAMES = 30
# Worst relative-pose error over the sequence (30 frames at 30 Hz, 0.3 m/s). Measured
# on the synthetic room (docs/ros.md); the bounds leave about 3x margin.
TRANSLATION_TOLERANCE = 0.03  # m
ROTATION_TOLERANCE = 0.03  # rad


def executable(name):
    paths = [p for p in roslib.packages.find_node("acvo", name) if os.access(p, os.X_OK)]
    if not paths:
        raise RuntimeError("%s not found in package acvo (built?)" % name)
    return paths[0]


def read_trajectory(path):
    rows = {}
    with open(path) as f:
        for line in f:
            parts = line.split()
            if not parts or parts[0].startswith("#"):
                continue
            rows[round(float(parts[0]), 6)] = [float(v) for v in parts[1:8]]
    return rows


def matrix(values):
    tx, ty, tz, qx, qy, qz, qw = values
    q = np.array([qw, qx, qy, qz]) / np.linalg.norm([qw, qx, qy, qz])
    w, x, y, z = q
    m = np.eye(4)
    m[:3, :3] = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                 [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                 [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
    m[:3, 3] = [tx, ty, tz]
    return m


def rotation_angle(r):
    return float(np.arccos(np.clip((np.trace(r) - 1) / 2, -1.0, 1.0)))


class TumBagTest(unittest.TestCase):
    def test_bag_through_launch_matches_ground_truth(self):
        work = tempfile.mkdtemp(prefix="acvo_tum_bag_")
        folder = os.path.join(work, "synthetic_tum")
        bag_path = os.path.join(work, "synthetic.bag")
        estimate_path = os.path.join(work, "estimate.txt")
        # 320x240 keeps the test quick; Kinect-like noise on, random hand-held motion.
        subprocess.run([executable("acvo_synth"), folder, "--frames", str(FRAMES), "--width",
                        "320", "--height", "240", "--speed", "0.3"], check=True)
        subprocess.run([executable("tum_to_bag"), folder, bag_path], check=True)

        # The bag looks like a TUM bag.
        with rosbag.Bag(bag_path) as bag:
            info = bag.get_type_and_topic_info().topics
            self.assertEqual(info["/camera/rgb/image_color"].message_count, FRAMES)
            self.assertEqual(info["/camera/depth/image"].msg_type, "sensor_msgs/Image")
            self.assertEqual(info["/camera/rgb/camera_info"].message_count, FRAMES)
            self.assertEqual(info["/tf"].message_count, FRAMES)
            for topic, msg, _ in bag.read_messages(topics=["/camera/rgb/image_color",
                                                           "/camera/depth/image"]):
                self.assertEqual(msg.encoding,
                                 "rgb8" if topic.endswith("image_color") else "32FC1")
                self.assertTrue(msg.header.frame_id.startswith("/openni_"))

        config = os.path.join(os.path.dirname(os.path.abspath(__file__)), "test_params.yaml")
        launch = subprocess.run(
            ["roslaunch", "acvo", "tum_bag.launch", "bag:=" + bag_path, "rviz:=false",
             "record:=" + estimate_path, "rate:=0.5", "delay:=5", "config:=" + config,
             "record_idle_timeout:=5"],
            timeout=300, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        self.assertTrue(os.path.exists(estimate_path),
                        "no trajectory recorded; roslaunch said:\n" + launch.stdout[-4000:])

        estimate = read_trajectory(estimate_path)
        truth = read_trajectory(os.path.join(folder, "groundtruth.txt"))
        # The recorder writes the image stamps: every estimate has its ground-truth pose.
        stamps = sorted(estimate)
        self.assertGreaterEqual(len(stamps), int(0.8 * FRAMES),
                                "too few frames processed:\n" + launch.stdout[-4000:])
        for s in stamps:
            self.assertIn(s, truth)
        e0, g0 = matrix(estimate[stamps[0]]), matrix(truth[stamps[0]])
        worst_t, worst_r = 0.0, 0.0
        for s in stamps:
            e = np.linalg.inv(e0) @ matrix(estimate[s])
            g = np.linalg.inv(g0) @ matrix(truth[s])
            err = np.linalg.inv(g) @ e
            worst_t = max(worst_t, float(np.linalg.norm(err[:3, 3])))
            worst_r = max(worst_r, rotation_angle(err[:3, :3]))
        print("[ MEASURED ] tum_bag: %d/%d frames, worst relative error %.4f m, %.4f rad"
              % (len(stamps), FRAMES, worst_t, worst_r))
        self.assertLess(worst_t, TRANSLATION_TOLERANCE)
        self.assertLess(worst_r, ROTATION_TOLERANCE)


if __name__ == "__main__":
    rostest.rosrun("acvo", "tum_bag", TumBagTest, sys.argv)
