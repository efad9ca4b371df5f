#!/usr/bin/env python3
"""Peak memory of the stack (issue 15): launches a scenario in the simulator, samples every process the
launch started once a second, and reports each one's peak resident memory (VmHWM) and the peak of their
sum, with and without the simulator (docking_sim, the target's renderer; not part of the robot's stack).

  scripts/eval/stack_memory.py [--scenario closed_loop_still_1p5m] [--seconds 60] [--out FILE.json]

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
    parser.add_argument("--out", default=str(ROOT / "results" / "stack_memory.json"))
    args = parser.parse_args()
    env = dict(os.environ, ROS_MASTER_URI=f"http://127.0.0.1:{free_port()}", ROS_IP="127.0.0.1")
    launch = subprocess.Popen(["roslaunch", str(ROOT / "launch" / "sim.launch"),
                               f"scenario:={args.scenario}", f"real_time_factor:={args.real_time_factor}",
                               "output:=log", "rviz:=false"],
                              env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    peak_hwm = {}     # node name -> highest VmHWM seen, kB
    peak_sum = {"stack": 0, "simulator": 0, "master": 0, "helper": 0}      # RSS summed, kB
    peak_pss_sum = dict(peak_sum)                                             # PSS summed, kB
    try:
        deadline = time.time() + args.seconds
        while time.time() < deadline and launch.poll() is None:
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
            for key, value in sums.items():
                peak_sum[key] = max(peak_sum[key], value)
                peak_pss_sum[key] = max(peak_pss_sum[key], pss_sums[key])
            time.sleep(1.0)
    finally:
        os.killpg(launch.pid, signal.SIGINT)
        try:
            launch.wait(timeout=30)
        except subprocess.TimeoutExpired:
            os.killpg(launch.pid, signal.SIGKILL)
    if launch.returncode not in (None, 0, -2) and not peak_hwm:
        print(f"stack_memory: the launch ended with {launch.returncode} before any sample", file=sys.stderr)
        return 1
    print(f"peak resident memory, {args.scenario}, {args.seconds:.0f} s wall (VmHWM per process, MB):")
    for name, kb in sorted(peak_hwm.items(), key=lambda item: -item[1]):
        print(f"  {name:28s} {kb / 1024:7.1f}  ({group(name)})")
    by_group = {g: sum(kb for n, kb in peak_hwm.items() if group(n) == g) / 1024 for g in peak_sum}
    print(f"stack without the simulator: RSS: sum of peaks {by_group['stack']:.1f} MB, peak of the sum "
          f"{peak_sum['stack'] / 1024:.1f} MB; PSS (shared pages split): peak of the sum {peak_pss_sum['stack'] / 1024:.1f} MB; "
          f"simulator {by_group['simulator']:.1f} MB; master {by_group['master']:.1f} MB")
    result = {"scenario": args.scenario, "seconds": args.seconds,
              "peak_rss_mb_by_process": {n: round(kb / 1024, 1) for n, kb in peak_hwm.items()},
              "stack_sum_of_peaks_mb": round(by_group["stack"], 1), "stack_peak_of_sum_mb": round(peak_sum["stack"] / 1024, 1),
              "stack_peak_of_pss_sum_mb": round(peak_pss_sum["stack"] / 1024, 1),
              "simulator_mb": round(by_group["simulator"], 1), "master_mb": round(by_group["master"], 1)}
    pathlib.Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    pathlib.Path(args.out).write_text(json.dumps(result, indent=2) + "\n")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
