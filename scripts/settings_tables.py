#!/usr/bin/env python3
"""Writes (or checks) the settings table of every declaration (src/*/settings/*.yaml) into the README it
names, between <!-- settings:NODE --> and <!-- /settings:NODE -->.
    scripts/settings_tables.py --write      # after changing a declaration or a shipped YAML
    scripts/settings_tables.py --check      # exit 1 when a table is not current (make test checks it too)"""
import argparse
import pathlib
import sys

WORKSPACE = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(WORKSPACE / "src" / "docking_settings" / "src"))
from docking_settings import tables  # noqa: E402
from docking_settings.declarations import find_declarations  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    mode = parser.add_mutually_exclusive_group(required=True)
    mode.add_argument("--write", action="store_true")
    mode.add_argument("--check", action="store_true")
    args = parser.parse_args()
    stale = 0
    for declaration in find_declarations(WORKSPACE):
        if not declaration.readme:
            continue
        if args.write:
            tables.write(declaration, WORKSPACE)
            print("settings_tables: %s -> %s" % (declaration.path.relative_to(WORKSPACE), declaration.readme))
        elif tables.current_block(declaration, WORKSPACE) != tables.table(declaration, WORKSPACE):
            stale += 1
            print("settings_tables: %s: the table of %s is not current" % (declaration.readme, declaration.node))
    sys.exit(1 if stale else 0)


if __name__ == "__main__":
    main()
