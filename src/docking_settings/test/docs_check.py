#!/usr/bin/env python3
"""The docs check (scripts/docs/check_docs.py) on every doc of the workspace: what README.md, docs/ and the
package READMEs name exists (paths, links, make targets, launch args, rosrun programs), the settings tables are
current, and the docs keep their sizes. And the check itself: it must find a broken link, a missing path, an
unknown make target and an over-long README in a doc made to have them."""
import pathlib
import sys
import tempfile
import unittest

WORKSPACE = pathlib.Path(__file__).resolve().parents[3]
sys.path.insert(0, str(WORKSPACE / "scripts" / "docs"))
import check_docs  # noqa: E402


class DocsCheck(unittest.TestCase):
    def test_workspace_docs(self):
        files = check_docs.docs()
        self.assertIn(WORKSPACE / "README.md", files)
        problems = check_docs.check(files)
        print("checked %d docs" % len(files))
        self.assertFalse(problems, "\n" + "\n".join(problems))

    def test_finds_what_is_broken(self):
        with tempfile.TemporaryDirectory() as folder:
            doc = pathlib.Path(folder) / "broken.md"
            doc.write_text("See [the guide](docs/no_such_guide.md) and `config/no_such_file.yaml`.\n"
                           "Then `make no-such-target` and [a real one](README.md).\n")
            problems = check_docs.check_file(doc, check_docs.make_targets())
        self.assertEqual(3, len(problems), problems)
        self.assertIn("link to docs/no_such_guide.md: no such file", problems[0])
        self.assertIn("config/no_such_file.yaml: no such file or folder", problems[1])
        self.assertIn("make no-such-target: no such target", problems[2])

    def test_finds_a_readme_too_long(self):
        lines = check_docs.ROOT / "README.md"
        problems = check_docs.size_problems(lines.resolve(), ["x" * 201] + ["line"] * 400)
        self.assertEqual(["README.md: 401 lines, at most 400", "README.md:1: 201 characters, at most 200"], problems)


if __name__ == "__main__":
    import rostest
    rostest.rosrun("docking_settings", "docs_check", DocsCheck)
