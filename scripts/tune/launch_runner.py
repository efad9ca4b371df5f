"""Runs roslaunch on a master of its own (scripts/tune): each replay or recording gets a free port, so
that runs never meet each other or a running system on 11311.

A replay whose configuration a node refuses does not end by itself: perception's loaders are respawned
(docs/RELIABILITY.md), so the refused nodelet fails again every second, and the lossless player waits
its timeout for each of that estimator's frames. The runner therefore watches the launch's output and
stops it at the first FATAL line or at the death of a process other than the player, and returns the
node's own words (e.g. "parameter /disparity_detector/median_kernel_px must be 0, 1 (off), 3 or 5").
"""
import dataclasses
import os
import random
import re
import signal
import socket
import subprocess
import time

ANSI_ESCAPE = re.compile(r"\x1b\[[0-9;]*m")
LOG_STAMP = re.compile(r"\[[0-9.]+(, [0-9.]+)?\]: ")
PID = re.compile(r"\[pid \d+, ")
# replay_paced's last line (src/docking_perception/scripts/replay_paced).
PLAYER_SUMMARY = re.compile(r"replay_paced: (\d+) frames played, (\d+) skipped.*?(\d+) lost")
# A node that gives up: its FATAL lines, or roslaunch reporting its death (the player's failure is said by
# its own lines; its normal end ends the launch quietly: src/docking_perception/scripts/ends_launch).
FAILURE = re.compile(r"\[FATAL\]|^\[(?!play-)[\w-]+\] process has died")


@dataclasses.dataclass
class LaunchResult:
    """How one roslaunch ended."""
    exit_code: int
    failure_lines: list    # the nodes' own error lines, when a node refused to run
    timed_out: bool
    player_summary: str    # replay_paced's summary line ("" when it never finished)
    frames_played: int
    frames_lost: int


# Masters get ports below the kernel's ephemeral range (/proc/sys/net/ipv4/ip_local_port_range, 32768-60999
# by default). A port the kernel picked (bind to 0) is free when checked, but it can be handed to any
# node's XML-RPC server before roslaunch binds it; roslaunch then takes that node for a running master
# and exits 1 (seen once in a rostest). The kernel hands out no port below its range by itself.
MASTER_PORTS = (20000, 32767)
_port_random = random.Random(os.urandom(8))  # not the global generator, which a test may have seeded


def ephemeral_low():
    try:
        with open("/proc/sys/net/ipv4/ip_local_port_range") as stream:
            return int(stream.read().split()[0])
    except (OSError, ValueError, IndexError):
        return MASTER_PORTS[1] + 1


def free_port():
    """A TCP port nobody listens on now, outside the kernel's ephemeral range, for `roslaunch -p`."""
    high = min(MASTER_PORTS[1], ephemeral_low() - 1)
    for _ in range(1000):
        port = _port_random.randint(MASTER_PORTS[0], high)
        with socket.socket() as sock:
            try:
                sock.bind(("127.0.0.1", port))
            except OSError:
                continue
            return port
    raise RuntimeError("no free port in %d-%d" % (MASTER_PORTS[0], high))


def stop(proc, timeout_s=60.0):
    """SIGINT to the launch's process group (roslaunch then stops its nodes in order), then waits; SIGKILL
    after timeout_s. Nothing to do for no process or one already gone."""
    if proc is None or proc.poll() is not None:
        return
    try:
        os.killpg(proc.pid, signal.SIGINT)
        try:
            proc.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    except ProcessLookupError:
        pass


def failure_context(lines):
    """The distinct failure lines of the failing node(s), in order, without colours or the command."""
    seen, out = set(), []
    for line in lines:
        text = ANSI_ESCAPE.sub("", line).strip().split(", cmd ")[0]
        text = LOG_STAMP.sub("", PID.sub("[", text))  # repeated by each respawn: said once
        if FAILURE.search(text) and text not in seen:
            seen.add(text)
            out.append(text)
    return out[:12]


def run_launch(args, log_path, timeout_s, stop_on_failure=True, port=None):
    """Runs `roslaunch -p PORT args...` (PORT: `port`, else a free one) with its output in log_path; returns a
    LaunchResult."""
    port = port or free_port()
    env = dict(os.environ, ROS_MASTER_URI="http://127.0.0.1:%d" % port)
    deadline = time.time() + timeout_s
    lines, failed, timed_out = [], False, False
    with open(log_path, "w") as log:
        proc = subprocess.Popen(["roslaunch", "-p", str(port)] + args, env=env, stdout=log,
                                stderr=subprocess.STDOUT, start_new_session=True)
        with open(log_path) as reader:
            while proc.poll() is None:
                time.sleep(0.5)
                new = reader.read().splitlines()
                lines += new
                if stop_on_failure and any(FAILURE.search(ANSI_ESCAPE.sub("", line)) for line in new):
                    time.sleep(2.0)  # the rest of the node's complaint
                    failed = True
                    break
                if time.time() > deadline:
                    timed_out = True
                    break
            stop(proc)
            lines += reader.read().splitlines()
    match = next((PLAYER_SUMMARY.search(ANSI_ESCAPE.sub("", l)) for l in lines if PLAYER_SUMMARY.search(l)), None)
    summary = match.string[match.start():].strip() if match else ""
    return LaunchResult(proc.returncode, failure_context(lines) if failed else [], timed_out, summary,
                        int(match.group(1)) if match else 0, int(match.group(3)) if match else 0)
