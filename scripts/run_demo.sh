#!/usr/bin/env bash
# Placeholder until the simulator and the closed loop exist (issues 3 and 6).
echo "make demo: not available yet: it needs the simulator (issue 3) and the closed loop (issue 6)." >&2
exit 2
