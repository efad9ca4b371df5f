#!/usr/bin/env python3
"""Odometry against the simulator's truth in a sim.launch bag (make demo's results/demo/run.bag):
the chaser's /odom pose against its true pose (tf world -> chaser_truth, put in the odom frame through the
static world -> odom), at the end of the run and at its largest, as a share of the true path length.
    scripts/odometry_vs_truth.py results/demo/run.bag
"""
import bisect
import math
import sys

import rosbag


def yaw_of(q):
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def read(bag_path):
    truth, odom, world_to_odom = [], [], None
    with rosbag.Bag(bag_path) as bag:
        for topic, msg, _ in bag.read_messages(topics=["/tf", "/tf_static", "/odom"]):
            if topic == "/odom":
                p = msg.pose.pose.position
                odom.append((msg.header.stamp.to_sec(), p.x, p.y, yaw_of(msg.pose.pose.orientation)))
                continue
            for tr in msg.transforms:
                if tr.header.frame_id.lstrip("/") != "world":
                    continue
                pose = (tr.header.stamp.to_sec(), tr.transform.translation.x, tr.transform.translation.y,
                        yaw_of(tr.transform.rotation))
                if tr.child_frame_id == "chaser_truth":
                    truth.append(pose)
                elif tr.child_frame_id == "odom":
                    world_to_odom = pose
    if not truth or not odom or world_to_odom is None:
        sys.exit(f"{bag_path}: needs /odom, the truth tf and world -> odom (a sim.launch bag)")
    truth.sort()
    return truth, odom, world_to_odom


def main():
    truth, odom, (_, ox, oy, oyaw) = read(sys.argv[1])
    c, s = math.cos(oyaw), math.sin(oyaw)
    stamps = [t[0] for t in truth]
    path = sum(math.hypot(b[1] - a[1], b[2] - a[2]) for a, b in zip(truth, truth[1:]))
    worst = end = 0.0
    for stamp, x, y, _ in odom:
        i = bisect.bisect_left(stamps, stamp)
        if i == 0 or i == len(truth):
            continue
        a, b = truth[i - 1], truth[i]
        f = (stamp - a[0]) / (b[0] - a[0]) if b[0] > a[0] else 0.0
        wx, wy = a[1] + f * (b[1] - a[1]), a[2] + f * (b[2] - a[2])
        tx, ty = c * (wx - ox) + s * (wy - oy), -s * (wx - ox) + c * (wy - oy)  # truth in the odom frame
        end = math.hypot(x - tx, y - ty)
        worst = max(worst, end)
    print(f"odometry vs truth: true path {path:.3f} m; error at the end {end * 1e3:.2f} mm "
          f"({100 * end / path:.3f} % of the path), largest {worst * 1e3:.2f} mm ({100 * worst / path:.3f} %)")


if __name__ == "__main__":
    main()
