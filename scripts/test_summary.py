#!/usr/bin/env python3
"""Reads the JUnit XML files that `catkin_make run_tests` leaves and prints one line
`N passed, N failed` (exit 1 on any failure, on any error, or when no test ran at all).

catkin_test_results reports suites; this counts test cases, and lists each failing one by name.
A crashed gtest or rostest leaves a MISSING-RESULT file or an <error>, which counts as a failure.
Each failure is printed with the last lines of its message, so a CI log says why it failed.
"""
import pathlib
import sys
import xml.etree.ElementTree as ET


def main(results_dir):
    passed, failed, skipped = 0, [], 0
    files = sorted(pathlib.Path(results_dir).rglob("*.xml")) if pathlib.Path(results_dir).exists() else []
    for path in files:
        try:
            root = ET.parse(path).getroot()
        except ET.ParseError as err:
            failed.append(f"{path.name}: unreadable result file ({err})")
            continue
        cases = list(root.iter("testcase"))
        if not cases and root.tag in ("testsuite", "testsuites"):
            errors = int(root.get("errors", 0)) + int(root.get("failures", 0))
            if errors:
                failed.append(f"{path.name}: {errors} errors and no test cases")
            continue
        for case in cases:
            name = f"{path.parent.name}/{case.get('classname', '')}.{case.get('name', '')}"
            problem = case.find("failure")
            if problem is None:
                problem = case.find("error")
            if problem is not None:
                # Say why, briefly: CI logs show only this script's output for a failure.
                text = (problem.get("message") or "") + "\n" + (problem.text or "")
                lines = [ln for ln in text.strip().splitlines() if ln.strip()][-12:]
                failed.append(name + "".join("\n    " + ln for ln in lines))
            elif case.find("skipped") is not None:
                skipped += 1
            else:
                passed += 1
    for name in failed:
        print(f"FAILED: {name}")
    if passed == 0 and not failed:
        failed.append("no test results found")
        print(f"FAILED: no test results under {results_dir}")
    line = f"{passed} passed, {len(failed)} failed"
    if skipped:
        line += f", {skipped} skipped"
    print(line)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else "build/test_results"))
