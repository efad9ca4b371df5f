#!/usr/bin/env python3
"""robot.launch in bench mode, end to end, with no hardware (wall time: there is no simulator clock).

The cameras read image sequences that the simulator's renderer wrote (render_bench_frames, run by the launch
itself), perception and the planner run as on the robot, omni_base drives the fake motor board over a
pseudo-terminal; the board's ~wheels topic is the truth of what the wheels do. Asserts:
  1. frames in: images on the three camera topics, and valid target estimates from them;
  2. no goal: for idle_s the planner is IDLE, every cmd_vel is zero, no wheel turns and odometry moves
     less than 1 mm;
  3. a goal (the docking action): non-zero wheel speeds reach the board;
  4. cancel: the goal ends CANCELLED, the planner goes IDLE and the wheels stop within stop_within_s;
  5. a client that dies (kill -9) mid-docking: the planner ends the docking, the wheels stop;
  6. the cameras unplugged mid-docking (their frames taken away): within the hold limit (the client's
     --search-timeout) the docking ends PERCEPTION_LOST, `dock start`'s last line names the camera and its
     source's fault, and the wheels stop.
"""
import math
import os
import pathlib
import signal
import subprocess
import sys
import threading
import time
import unittest

import actionlib
import rospy
import rostest
from docking_settings.declarations import declared_defaults
from actionlib_msgs.msg import GoalStatus
from docking_msgs.msg import DockAction, DockGoal, DockResult, DockingState, TargetEstimate
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from sensor_msgs.msg import Image, JointState

PKG = "docking_planner"
WORKSPACE = pathlib.Path(__file__).resolve().parents[4]
STOPPED_RAD_S = 0.5  # a wheel slower than this (1.2 cm/s at the rim) counts as stopped


def planner_setting(key):
    """The planner's value in force: its parameter when config/planner.yaml sets it, else its declared default."""
    return rospy.get_param("/planner/" + key, declared_defaults("planner.yaml")[key])


