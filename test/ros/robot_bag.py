#!/usr/bin/python3
"""Writes the bag a robot would record, from a TUM-format folder (acvo_synth's output): a camera
driver's topics and encodings, the driver's static TF tree on a robot's base_link, and the
robot's wheel odometry (exact, and biased as real wheels are) on topics of their own.

usage: robot_bag.py FOLDER OUT.bag --driver realsense|freenect

Topics (DRIVERS below):
  the driver's colour image, registered depth (16UC1 millimetres, 0 = invalid) and camera info,
      with the driver's encodings, optical frame ids and stamp offsets
  /tf_static      base_link -> camera_link -> <driver's camera frame> -> <optical frame>
                  (one message, latched as a driver's static publisher is)
  /wheel_exact/tf   odom -> base_link, the base's true motion (from groundtruth.txt)
  /wheel_biased/tf  odom -> base_link with each step's translation scaled by BIAS_SCALE and
                    BIAS_YAW added to its yaw: slipping wheels and a drifting heading
The wheel topics are played remapped to /tf (`/wheel_exact/tf:=/tf`) when a guess is wanted,
and left out otherwise (the odometry would then give base_link a second parent).

The ground truth of the folder is the camera's optical frame in the world; the base is that
pose composed with BASE_FROM_OPTICAL^-1.
"""
import argparse
import math
import os
import sys

import cv2
import numpy as np
import rosbag
import rospy
import yaml
from geometry_msgs.msg import TransformStamped
from sensor_msgs.msg import CameraInfo, Image
from tf2_msgs.msg import TFMessage

sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
from poses import matrix  # noqa: E402

# Per driver: topics, encodings, frames, the depth stamp's offset from the colour stamp.
DRIVERS = {
    # realsense2_camera, align_depth:=true, enable_sync:=true.
    "realsense": {
        "rgb": "/camera/color/image_raw", "rgb_encoding": "rgb8",
        "depth": "/camera/aligned_depth_to_color/image_raw",
        "info": "/camera/color/camera_info",
        "camera_frame": "camera_color_frame", "optical_frame": "camera_color_optical_frame",
        "depth_offset": 0.0,
    },
    # freenect_launch, depth_registration:=true (image_proc's debayering gives bgr8).
    "freenect": {
        "rgb": "/camera/rgb/image_rect_color", "rgb_encoding": "bgr8",
        "depth": "/camera/depth_registered/image_raw",
        "info": "/camera/rgb/camera_info",
        "camera_frame": "camera_rgb_frame", "optical_frame": "camera_rgb_optical_frame",
        "depth_offset": 0.004,
    },
}
BASE_TO_CAMERA_LINK = (0.12, 0.0, 0.35, 0.0, 0.0, 0.0, 1.0)  # x y z qx qy qz qw
CAMERA_LINK_TO_CAMERA = (0.0, 0.015, 0.0, 0.0, 0.0, 0.0, 1.0)
CAMERA_TO_OPTICAL = (0.0, 0.0, 0.0, -0.5, 0.5, -0.5, 0.5)  # REP 103: z forward, x right
BIAS_SCALE = 1.15  # the biased wheels' translation per step, relative to the truth
BIAS_YAW = math.radians(0.5)  # added to each step's yaw (rad)


def values(m):
    """x y z qx qy qz qw of a rigid 4x4 matrix."""
    r = m[:3, :3]
    w = math.sqrt(max(0.0, 1.0 + r[0, 0] + r[1, 1] + r[2, 2])) / 2.0
    x = math.copysign(math.sqrt(max(0.0, 1.0 + r[0, 0] - r[1, 1] - r[2, 2])) / 2.0, r[2, 1] - r[1, 2])
    y = math.copysign(math.sqrt(max(0.0, 1.0 - r[0, 0] + r[1, 1] - r[2, 2])) / 2.0, r[0, 2] - r[2, 0])
    z = math.copysign(math.sqrt(max(0.0, 1.0 - r[0, 0] - r[1, 1] + r[2, 2])) / 2.0, r[1, 0] - r[0, 1])
    return (m[0, 3], m[1, 3], m[2, 3], x, y, z, w)


def yaw_matrix(angle):
    m = np.eye(4)
    c, s = math.cos(angle), math.sin(angle)
    m[:2, :2] = [[c, -s], [s, c]]
    return m


def base_from_optical():
    return matrix(BASE_TO_CAMERA_LINK) @ matrix(CAMERA_LINK_TO_CAMERA) @ matrix(CAMERA_TO_OPTICAL)


def stamp_of(text):
    secs, _, frac = text.partition(".")
    return rospy.Time(int(secs), int((frac + "000000000")[:9]))


def read_rows(path):
    with open(path) as f:
        return [line.split() for line in f if line.strip() and not line.startswith("#")]


def read_folder(folder):
    """[(rgb stamp text, rgb file, depth file)], {stamp text: camera pose values}, camera."""
    frames = [(r[0], r[1], r[3]) for r in read_rows(os.path.join(folder, "associations.txt"))]
    truth = {r[0]: tuple(float(v) for v in r[1:8])
             for r in read_rows(os.path.join(folder, "groundtruth.txt"))}
    with open(os.path.join(folder, "camera.yaml")) as f:
        camera = yaml.safe_load(f)
    return frames, truth, camera


