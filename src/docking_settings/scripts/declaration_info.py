#!/usr/bin/env python3
"""For the build (docking_settings_generate): a declaration's generated header and the other files it is made
from (defaults_from, imports, relative to the workspace), as one CMake list: HEADER;FILE;FILE..."""
import sys

import yaml

spec = yaml.safe_load(open(sys.argv[1]))
files = ([spec["defaults_from"]] if spec.get("defaults_from") else []) + list(spec.get("imports") or [])
print(";".join([spec["cpp"]["header"]] + files))
