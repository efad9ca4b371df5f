#!/usr/bin/env python3
"""Every settings declaration of the workspace (src/*/settings/*.yaml) against the shipped YAML files of
config/ and the README tables (docking_settings.consistency): a key nobody reads, a value its declaration
refuses, a restated default or a stale table fails. Also: every file of config/ that configures a node is
claimed by a declaration (the data files of the robot, the target, the cameras and the scenarios are not
settings)."""
import pathlib
import sys
import unittest

WORKSPACE = pathlib.Path(__file__).resolve().parents[3]
sys.path.insert(0, str(WORKSPACE / "src" / "docking_settings" / "src"))
from docking_settings import consistency  # noqa: E402
from docking_settings.declarations import find_declarations  # noqa: E402

# Not a node's settings: what the robot and the target are (data every node reads); the simulated world
# (docking_sim's own loader checks every key); Debian's stereo_image_proc's parameters; the image_transport
# plugin's settings per camera topic (their meaning: src/docking_image_transport/README.md).
DATA_FILES = {"robot.yaml", "target.yaml", "target_tagged.yaml", "target_tagged_inset.yaml", "sim.yaml",
              "stereo_image_proc.yaml", "image_transport.yaml"}


class SettingsConsistency(unittest.TestCase):
    def test_declarations_files_and_tables_agree(self):
        declarations = find_declarations(WORKSPACE)
        self.assertTrue(declarations, "no settings declaration found")
        found = []
        for declaration in declarations:
            found += consistency.problems(declaration, WORKSPACE)
        print("checked %d declarations, %d settings" % (len(declarations),
                                                          sum(len(d.settings) for d in declarations)))
        self.assertFalse(found, "\n" + "\n".join(found))

    def test_every_node_configuration_is_declared(self):
        declarations = find_declarations(WORKSPACE)
        claimed = {pathlib.Path(c).name for d in declarations for c in d.config}
        claimed |= {pathlib.Path(d.defaults_from).name for d in declarations if d.defaults_from}
        files = {p.name for p in (WORKSPACE / "config").glob("*.yaml")}
        unclaimed = sorted(files - claimed - DATA_FILES)
        self.assertFalse(unclaimed, "config files no declaration claims: %s" % unclaimed)


if __name__ == "__main__":
    import rostest
    rostest.rosrun("docking_settings", "settings_consistency", SettingsConsistency)
