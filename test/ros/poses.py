"""Pose helpers of the Python rostests: the package's executables, TUM pose rows as matrices,
and how far an estimated trajectory is from a reference."""
import os

import numpy as np
import roslib.packages


def executable(name):
    """The path of one of the package's executables (built and on the package path)."""
    paths = [p for p in roslib.packages.find_node("acvo", name) if os.access(p, os.X_OK)]
    if not paths:
        raise RuntimeError("%s not found in package acvo (built?)" % name)
    return paths[0]


def matrix(values):
    """The 4x4 rigid transform of a TUM pose row: tx ty tz qx qy qz qw (q normalised)."""
    tx, ty, tz, qx, qy, qz, qw = values
    w, x, y, z = np.array([qw, qx, qy, qz]) / np.linalg.norm([qw, qx, qy, qz])
    m = np.eye(4)
    m[:3, :3] = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                 [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                 [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
    m[:3, 3] = [tx, ty, tz]
    return m


def rotation_angle(r):
    """The angle (rad) of a rotation matrix."""
    return float(np.arccos(np.clip((np.trace(r) - 1) / 2, -1.0, 1.0)))


def worst_relative_error(estimate, reference, stamps):
    """Largest translation (m) and rotation (rad) error of the poses relative to the first stamp;
    estimate and reference map each stamp to a 4x4 pose."""
    e0, r0 = estimate[stamps[0]], reference[stamps[0]]
    worst_t, worst_r = 0.0, 0.0
    for s in stamps:
        err = np.linalg.inv(np.linalg.inv(r0) @ reference[s]) @ (np.linalg.inv(e0) @ estimate[s])
        worst_t = max(worst_t, float(np.linalg.norm(err[:3, 3])))
        worst_r = max(worst_r, rotation_angle(err[:3, :3]))
    return worst_t, worst_r
