#!/usr/bin/env python3
"""Writes DIR/provenance.json beside a measurement's results: the command that produced them, the UTC date
and the commit measured (with "+local" when src/, config/ or launch/ had uncommitted changes). The report
(scripts/report/make_report.py) names them in each row of docs/PERFORMANCE.md.

    provenance.py DIR COMMAND...
"""
import datetime
import json
import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]


def current_commit():
    def git(*args):
        return subprocess.run(["git", "-C", str(ROOT), *args], capture_output=True, text=True).stdout.strip()
    commit = git("rev-parse", "--short=7", "HEAD") or "unknown"
    return commit + ("+local" if git("status", "--porcelain", "--", "src", "config", "launch") else "")


def provenance(command):
    return {"command": command, "commit": current_commit(),
            "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")}


def main():
    if len(sys.argv) < 3:
        raise SystemExit(__doc__)
    folder = pathlib.Path(sys.argv[1])
    folder.mkdir(parents=True, exist_ok=True)
    record = provenance(" ".join(sys.argv[2:]).strip())
    (folder / "provenance.json").write_text(json.dumps(record, indent=2) + "\n")
    print("provenance: %s at %s (%s) -> %s" % (record["command"], record["commit"], record["date"],
                                                folder / "provenance.json"))


if __name__ == "__main__":
    main()
