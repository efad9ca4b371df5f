#!/usr/bin/env python3
"""Issue 12: a camera rate that is not a number, or out of range, must stop the camera at start-up with
an error naming the parameter (camera_rate_hz:=fast once ran at a default rate without a word). Since
issue 53 a configuration error parks the node (docking_settings::runNode): one FATAL naming the key, then
it waits publishing nothing. Starts ir_camera (config/ir_camera.yaml, a test image sequence) with each bad
rate_hz and asserts the key in its output and no image; a good rate keeps it running and publishing."""
import os
import select
import subprocess
import time
import unittest

import rospkg
import rospy
import rostest
import yaml

PKG = "docking_perception"


class BadCameraRate(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("bad_rate_check")
        package = rospkg.RosPack().get_path(PKG)
        with open(os.path.join(package, "..", "..", "config", "ir_camera.yaml")) as f:
            cls.config = yaml.safe_load(f)
        cls.frames = os.path.join(package, "test", "camera", "frames", "small_%04d.png")

    def start(self, name, rate):
        for key, value in self.config.items():
            rospy.set_param("/%s/%s" % (name, key), value)
        rospy.set_param("/%s/source" % name, self.frames)
        rospy.set_param("/%s/rate_hz" % name, rate)
        return subprocess.Popen(["rosrun", PKG, "ir_camera", "__name:=" + name],
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)

    def assert_refused(self, name, rate):
        process = self.start(name, rate)
        output = ""
        deadline = time.time() + 60.0
        try:
            while "/%s/rate_hz" % name not in output and time.time() < deadline and process.poll() is None:
                if select.select([process.stdout], [], [], 0.5)[0]:
                    output += process.stdout.readline()
            self.assertIn("/%s/rate_hz" % name, output, "ir_camera never named the bad rate_hz %r" % (rate,))
            self.assertIn("FATAL", output)
            self.assertIsNone(process.poll(), "a configuration error parks the node; it exited")
        finally:
            process.terminate()
            process.communicate()

    def test_non_numeric_rate_stops_the_camera(self):
        self.assert_refused("ir_fast", "fast")

    def test_out_of_range_rates_stop_the_camera(self):
        self.assert_refused("ir_zero", 0.0)
        self.assert_refused("ir_huge", 1000.0)

    def test_a_numeric_rate_keeps_it_running(self):
        process = self.start("ir_good", 10.0)
        try:
            process.communicate(timeout=5.0)
            self.fail("ir_camera exited with a good rate_hz")
        except subprocess.TimeoutExpired:
            pass
        finally:
            process.terminate()
            process.communicate()


if __name__ == "__main__":
    rostest.rosrun(PKG, "bad_camera_rate", BadCameraRate)
