#!/usr/bin/env python3
"""Live tuning: scripts/tune/save_params.py writes a running node's tuned values back into its YAML, which
holds only what differs from the declared defaults (settings/arbiter.yaml). The arbiter runs from a
temporary copy of config/arbiter.yaml; two of its settings are changed through dynamic_reconfigure (as
`dynparam set` does); save_params.py must add exactly those two lines, keep every other line byte for byte
(comments included), and write nothing on a dry run; set back to their defaults, the lines go again and
the file is as it was. It must refuse a node that is not running and a node no launch file maps to a YAML."""
import os
import pathlib
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import unittest

import rosparam
import rospy
import rostest
import yaml
from dynamic_reconfigure.client import Client

PKG = "docking_perception"
ROOT = pathlib.Path(__file__).resolve().parents[4]  # the repository this test belongs to
SAVE_PARAMS = ROOT / "scripts" / "tune" / "save_params.py"
NODE = "/arbiter"
# A float with a comment aligned after it, and an integer: the two kinds the file holds most.
CHANGES = {"switch_range_m": 2.75, "min_visible_inliers": 12}


def run_save_params(*args):
    return subprocess.run([sys.executable, str(SAVE_PARAMS)] + list(args), capture_output=True, text=True,
                          timeout=60)


class SaveParams(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("save_params_check")
        cls.dir = pathlib.Path(tempfile.mkdtemp(prefix="save_params_"))
        cls.config = cls.dir / "config"
        cls.config.mkdir()
        for yaml_file in (ROOT / "config").glob("*.yaml"):
            shutil.copy(yaml_file, cls.config)
        cls.yaml = cls.config / "arbiter.yaml"
        cls.original = cls.yaml.read_bytes()
        # The arbiter as guidance.launch starts it: the YAML in its private namespace, then the node.
        for params, namespace in rosparam.load_file(str(cls.yaml), default_namespace=NODE):
            rosparam.upload_params(namespace, params)
        cls.node = subprocess.Popen(["rosrun", PKG, "arbiter", "__name:=arbiter"], start_new_session=True)
        cls.client = None
        try:
            cls.client = cls.wait_for_server(60.0)
        except BaseException:
            cls.tearDownClass()  # unittest does not when setUpClass fails
            raise

    @classmethod
    def wait_for_server(cls, timeout_s):
        """The arbiter's dynamic_reconfigure client, once its server is up; an arbiter that exits (not
        built, a YAML key refused) fails the test at once, with its exit code."""
        deadline = time.time() + timeout_s
        while True:
            if cls.node.poll() is not None:
                raise RuntimeError("the arbiter exited (code %d) before its dynamic_reconfigure server came up"
                                   % cls.node.returncode)
            try:
                return Client(NODE, timeout=1.0)
            except rospy.ROSException:
                if time.time() > deadline:
                    raise

    @classmethod
    def tearDownClass(cls):
        if cls.client:
            cls.client.close()
        if cls.node.poll() is None:
            os.killpg(cls.node.pid, signal.SIGINT)
            cls.node.wait(timeout=30)
        shutil.rmtree(cls.dir, ignore_errors=True)

    def test_1_unchanged_node_writes_nothing(self):
        result = run_save_params("--config-dir", str(self.config), NODE)
        self.assertEqual(result.returncode, 0, result.stderr)
        self.assertEqual(result.stdout, "", "a diff before any change")
        self.assertEqual(self.yaml.read_bytes(), self.original)

    def test_2_dry_run_then_write_back(self):
        defaults = {key: self.client.get_configuration()[key] for key in CHANGES}
        applied = self.client.update_configuration(CHANGES)
        for key, value in CHANGES.items():
            self.assertEqual(applied[key], value, "the arbiter refused %s" % key)
        dry = run_save_params("--dry-run", "--config-dir", str(self.config), NODE)
        self.assertEqual(dry.returncode, 0, dry.stderr)
        self.assertEqual(self.yaml.read_bytes(), self.original, "a dry run wrote the file")
        for key in CHANGES:
            self.assertRegex(dry.stdout, r"(?m)^\+%s: " % key, "the dry run's diff lacks %s" % key)
        real = run_save_params("--config-dir", str(self.config), NODE)
        self.assertEqual(real.returncode, 0, real.stderr)
        self.assertEqual(real.stdout, dry.stdout, "the diff written differs from the dry run's")
        written = yaml.safe_load(self.yaml.read_text())
        self.assertEqual(written, CHANGES, "the file holds more or less than the two tuned values")
        self.assertEqual(type(written["min_visible_inliers"]), int, "an int written as float")
        comments = [line for line in self.original.decode().splitlines() if line.startswith("#")]
        self.assertTrue(comments, "the test expects a commented file")
        for line in comments:
            self.assertIn(line, self.yaml.read_text().splitlines(), "a comment lost")
        again = run_save_params("--config-dir", str(self.config), NODE)
        self.assertEqual((again.returncode, again.stdout), (0, ""), "a second save changed the file again")
        # Back to the defaults: the lines go, and the file is the original again.
        self.client.update_configuration(defaults)
        back = run_save_params("--config-dir", str(self.config), NODE)
        self.assertEqual(back.returncode, 0, back.stderr)
        self.assertEqual(self.yaml.read_bytes(), self.original, "the defaults did not restore the file")

    def test_3_refuses_node_not_running(self):
        result = run_save_params("--config-dir", str(self.config), "--timeout", "1", "/disparity_detector")
        self.assertEqual(result.returncode, 1)
        self.assertIn("not running", result.stderr)

    def test_4_refuses_unknown_node(self):
        result = run_save_params("--config-dir", str(self.config), "/no_such_node")
        self.assertEqual(result.returncode, 1)
        self.assertIn("unknown node", result.stderr)

    def test_5_refuses_nested_or_repeated_keys(self):
        sys.path.insert(0, str(SAVE_PARAMS.parent))
        import save_params
        nested = "# a comment\nconsistency:\n  gate: 1.0   # nested\n"
        with self.assertRaisesRegex(save_params.SaveError, "nested under 'consistency'"):
            save_params.write_back(nested, {"gate": 2.0}, "nested.yaml")
        repeated = "gate: 1.0\nother: true\ngate: 1.0\n"
        with self.assertRaisesRegex(save_params.SaveError, "ambiguous"):
            save_params.write_back(repeated, {"gate": 2.0}, "repeated.yaml")
        # Booleans, strings and a live key the file lacks (reported, not added).
        text = "flag: true  # on\nname: 'a b'   # quoted\n"
        new, changed, missing = save_params.write_back(text, {"flag": False, "name": "c d", "extra": 1}, "f.yaml")
        self.assertEqual(new, "flag: false # on\nname: 'c d'   # quoted\n")
        self.assertEqual((changed, missing), (["flag", "name"], ["extra"]))
        # With declared defaults: a value back at its default leaves the file, a new one is added.
        new, changed, _ = save_params.write_back(text, {"flag": True, "name": "x", "extra": 2.5}, "f.yaml",
                                                 {"flag": True, "name": "a b", "extra": 1.0})
        self.assertEqual(new, "name: 'x'     # quoted\nextra: 2.5\n")
        self.assertEqual(sorted(changed), ["extra", "flag", "name"])


if __name__ == "__main__":
    rostest.rosrun(PKG, "save_params_check", SaveParams)
