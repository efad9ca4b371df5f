#!/usr/bin/env python3
"""Issue 14: the markers' content in the closed loop (markers_sim.test: the simulator docking a still
target from 1.5 m). Asserts, from the topics alone:
  - lazy: while nobody subscribes to docking/markers, the markers node subscribes to none of its inputs,
    and again after the subscriber leaves;
  - the planner's safe circle and search orbit: every point at the planner's own radius
    (safe_radius_m, search_orbit_radius_m: settings/planner.yaml's defaults or /planner's overrides) from the port it holds (docking/geometry),
    in the planner's odom frame;
  - estimates: drawn in a camera optical frame, ellipsoid scales finite and positive, a source drawn;
  - the state label: in the planner's base frame, naming a state the planner published;
  - no NaN or infinite number in any marker.
"""
import math
import sys
import time
import unittest

import rosgraph
import rospy
import rostest
from docking_settings.declarations import declared_defaults
from docking_msgs.msg import DockingState, PlannerGeometry
from visualization_msgs.msg import Marker, MarkerArray

PKG = "docking_viz"
MARKERS_NODE = "/markers"
MARKERS_TOPIC = "/docking/markers"
INPUTS = ("/perception/disparity/estimate", "/perception/mono_visible/estimate", "/perception/mono_ir/estimate",
          "/target/estimate", "/docking/state", "/docking/geometry", "/cmd_vel")
MIN_ARRAYS = 20  # 2 s of markers at 10 Hz: every array's numbers are checked
OPTICAL_FRAMES = ("stereo_left_optical_frame", "stereo_right_optical_frame", "ir_optical_frame")


def subscriptions_of(node):
    _, subscribers, _ = rosgraph.Master("/markers_sim_check").getSystemState()
    return sorted(topic for topic, nodes in subscribers if node in nodes and topic in INPUTS)


def planner_setting(key):
    """The planner's value in force: its parameter when config/planner.yaml sets it, else its declared default."""
    return rospy.get_param("/planner/" + key, declared_defaults("planner.yaml")[key])


def numbers_of(marker):
    p, q, s = marker.pose.position, marker.pose.orientation, marker.scale
    values = [p.x, p.y, p.z, q.x, q.y, q.z, q.w, s.x, s.y, s.z]
    for point in marker.points:
        values += [point.x, point.y, point.z]
    return values


class MarkersInTheLoop(unittest.TestCase):
    def setUp(self):
        if not rospy.core.is_initialized():  # viz_sim_check.py runs it after another check
            rospy.init_node("markers_sim_check")
        self.arrays = []
        self.geometry = None
        self.states = set()

    def wait_for(self, condition, timeout_s, what):
        deadline = time.time() + timeout_s
        while not condition():
            self.assertLess(time.time(), deadline, what)
            time.sleep(0.5)

    def test_markers(self):
        # The markers node is up and its inputs are up (the planner publishes its state).
        rospy.wait_for_message("/docking/state", DockingState, timeout=600)
        self.wait_for(lambda: any(MARKERS_NODE in n for t, n in
                                  rosgraph.Master("/markers_sim_check").getSystemState()[0] if t == MARKERS_TOPIC),
                      120, "the markers node does not publish docking/markers")
        time.sleep(2.0)
        self.assertEqual(subscriptions_of(MARKERS_NODE), [], "inputs subscribed while nobody watches")

        state_sub = rospy.Subscriber("/docking/state", DockingState, lambda m: self.states.add(m.state_name))
        geometry_sub = rospy.Subscriber("/docking/geometry", PlannerGeometry, self.on_geometry)
        marker_sub = rospy.Subscriber(MARKERS_TOPIC, MarkerArray, self.arrays.append)
        self.wait_for(lambda: self.geometry is not None and self.geometry.has_port and self.drawn("planner", 0)
                      and self.drawn_estimate() and len(self.arrays) >= MIN_ARRAYS, 600,
                      "no safe circle and estimate drawn with a held port in %d arrays" % MIN_ARRAYS)
        self.check_arrays()
        marker_sub.unregister()
        geometry_sub.unregister()
        state_sub.unregister()
        self.wait_for(lambda: subscriptions_of(MARKERS_NODE) == [], 60,
                      "inputs still subscribed after the last subscriber left: %s" % subscriptions_of(MARKERS_NODE))

    def on_geometry(self, msg):
        self.geometry = msg

    def latest(self, ns, marker_id):
        for array in reversed(self.arrays):
            for m in array.markers:
                if m.ns == ns and m.id == marker_id and m.action == Marker.ADD:
                    return m
        return None

    def drawn(self, ns, marker_id):
        return self.latest(ns, marker_id) is not None

    def drawn_estimate(self):
        return any(m.ns.startswith("estimate/") and m.action == Marker.ADD for a in self.arrays for m in a.markers)

    def check_arrays(self):
        for array in self.arrays:
            for m in array.markers:
                if m.action == Marker.ADD:
                    self.assertTrue(all(math.isfinite(v) for v in numbers_of(m)), "%s/%d: not finite" % (m.ns, m.id))
                    self.assertTrue(m.header.frame_id, "%s/%d: no frame" % (m.ns, m.id))
        port = self.geometry.port
        for marker_id, parameter in ((0, "safe_radius_m"), (1, "search_orbit_radius_m")):
            circle = self.latest("planner", marker_id)
            self.assertIsNotNone(circle, "planner marker %d" % marker_id)
            self.assertEqual(circle.header.frame_id, self.geometry.header.frame_id)
            radius = planner_setting(parameter)
            distances = [math.hypot(p.x - port.x, p.y - port.y) for p in circle.points]
            self.assertGreaterEqual(len(distances), 8)
            # The port moves a little between the geometry message and the marker (a fresh estimate): 5 mm.
            self.assertLess(max(abs(d - radius) for d in distances), 0.005,
                            "%s: circle radii %.4f-%.4f m against %.4f m" % (parameter, min(distances),
                                                                            max(distances), radius))
        estimates = [m for a in self.arrays for m in a.markers if m.ns.startswith("estimate/") and m.action == Marker.ADD]
        self.assertTrue(all(m.header.frame_id in OPTICAL_FRAMES for m in estimates),
                        {m.header.frame_id for m in estimates})
        ellipsoids = [m for m in estimates if m.id == 1]
        self.assertTrue(ellipsoids, "no covariance ellipsoid drawn")
        self.assertTrue(all(m.scale.x > 0 and m.scale.y > 0 and m.scale.z > 0 for m in ellipsoids))
        label = self.latest("state", 0)
        self.assertIsNotNone(label, "no state label")
        self.assertEqual(label.header.frame_id, "base_link")
        self.assertTrue(any(name in label.text for name in self.states), "label %r names none of %s" % (
            label.text, self.states))
        print("markers_sim_check: %d arrays; namespaces %s; label %r" % (
            len(self.arrays), sorted({m.ns for a in self.arrays for m in a.markers}), label.text), flush=True)


if __name__ == "__main__":
    rostest.rosrun(PKG, "markers_sim", MarkersInTheLoop, sys.argv)
