#!/usr/bin/python3
"""Plot an estimated trajectory against ground truth (both TUM format, already aligned).

Left: the x-y plane; right: x, y and z over time. Used by acvo_eval --plot.
Exit status 3 when matplotlib is missing, 2 for unreadable input.
"""
import argparse
import math
import sys


def read_positions(path):
    """Stamps and positions of a TUM trajectory; skips what the TUM tools skip."""
    stamps, xyz = [], []
    with open(path) as f:
        for line in f:
            line = line.replace(",", " ").replace("\t", " ").strip()
            if not line or line.startswith("#"):
                continue
            v = [float(x) for x in line.split()]
            if len(v) != 8 or any(math.isnan(x) for x in v) or v[4:8] == [0.0] * 4:
                continue
            stamps.append(v[0])
            xyz.append(v[1:4])
    return stamps, xyz


def plot(plt, gt_t, gt, est_t, est, output, title):
    """Left the x-y plane, right x, y and z over time; written to `output`."""
    # Ground truth only over the estimate's time span (plus a second each side), so that a
    # short estimate is not lost in a long ground truth.
    span = [(t, p) for t, p in zip(gt_t, gt) if est_t[0] - 1.0 <= t <= est_t[-1] + 1.0]
    if span:
        gt_t, gt = [t for t, _ in span], [p for _, p in span]
    t0 = min(gt_t[0], est_t[0])
    fig, (plane, time) = plt.subplots(1, 2, figsize=(12, 5))
    plane.plot([p[0] for p in gt], [p[1] for p in gt], "k-", label="ground truth")
    plane.plot([p[0] for p in est], [p[1] for p in est], "r-", label="estimate (aligned)")
    plane.set_xlabel("x [m]")
    plane.set_ylabel("y [m]")
    plane.set_aspect("equal", adjustable="datalim")
    plane.legend()
    plane.grid(True)
    for axis, colour in enumerate("bgm"):
        name = "xyz"[axis]
        time.plot([t - t0 for t in gt_t], [p[axis] for p in gt], colour + "-",
                  label=name + " ground truth")
        time.plot([t - t0 for t in est_t], [p[axis] for p in est], colour + "--",
                  label=name + " estimate")
    time.set_xlabel("time [s]")
    time.set_ylabel("position [m]")
    time.legend(ncol=3, fontsize="small")
    time.grid(True)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(output, dpi=100)


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--groundtruth", required=True)
    parser.add_argument("--estimate", required=True)
    parser.add_argument("--output", required=True, help="PNG file to write")
    parser.add_argument("--title", default="")
    args = parser.parse_args()
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError as e:
        sys.stderr.write("plot_trajectories: matplotlib is missing (%s); on Debian install "
                         "python3-matplotlib\n" % e)
        return 3
    try:
        gt_t, gt = read_positions(args.groundtruth)
        est_t, est = read_positions(args.estimate)
    except (OSError, ValueError) as e:
        sys.stderr.write("plot_trajectories: %s\n" % e)
        return 2
    if not gt or not est:
        sys.stderr.write("plot_trajectories: an input trajectory is empty\n")
        return 2
    plot(plt, gt_t, gt, est_t, est, args.output, args.title)
    return 0


if __name__ == "__main__":
    sys.exit(main())
