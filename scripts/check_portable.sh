#!/usr/bin/env bash
# CI guard: x86-only constructs (intrinsics, -msse/-mavx/-march=native, inline asm) must stay inside
# x86 guards so that the workspace builds on arm64. The checking is in check_portable.py (see there);
# any python3 will do (standard library only).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
exec python3 "$here/check_portable.py" "$@"
