#!/usr/bin/env python3
"""Peak memory and CPU of the stack (issue 15): launches a scenario in the simulator, samples every process
the launch started once a second, and reports each one's peak resident memory (VmHWM) and the peak of their
sum, with and without the simulator (docking_sim, the target's renderer; not part of the robot's stack),
and each process's CPU time per second of sim time: at the simulator's camera rate (30 Hz unless
--camera-rate-hz), the share of one core that process takes at that input rate, whatever the real-time
factor the machine reached.

  scripts/eval/stack_memory.py [--scenario closed_loop_still_1p5m] [--seconds 60] [--camera-rate-hz 30]
                               [--launch-arg NAME:=VALUE ...] [--out FILE.json]

Runs its own roscore on a free port (ROS_MASTER_URI is set for the launch), binds to loopback, and stops
everything it started. The master (rosmaster, rosout) is counted apart: a robot runs one whatever the
stack. A program that prints figures; nothing here asserts.
"""
import argparse
import json
import os
import pathlib
import signal
import socket
import subprocess
import sys
import time

import rosgraph

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "report"))
from provenance import provenance  # noqa: E402  (what ran, when, on which commit)

ROOT = pathlib.Path(__file__).resolve().parents[2]
SIMULATOR_NAMES = ("docking_sim",)       # the simulator's own processes: excluded from the stack's figure
MASTER_NAMES = ("rosmaster", "rosout", "roslaunch")
# roslaunch's substitution helpers ($(find), $(eval), the URDF command): alive for a moment at start-up.
HELPER_NAMES = ("catkin_find", "rosversion", "bash", "sh", "make_urdf.py")


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def descendants(pid):
    """Every process below pid (from /proc's parent links)."""
    children = {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            fields = pathlib.Path(f"/proc/{entry}/stat").read_text().rsplit(")", 1)[1].split()
            children.setdefault(int(fields[1]), []).append(int(entry))
        except (OSError, IndexError):
            continue
    found, todo = [], [pid]
    while todo:
        for child in children.get(todo.pop(), []):
            found.append(child)
            todo.append(child)
    return found


def node_name(pid):
    """The ROS node name (__name:=) or the program's name."""
    try:
        args = pathlib.Path(f"/proc/{pid}/cmdline").read_bytes().split(b"\0")
    except OSError:
        return None
    for arg in args:
        if arg.startswith(b"__name:="):
            return arg.split(b"=", 1)[1].decode()
    program = os.path.basename(args[0].decode()) if args and args[0] else "?"
    if program.startswith("python") and len(args) > 1:
        program = os.path.basename(args[1].decode())
    return program


def memory_kb(pid):
    """(VmRSS, VmHWM, Pss) in kB, or None when the process has gone. RSS counts every shared library page
    in every process that maps it; PSS splits each shared page among its users, so PSS sums to what the
    processes together hold."""
    try:
        status = pathlib.Path(f"/proc/{pid}/status").read_text()
        rollup = pathlib.Path(f"/proc/{pid}/smaps_rollup").read_text()
    except OSError:
        return None
    values = {}
    for line in (status + rollup).splitlines():
        key, _, rest = line.partition(":")
        if key in ("VmRSS", "VmHWM", "Pss") and rest.split():
            values[key] = int(rest.split()[0])
    return (values.get("VmRSS", 0), values.get("VmHWM", 0), values.get("Pss", 0)) if values else None


def cpu_seconds(pid):
    """User + system CPU time of a process so far, in seconds, or None when it has gone."""
    try:
        fields = pathlib.Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return None
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")  # utime, stime (fields 14, 15)


class SimClock:
    """The latest /clock, read by a subscriber of this script's own (anonymous) node."""

    def __init__(self):
        import rospy
        from rosgraph_msgs.msg import Clock
        self.now = None
        rospy.init_node("stack_memory", anonymous=True, disable_signals=True)
        rospy.Subscriber("/clock", Clock, self._on_clock, queue_size=1)

    def _on_clock(self, message):
        self.now = message.clock.to_sec()


def group(name):
    if name in HELPER_NAMES:
        return "helper"
    if any(name.startswith(m) for m in MASTER_NAMES):
        return "master"
    return "simulator" if name in SIMULATOR_NAMES else "stack"


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--scenario", default="closed_loop_still_1p5m")
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--real-time-factor", default="1.0")
    parser.add_argument("--camera-rate-hz", default="30")
    parser.add_argument("--launch-arg", action="append", default=[], metavar="NAME:=VALUE",
                        help="another sim.launch argument, e.g. perception_launch:=my_variant.launch")
    parser.add_argument("--out", default=str(ROOT / "results" / "stack_memory.json"))
    args = parser.parse_args()
    env = dict(os.environ, ROS_MASTER_URI=f"http://127.0.0.1:{free_port()}", ROS_IP="127.0.0.1")
    launch = subprocess.Popen(["roslaunch", str(ROOT / "launch" / "sim.launch"),
                               f"scenario:={args.scenario}", f"real_time_factor:={args.real_time_factor}",
                               f"camera_rate_hz:={args.camera_rate_hz}", "output:=log", "rviz:=false", *args.launch_arg],
                              env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    peak_hwm = {}     # node name -> highest VmHWM seen, kB
    peak_sum = {"stack": 0, "simulator": 0, "master": 0, "helper": 0}      # RSS summed, kB
    peak_pss_sum = dict(peak_sum)                                             # PSS summed, kB
    cpu_first, cpu_last = {}, {}  # pid -> CPU seconds, (name, CPU seconds): its first and last sample
    os.environ["ROS_MASTER_URI"] = env["ROS_MASTER_URI"]
    clock, sim_start, sim_end = None, None, None
    try:
        deadline = time.time() + args.seconds
        while time.time() < deadline and launch.poll() is None:
            # rospy.init_node waits for a master: call it once roslaunch has started one (a launch that ended never will)
            if clock is None and rosgraph.is_master_online():
                clock = SimClock()
            if clock is not None and clock.now is not None:
                sim_start = clock.now if sim_start is None else sim_start
                sim_end = clock.now
            sums = {"stack": 0, "simulator": 0, "master": 0, "helper": 0}
            pss_sums = dict(sums)
            for pid in descendants(launch.pid):
                name = node_name(pid)
                memory = memory_kb(pid)
                if not name or not memory:
                    continue
                sums[group(name)] += memory[0]
                pss_sums[group(name)] += memory[2]
                peak_hwm[name] = max(peak_hwm.get(name, 0), memory[1])
                cpu = cpu_seconds(pid)
                if cpu is not None and sim_start is not None:  # from the first /clock on: not start-up
                    cpu_first.setdefault(pid, cpu)
                    cpu_last[pid] = (name, cpu)
            for key, value in sums.items():
                peak_sum[key] = max(peak_sum[key], value)
                peak_pss_sum[key] = max(peak_pss_sum[key], pss_sums[key])
            time.sleep(1.0)
    finally:
        try:
            os.killpg(launch.pid, signal.SIGINT)
            launch.wait(timeout=30)
        except ProcessLookupError:  # the launch ended by itself (a scenario with a duration, a required node)
            pass
        except subprocess.TimeoutExpired:
            os.killpg(launch.pid, signal.SIGKILL)
    if launch.returncode is not None and time.time() < deadline:
        print(f"stack_memory: the launch ended after {args.seconds - (deadline - time.time()):.0f} s of "
              f"{args.seconds:.0f} (a scenario with a duration ends the simulator; pick one without)", file=sys.stderr)
    if launch.returncode not in (None, 0, -2) and not peak_hwm:
        print(f"stack_memory: the launch ended with {launch.returncode} before any sample", file=sys.stderr)
        return 1
    print(f"peak resident memory, {args.scenario}, {args.seconds:.0f} s wall (VmHWM per process, MB):")
    for name, kb in sorted(peak_hwm.items(), key=lambda item: -item[1]):
        print(f"  {name:28s} {kb / 1024:7.1f}  ({group(name)})")
    cpu_per_sim_s = {}
    if sim_start is not None and sim_end > sim_start:
        # Only what ran from the first /clock sample on counts: start-up (loading the model, building
        # pyramids) is not the per-frame cost. A respawned process counts from its first sample.
        for pid, (name, last) in cpu_last.items():
            cpu_per_sim_s[name] = cpu_per_sim_s.get(name, 0.0) + (last - cpu_first[pid]) / (sim_end - sim_start)
        print(f"CPU per second of sim time ({sim_end - sim_start:.1f} s of sim time, cameras at "
              f"{args.camera_rate_hz} Hz; 1.0 = one core):")
        for name, share in sorted(cpu_per_sim_s.items(), key=lambda item: -item[1]):
            if share >= 0.005:
                print(f"  {name:28s} {share:6.3f}  ({group(name)})")
    by_group = {g: sum(kb for n, kb in peak_hwm.items() if group(n) == g) / 1024 for g in peak_sum}
    print(f"stack without the simulator: RSS: sum of peaks {by_group['stack']:.1f} MB, peak of the sum "
          f"{peak_sum['stack'] / 1024:.1f} MB; PSS (shared pages split): peak of the sum {peak_pss_sum['stack'] / 1024:.1f} MB; "
          f"simulator {by_group['simulator']:.1f} MB; master {by_group['master']:.1f} MB")
    result = {"scenario": args.scenario, "seconds": args.seconds,
              "peak_rss_mb_by_process": {n: round(kb / 1024, 1) for n, kb in peak_hwm.items()},
              "stack_sum_of_peaks_mb": round(by_group["stack"], 1), "stack_peak_of_sum_mb": round(peak_sum["stack"] / 1024, 1),
              "stack_peak_of_pss_sum_mb": round(peak_pss_sum["stack"] / 1024, 1),
              "simulator_mb": round(by_group["simulator"], 1), "master_mb": round(by_group["master"], 1),
              "camera_rate_hz": float(args.camera_rate_hz),
              "sim_seconds": round(sim_end - sim_start, 2) if cpu_per_sim_s else 0.0,
              "cpu_cores_per_sim_second_by_process": {n: round(v, 3) for n, v in cpu_per_sim_s.items()},
              # the robot's stack alone (no simulator, master or helpers), for docs/PERFORMANCE.md (make report)
              "stack_cpu_cores_per_sim_second": round(sum(v for n, v in cpu_per_sim_s.items() if group(n) == "stack"), 3),
              "provenance": provenance(" ".join(["scripts/eval/stack_memory.py"] + sys.argv[1:]))}
    pathlib.Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    pathlib.Path(args.out).write_text(json.dumps(result, indent=2) + "\n")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
