#!/usr/bin/env python3
"""performance_report.test: the generator of docs/PERFORMANCE.md (scripts/report/make_report.py) on the fixture
results beside this file (results/ is never committed), and the committed page against its committed figures."""
import json
import os
import pathlib
import shutil
import subprocess
import sys
import tempfile
import unittest

import rostest
import yaml

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parents[3]
GENERATOR = ROOT / "scripts" / "report" / "make_report.py"
FIXTURE = HERE / "fixture_results"


def generate(*args):
    done = subprocess.run([sys.executable, str(GENERATOR), *map(str, args)], stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, text=True)
    print(done.stdout, flush=True)
    return done


class PerformanceReport(unittest.TestCase):
    def setUp(self):
        self.work = pathlib.Path(tempfile.mkdtemp(prefix="performance_report_"))
        self.figures, self.page = self.work / "figures.json", self.work / "PERFORMANCE.md"

    def tearDown(self):
        shutil.rmtree(self.work, ignore_errors=True)

    def report(self, results):
        done = generate("--results", results, "--figures", self.figures, "--out", self.page)
        self.assertEqual(done.returncode, 0, done.stdout)
        return self.page.read_text()

    def test_rows_carry_the_fixture_numbers(self):
        text = self.report(FIXTURE)
        for expected in [
                "| `make demo`: default scene (4 m, port 40 deg off, target turning 3 deg/s) | 1 | DOCKED | 2.9 | 0.05 | 24.2 "
                "| 2026-12-01 `f1x7ure` | `make demo` |",
                "| campaign, seeds 1000-1003 | 4 | 75 % (docked 100 %) | 2.8 / 12.3 / 13.1 | 0.05 / 0.21 / 0.24 | 18.4 |",
                "| `eval_far_4m_on` | 4.0 | 1.00 | 12.3 (0.31 %) | 24.6 | - / - | - / - | 0 | 0.97 | 2026-12-01 `f1x7ure` "
                "| `make eval EVAL_ARGS=\"--only eval_far_4m_on\"` |",
                "| `eval_near_1m_on` | 1.0 | 1.00 | 0.6 (0.06 %) | 1.2 | 0.31 / 0.62 | 0.52 / 0.63 | 0 | 0.97 |",
                "| `eval_dark_1m` fused | 1.0 | 1.00 | 0.2 (0.02 %) |",
                "| `disparity_total` | 22.20 | 45 | 239.0 | 5 Hz notebook, 0.5 Hz Pi 3 | 2026-12-01 `f1x7ure` | `make bench` |",
                "| `make demo`, one docking | 301 | 9.5 | 15.8 | 41.2 | 8.1 / 13.9 | 1.2 / 2.6 |",
                "| `closed_loop_still_1p5m` | 30 | 0.45 | 252 | 298 | 2026-12-01 `f1x7ure` | `scripts/eval/stack_memory.py` |",
                "| `eval_near_1m_on` | 1.00 | 0 | 0.6 mm / 0.31 deg / 6.4 ms | 1.9 mm / 1.91 deg / 5.2 ms "
                "| 3.7 mm / 0.11 deg / 8.1 ms |",
                "| `eval_real_motion9px_1m` | nominal | 1.0 | 0.97 / 1.00 / 0.00 / 1.00 | 2 | 0.97 |",
                "replay fused: detection 0.931 (on 0.950), wrong 3 (on 0), CPU 1.0 ms (on 1.0) | 2026-12-01 `f1x7ure` |",
                "- results/campaign/summary.json: `make campaign CAMPAIGN_RUNS=4`, 2026-12-01 10:00 UTC, commit `f1x7ure`"]:
            self.assertIn(expected, text)
        self.assertLessEqual(text.count("\n"), 500)

    def test_every_ablation_rule_has_a_row(self):
        text = self.report(FIXTURE)
        for path in sorted((ROOT / "scripts" / "ablate" / "rules").glob("*.yaml")):
            for rule in yaml.safe_load(path.read_text()):
                line = next((l for l in text.splitlines() if l.startswith("| `%s` |" % rule["rule"])), None)
                self.assertIsNotNone(line, "no row for rule %s" % rule["rule"])
                if rule["rule"] != "arbiter_hysteresis":
                    self.assertIn('| not measured | - | `make ablate ABLATE_ARGS="--rules %s"` |' % rule["rule"], line)

    def test_a_later_result_replaces_only_what_it_measures(self):
        self.report(FIXTURE)
        later = self.work / "results"
        shutil.copytree(FIXTURE / "bench", later / "bench")
        summary = json.loads((later / "bench" / "summary.json").read_text())
        summary["stages"]["disparity_total"]["ms_median"] = 30.5
        (later / "bench" / "summary.json").write_text(json.dumps(summary))
        (later / "bench" / "provenance.json").write_text(json.dumps(
            {"command": "make bench", "commit": "1a7e500", "date": "2026-12-05 08:00 UTC"}))
        text = self.report(later)
        self.assertIn("| `disparity_total` | 30.50 | 45 | 239.0 | 5 Hz notebook, 0.5 Hz Pi 3 | 2026-12-05 `1a7e500` |", text)
        self.assertIn("| `eval_far_4m_on` | 4.0 | 1.00 | 12.3 (0.31 %) | 24.6 | - / - | - / - | 0 | 0.97 | 2026-12-01 `f1x7ure` |",
                      text)

    def test_rendering_is_repeatable(self):
        self.report(FIXTURE)
        self.assertEqual(generate("--check", "--figures", self.figures, "--out", self.page).returncode, 0)
        self.page.write_text(self.page.read_text().replace("12.3 (0.31 %)", "12.4 (0.31 %)"))
        self.assertEqual(generate("--check", "--figures", self.figures, "--out", self.page).returncode, 1)

    def test_docs_performance_is_what_its_figures_render(self):
        done = generate("--check")
        self.assertEqual(done.returncode, 0, done.stdout)
        text = (ROOT / "docs" / "PERFORMANCE.md").read_text()
        figures = json.loads((ROOT / "docs" / "performance-figures.json").read_text())
        self.assertTrue(figures["sources"], "docs/performance-figures.json names no results")
        for name, runs in figures["sources"].items():
            for measured in runs:
                self.assertIn("- %s: `%s`, %s, commit `%s`" % (name, measured["command"], measured["date"],
                                                               measured["commit"]), text)


if __name__ == "__main__":
    os.environ.setdefault("PYTHONDONTWRITEBYTECODE", "1")
    rostest.rosrun("docking_perception", "performance_report", PerformanceReport)
