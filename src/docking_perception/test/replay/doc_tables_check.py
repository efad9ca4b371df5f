#!/usr/bin/env python3
"""doc_tables.test: scripts/tune/doc_tables.py --check must find every generated block of the docs equal to
what the tool prints today, and the sample bags' replays (each sweep's run at config/'s own value) must
meet ~limits against the truth the bags hold (see the .test file). The figures are printed."""
import json
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

import rospkg
import rospy
import rostest

PKG = "docking_perception"
ROOT = os.path.abspath(os.path.join(rospkg.RosPack().get_path(PKG), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "scripts", "tune"))
import doc_tables  # noqa: E402


class DocTables(unittest.TestCase):
    def setUp(self):
        self.out = tempfile.mkdtemp(prefix="doc_tables_")

    def tearDown(self):
        shutil.rmtree(self.out, ignore_errors=True)

    def test_docs_print_what_the_tool_prints(self):
        for sweep in doc_tables.SWEEPS:
            bag = os.path.join(ROOT, sweep.bag)
            self.assertTrue(os.path.isfile(bag), "no sample bag %s" % bag)
            self.assertLessEqual(os.path.getsize(bag), 20e6, "%s is over 20 MB" % bag)
        done = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "tune", "doc_tables.py"), "--check",
                               "--out", self.out], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        print(done.stdout, flush=True)
        self.assertEqual(done.returncode, 0, done.stdout[-4000:])
        for sweep, source, min_share, max_median_mm, max_p95_mm, max_rotation_deg in rospy.get_param("~limits"):
            with open(os.path.join(self.out, sweep, "report.json")) as stream:
                metrics = doc_tables.config_run(json.load(stream))["sources"][source]
            name = "%s %s" % (sweep, source)
            position, rotation = metrics["position_error_mm"], metrics["orientation_error_deg"]
            share = metrics["valid_frames"] / float(metrics["frames"])
            orientation = rotation.get("median") if rotation else None
            print("doc_tables_check: %s: valid %d/%d, position error median %.1f / p95 %.1f mm, orientation "
                  "median %s" % (name, metrics["valid_frames"], metrics["frames"], position["median"], position["p95"],
                                 "-" if orientation is None else "%.2f deg" % orientation), flush=True)
            self.assertGreaterEqual(share, min_share, "%s: valid share" % name)
            self.assertLessEqual(position["median"], max_median_mm, "%s: median position error" % name)
            self.assertLessEqual(position["p95"], max_p95_mm, "%s: p95 position error" % name)
            if max_rotation_deg >= 0:
                self.assertLessEqual(rotation["median"], max_rotation_deg, "%s: median orientation error" % name)


if __name__ == "__main__":
    rospy.init_node("doc_tables_check")
    rostest.rosrun(PKG, "doc_tables", DocTables, sys.argv)