def transform(parent, child, stamp, pose_values):
    t = TransformStamped()
    t.header.stamp = stamp
    t.header.frame_id = parent
    t.child_frame_id = child
    (t.transform.translation.x, t.transform.translation.y, t.transform.translation.z,
     t.transform.rotation.x, t.transform.rotation.y, t.transform.rotation.z,
     t.transform.rotation.w) = pose_values
    return t


def image_msg(array, encoding, stamp, frame_id):
    msg = Image()
    msg.header.stamp = stamp
    msg.header.frame_id = frame_id
    msg.height, msg.width = array.shape[:2]
    msg.encoding = encoding
    msg.step = array.strides[0]
    msg.data = array.tobytes()
    return msg


def info_msg(camera, stamp, frame_id):
    msg = CameraInfo()
    msg.header.stamp = stamp
    msg.header.frame_id = frame_id
    msg.width, msg.height = int(camera["width"]), int(camera["height"])
    fx, fy, cx, cy = (float(camera[k]) for k in ("fx", "fy", "cx", "cy"))
    msg.distortion_model = "plumb_bob"
    msg.D = [0.0] * 5
    msg.K = [fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0]
    msg.R = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
    msg.P = [fx, 0.0, cx, 0.0, 0.0, fy, cy, 0.0, 0.0, 0.0, 1.0, 0.0]
    return msg


def base_poses(frames, truth):
    """{stamp text: base pose (4x4) in the world} for each frame with a ground-truth pose."""
    optical_to_base = np.linalg.inv(base_from_optical())
    return {s: matrix(truth[s]) @ optical_to_base for s, _, _ in frames if s in truth}


def biased(poses, stamps):
    """The wheel odometry of slipping wheels: each step's translation scaled, its yaw turned."""
    out = {stamps[0]: poses[stamps[0]]}
    for a, b in zip(stamps, stamps[1:]):
        step = np.linalg.inv(poses[a]) @ poses[b]
        step[:3, 3] *= BIAS_SCALE
        out[b] = out[a] @ step @ yaw_matrix(BIAS_YAW)
    return out


def write(folder, bag_path, driver_name):
    driver = DRIVERS[driver_name]
    frames, truth, camera = read_folder(folder)
    scale = float(camera["depth_scale"])
    poses = base_poses(frames, truth)
    stamps = [s for s, _, _ in frames if s in poses]
    wheels = {"/wheel_exact/tf": poses, "/wheel_biased/tf": biased(poses, stamps)}
    optical = driver["optical_frame"]
    with rosbag.Bag(bag_path, "w") as bag:
        first = stamp_of(frames[0][0]) - rospy.Duration(0.5)
        static = TFMessage(transforms=[
            transform("base_link", "camera_link", first, BASE_TO_CAMERA_LINK),
            transform("camera_link", driver["camera_frame"], first, CAMERA_LINK_TO_CAMERA),
            transform(driver["camera_frame"], optical, first, CAMERA_TO_OPTICAL)])
        latched = {"topic": "/tf_static", "type": static._type, "md5sum": static._md5sum,
                   "message_definition": static._full_text, "latching": "1"}
        bag.write("/tf_static", static, first, connection_header=latched)
        for stamp_text, rgb_file, depth_file in frames:
            t = stamp_of(stamp_text)
            if stamp_text in poses:
                for topic, wheel in wheels.items():
                    bag.write(topic, TFMessage(transforms=[
                        transform("odom", "base_link", t, values(wheel[stamp_text]))]),
                        t - rospy.Duration(0.001))
            bgr = cv2.imread(os.path.join(folder, rgb_file), cv2.IMREAD_COLOR)
            raw = cv2.imread(os.path.join(folder, depth_file), cv2.IMREAD_UNCHANGED)
            if bgr is None or raw is None or raw.dtype != np.uint16:
                sys.exit("robot_bag: cannot read %s or %s" % (rgb_file, depth_file))
            colour = bgr if driver["rgb_encoding"] == "bgr8" else cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB)
            millimetres = np.round(raw.astype(np.float64) * (1000.0 / scale)).astype(np.uint16)
            t_depth = t + rospy.Duration(driver["depth_offset"])
            bag.write(driver["rgb"], image_msg(np.ascontiguousarray(colour), driver["rgb_encoding"],
                                               t, optical), t)
            bag.write(driver["info"], info_msg(camera, t, optical), t)
            bag.write(driver["depth"], image_msg(millimetres, "16UC1", t_depth, optical), t_depth)
    return stamps


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("folder")
    parser.add_argument("bag")
    parser.add_argument("--driver", choices=sorted(DRIVERS), required=True)
    args = parser.parse_args()
    stamps = write(args.folder, args.bag, args.driver)
    print("robot_bag: %d frames (%s) -> %s" % (len(stamps), args.driver, args.bag))


if __name__ == "__main__":
    main()