class RobotBench(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("robot_bench_check")
        cls.lock = threading.Lock()
        cls.images = {"stereo/left/image_raw": 0, "stereo/right/image_raw": 0, "ir/image_raw": 0}
        cls.valid_estimates = 0
        cls.odom = []    # (wall, x, y)
        cls.wheels = []  # (wall, max |rad/s|)
        cls.cmds = []    # (wall, Twist)
        cls.states = []  # (wall, DockingState)
        for topic in cls.images:
            rospy.Subscriber(topic, Image, lambda m, t=topic: cls.count_image(t), queue_size=1)
        rospy.Subscriber("target/estimate", TargetEstimate, cls.on_estimate, queue_size=10)
        rospy.Subscriber("odom", Odometry, cls.on_odom, queue_size=50)
        rospy.Subscriber("fake_motor_board/wheels", JointState, cls.on_wheels, queue_size=50)
        rospy.Subscriber("cmd_vel", Twist, cls.on_cmd, queue_size=50)
        rospy.Subscriber("docking/state", DockingState, cls.on_state, queue_size=50)

    @classmethod
    def count_image(cls, topic):
        with cls.lock:
            cls.images[topic] += 1

    @classmethod
    def on_estimate(cls, msg):
        if msg.valid and msg.position_valid:
            with cls.lock:
                cls.valid_estimates += 1

    @classmethod
    def on_odom(cls, msg):
        with cls.lock:
            cls.odom.append((time.time(), msg.pose.pose.position.x, msg.pose.pose.position.y))

    @classmethod
    def on_wheels(cls, msg):
        with cls.lock:
            cls.wheels.append((time.time(), max(abs(v) for v in msg.velocity) if msg.velocity else 0.0))

    @classmethod
    def on_cmd(cls, msg):
        with cls.lock:
            cls.cmds.append((time.time(), msg))

    @classmethod
    def on_state(cls, msg):
        with cls.lock:
            cls.states.append((time.time(), msg))

    def wait_for(self, what, predicate, timeout_s):
        deadline = time.time() + timeout_s
        while time.time() < deadline:
            with self.lock:
                if predicate():
                    return
            time.sleep(0.1)
        with self.lock:
            self.fail("%s within %.0f s (images %s, valid estimates %d, last state %s)" % (
                what, timeout_s, self.images, self.valid_estimates,
                self.states[-1][1].state_name + ": " + self.states[-1][1].reason if self.states else "none"))

    def wheels_stopped_since(self, t0):
        """Wall time from t0 until the board's wheels were last seen turning (None: never seen stopped)."""
        with self.lock:
            after = [(t, w) for t, w in self.wheels if t >= t0]
        turning = [t for t, w in after if w > STOPPED_RAD_S]
        stopped = [t for t, w in after if w <= STOPPED_RAD_S]
        if not stopped:
            return None
        return (max(turning) - t0) if turning else 0.0

    def start_docking(self, client):
        client.send_goal(DockGoal())
        t_goal = time.time()
        self.wait_for("wheels turning on the fake board after the goal",
                      lambda: any(t > t_goal and w > 2.0 for t, w in self.wheels), 60.0)

    def test_bench_chain(self):
        startup = rospy.get_param("~startup_timeout_s", 120.0)
        idle_s = rospy.get_param("~idle_s", 20.0)
        stop_within = rospy.get_param("~stop_within_s", 0.6)
        # 1. Frames in, estimates out.
        self.wait_for("images on every camera topic",
                      lambda: all(n >= 5 for n in self.images.values()), startup)
        self.wait_for("valid target estimates from the frames", lambda: self.valid_estimates >= 5, startup)
        self.wait_for("odometry from the fake board", lambda: len(self.odom) > 10, 30.0)

        # 2. No goal: nothing moves.
        t0 = time.time()
        time.sleep(idle_s)
        with self.lock:
            odom = [o for o in self.odom if o[0] >= t0]
            wheels = [w for t, w in self.wheels if t >= t0]
            cmds = [c for t, c in self.cmds if t >= t0]
            states = [s for t, s in self.states if t >= t0]
        self.assertGreater(len(odom), 10 * idle_s, "too little odometry while idle")
        moved = math.hypot(odom[-1][1] - odom[0][1], odom[-1][2] - odom[0][2])
        self.assertLess(moved, 0.001, "odometry moved %.4f m with no docking goal" % moved)
        self.assertTrue(wheels and max(wheels) <= STOPPED_RAD_S, "a wheel turned with no goal: %.2f rad/s" % max(wheels))
        self.assertTrue(all(c.linear.x == 0 and c.linear.y == 0 and c.angular.z == 0 for c in cmds),
                        "non-zero cmd_vel with no docking goal")
        self.assertTrue(states and all(s.state == DockingState.IDLE for s in states),
                        "planner not IDLE without a goal: %s" % sorted({s.state_name for s in states}))
        rospy.loginfo("robot_bench_check: %.0f s without a goal: odometry moved %.5f m, %d zero cmd_vel",
                      idle_s, moved, len(cmds))

        # 3. A goal: commands reach the board.
        client = actionlib.SimpleActionClient("docking/dock", DockAction)
        self.assertTrue(client.wait_for_server(rospy.Duration(30.0)), "no docking action server")
        self.start_docking(client)

        # 4. Cancel: CANCELLED, IDLE, wheels stopped within the watchdog time.
        t_cancel = time.time()
        client.cancel_goal()
        self.assertTrue(client.wait_for_result(rospy.Duration(10.0)), "no result after cancel")
        self.assertEqual(client.get_state(), GoalStatus.PREEMPTED)
        self.assertEqual(client.get_result().outcome, DockResult.CANCELLED, client.get_result().reason)
        time.sleep(2.0)
        stop_s = self.wheels_stopped_since(t_cancel)
        self.assertIsNotNone(stop_s, "the wheels never stopped after cancel")
        self.assertLessEqual(stop_s, stop_within, "wheels turned %.2f s after cancel" % stop_s)
        with self.lock:
            self.assertEqual(self.states[-1][1].state, DockingState.IDLE)
        rospy.loginfo("robot_bench_check: cancel -> wheels stopped after %.2f s", stop_s)

        # 5. The client dies mid-docking: the planner notices, ends the docking, the wheels stop.
        dock = WORKSPACE / "src" / "docking_planner" / "scripts" / "dock"
        proc = subprocess.Popen([str(dock), "start"], stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL, env=dict(os.environ))
        t_goal = time.time()
        self.wait_for("wheels turning after the command-line client's goal",
                      lambda: any(t > t_goal and w > 2.0 for t, w in self.wheels), 60.0)
        t_kill = time.time()
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        loss_timeout = planner_setting("client_loss_timeout_s")
        time.sleep(loss_timeout + 3.0)
        stop_s = self.wheels_stopped_since(t_kill)
        self.assertIsNotNone(stop_s, "the wheels never stopped after the client died")
        self.assertLessEqual(stop_s, loss_timeout + stop_within, "wheels turned %.2f s after the client died" % stop_s)
        with self.lock:
            last = self.states[-1][1]
        self.assertEqual(last.state, DockingState.IDLE, last.reason)
        rospy.loginfo("robot_bench_check: client killed -> wheels stopped after %.2f s (%s)", stop_s, last.reason)

        # 6. The cameras unplugged mid-docking: the docking ends within the hold limit, naming the cameras.
        self.unplug_cameras_mid_docking(stop_within)

    def unplug_cameras_mid_docking(self, stop_within):
        hold_limit = rospy.get_param("~hold_limit_s", 5.0)
        frames = pathlib.Path(rospy.get_param("~frames_dir"))
        proc = subprocess.Popen(["rosrun", PKG, "dock", "start", "--search-timeout", str(hold_limit)],
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        t_goal = time.time()
        self.wait_for("wheels turning after dock start", lambda: any(t > t_goal and w > 2.0 for t, w in self.wheels), 60.0)
        unplugged = frames.with_name(frames.name + ".unplugged")
        frames.rename(unplugged)
        t_unplug = time.time()
        try:
            out = proc.communicate(timeout=hold_limit + 60.0)[0]
        finally:
            unplugged.rename(frames)
        t_end = time.time()
        last = out.strip().splitlines()[-1] if out.strip() else ""
        self.assertEqual(proc.returncode, 1, out)
        self.assertTrue(last.startswith("dock: FAILED after") and "PERCEPTION_LOST" in last, out)
        self.assertIn("camera stereo_camera", last, "the result does not name the stereo camera: " + last)
        self.assertIn("no readable image matches", last, "the result does not say what is wrong with it: " + last)
        stop_s = self.wheels_stopped_since(t_unplug)
        self.assertIsNotNone(stop_s, "the wheels never stopped after the cameras were unplugged")
        with self.lock:
            turning_late = [t for t, w in self.wheels if t > t_end and w > STOPPED_RAD_S]
        self.assertFalse(turning_late, "wheels turning after the docking ended")
        print("robot_bench_check: cameras unplugged -> ended after %.1f s, wheels stopped after %.2f s: %s" % (
            t_end - t_unplug, stop_s, last), flush=True)


if __name__ == "__main__":
    rostest.rosrun(PKG, "robot_bench_check", RobotBench, sys.argv)
