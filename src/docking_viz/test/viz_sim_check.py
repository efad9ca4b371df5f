#!/usr/bin/env python3
"""markers_sim.test's one check: markers_sim_check.py's, then debug_images_check.py's, on one launched
closed loop (each launched one of its own before: the same scene twice, ~12 s more wall time).

The markers' check runs first: it needs the docking under way (the planner's safe circle around a held
port), and the docking, started with the launch, ends ~13 s (sim) in. The debug images' check does not
depend on the docking (the disparity detector never rests there: markers_sim.test) and counts its
phases' frames from its own start.
"""
import sys
import unittest

import rospy
import rostest
from debug_images_check import DebugImages
from markers_sim_check import MarkersInTheLoop

PKG = "docking_viz"


def suite():
    loader = unittest.TestLoader()
    return unittest.TestSuite([loader.loadTestsFromTestCase(MarkersInTheLoop),
                               loader.loadTestsFromTestCase(DebugImages)])


if __name__ == "__main__":
    rospy.init_node("viz_sim_check")
    rostest.rosrun(PKG, "viz_sim", "__main__.suite", sys.argv)
