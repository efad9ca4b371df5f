#!/usr/bin/env python3
"""What a docking sends across the link between the robot's computer and a laptop, measured.

Subscribes (as raw bytes, rospy.AnyMsg) to the topics that cross the link in each split of README "Two
computers", for --duration seconds of ROS time (sim time in the simulator: the rates are then what the
link carries when the simulator runs in real time), and prints bytes per second per topic and the sum
per split against a 100 Mbit/s link. Run it beside a docking, e.g.
  roslaunch launch/sim.launch dock:=true real_time_factor:=0.3 &
  scripts/link_budget.py --duration 20 --json results/link_budget.json
Exit status 0; 1 when nothing was received.
"""
import argparse
import io
import json
import sys
import threading
import time

import rospy

LINK_BYTES_PER_S = 100e6 / 8  # 100 Mbit/s
CAMERAS = ("/stereo/left", "/stereo/right", "/ir")
# Robot -> laptop besides images or estimates, in both splits; and laptop -> robot.
COMMON = ["/tf", "/tf_static", "/odom", "/clock", "/cmd_vel", "/docking/state"]
SPLITS = {
    "images cross, raw (perception on the laptop)":
        [c + "/image_raw" for c in CAMERAS] + [c + "/camera_info" for c in CAMERAS] + COMMON,
    "images cross, compressed (perception on the laptop, image_transport:=compressed)":
        [c + "/image_raw/compressed" for c in CAMERAS] + [c + "/camera_info" for c in CAMERAS] + COMMON,
    "estimates cross (perception on the robot)":
        ["/perception/disparity/estimate", "/perception/mono_visible/estimate", "/perception/mono_ir/estimate",
         "/target/estimate", "/target/pose", "/target/twist"] + COMMON,
}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--duration", type=float, default=20.0, help="ROS-time seconds to measure")
    ap.add_argument("--json", help="also write the figures here")
    args = ap.parse_args(rospy.myargv()[1:])
    rospy.init_node("link_budget", anonymous=True)
    lock = threading.Lock()
    counts = {}  # topic -> [messages, bytes]
    topics = sorted({t for ts in SPLITS.values() for t in ts})

    def size_of(msg):
        if hasattr(msg, "_buff"):
            return len(msg._buff)
        buff = io.BytesIO()  # a topic rospy itself subscribes to typed (/clock) arrives deserialized
        msg.serialize(buff)
        return buff.tell()

    def on_message(msg, topic):
        size = size_of(msg) + 4  # + the TCPROS length prefix
        with lock:
            c = counts.setdefault(topic, [0, 0])
            c[0] += 1
            c[1] += size

    for topic in topics:
        rospy.Subscriber(topic, rospy.AnyMsg, on_message, callback_args=topic, queue_size=100)
    while not rospy.is_shutdown() and rospy.get_time() == 0.0:
        time.sleep(0.1)  # wait for /clock in sim time
    rospy.sleep(2.0)  # connections up
    with lock:
        counts.clear()
    t0 = rospy.get_time()
    rospy.sleep(args.duration)
    span = rospy.get_time() - t0
    with lock:
        snapshot = {t: list(c) for t, c in counts.items()}
    if not snapshot:
        print("link_budget: nothing received: is a docking running?", file=sys.stderr)
        return 1
    rates = {t: {"hz": c[0] / span, "bytes_per_s": c[1] / span} for t, c in snapshot.items()}
    out = {"duration_s": span, "topics": rates, "splits": {}}
    print("%-48s %8s %12s" % ("topic", "Hz", "kB/s"))
    for t in topics:
        r = rates.get(t, {"hz": 0.0, "bytes_per_s": 0.0})
        print("%-48s %8.1f %12.1f" % (t, r["hz"], r["bytes_per_s"] / 1e3))
    print()
    for name, ts in SPLITS.items():
        total = sum(rates.get(t, {"bytes_per_s": 0.0})["bytes_per_s"] for t in ts)
        share = total / LINK_BYTES_PER_S
        out["splits"][name] = {"bytes_per_s": total, "share_of_100_mbit": share}
        print("%-82s %8.2f MB/s  %5.1f %% of 100 Mbit/s" % (name, total / 1e6, 100 * share))
    if args.json:
        with open(args.json, "w") as f:
            json.dump(out, f, indent=2)
    return 0


if __name__ == "__main__":
    sys.exit(main())
