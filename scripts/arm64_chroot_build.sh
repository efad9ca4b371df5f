#!/usr/bin/env bash
# Builds this branch in a Debian 12 (bookworm) arm64 chroot under qemu-user-static and runs its
# gtests (and, with ROSTESTS=..., rostests), to prove the workspace builds and passes on arm64
# (docs/ARM64.md). Idempotent: an existing chroot, its packages, clone and build folder are reused.
#
#   sudo scripts/arm64_chroot_build.sh            # as root, on an x86-64 Debian 12 host
#
# Environment: ARM64_ROOT (default /work/arm64-root: keep it outside any repository), JOBS (2),
# FRESH=1 (delete the chroot's clone and build first; needed when switching CROSS), ROSTESTS (""
# none, default; "all"; or package names, e.g. "omni_base docking_planner"), MIRROR (default
# http://deb.debian.org/debian), CROSS=1 (compile with Debian's x86-64 cross g++-12 for arm64,
# unpacked in the chroot: the same GCC 12.2 and the same arm64 libraries, but the compiler runs at
# native speed; cmake, make, the code generators and the tests still run emulated).
set -euo pipefail

ROOT="${ARM64_ROOT:-/work/arm64-root}"
JOBS="${JOBS:-2}"
MIRROR="${MIRROR:-http://deb.debian.org/debian}"
ROSTESTS="${ROSTESTS:-}"
REPO="$(cd "$(dirname "$0")/.." && git rev-parse --show-toplevel)"
BRANCH="$(git -C "$REPO" rev-parse --abbrev-ref HEAD)"
WS=/root/ws                       # the clone, as seen inside the chroot
LOG="$ROOT/root/arm64-build.log"  # step times, appended per run
# Packages of scripts/deb-packages.txt not wanted inside the chroot: the tools that build the
# chroot itself (they exist for arm64, but an arm64 robot needs none of them).
EXCLUDE="qemu-user-static debootstrap binfmt-support"
# catkin's gtest targets, per package (run_tests_<pkg>_gtest); rostests likewise.
PACKAGES="omni_base docking_perception docking_planner docking_sim"

[ "$(id -u)" -eq 0 ] || { echo "arm64_chroot_build: run as root (debootstrap, chroot, mounts)" >&2; exit 1; }
case "$ROOT" in "$REPO"|"$REPO"/*) echo "arm64_chroot_build: ARM64_ROOT must be outside the repository" >&2; exit 1;; esac

step_start=0
step() {  # step NAME: ends the previous step (logging its wall time), starts the next
  local now; now=$(date +%s)
  if [ -n "${step_name:-}" ] && [ -d "$ROOT/root" ]; then
    echo "$(date -Is) step '$step_name': $((now - step_start)) s" | tee -a "$LOG"
  fi
  step_name="$1"
  step_start=$now
  [ -z "$1" ] || echo "== $1"
}

in_chroot() {  # runs a bash command inside the chroot with a clean environment, at lowest priority
  nice -n 19 chroot "$ROOT" /usr/bin/env -i HOME=/root LANG=C.UTF-8 TERM=dumb \
    PATH=/usr/sbin:/usr/bin:/sbin:/bin DEBIAN_FRONTEND=noninteractive /bin/bash -c "$1"
}

# --- host tools and the aarch64 binfmt handler -------------------------------------------------
step "host tools"
need=()
for pkg in qemu-user-static debootstrap binfmt-support; do
  dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed" || need+=("$pkg")
done
if [ ${#need[@]} -gt 0 ]; then
  apt-get update && DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends "${need[@]}"
fi
# In a container binfmt_misc may exist but be unmounted; mounting it is allowed when root there.
[ -e /proc/sys/fs/binfmt_misc/register ] || mount -t binfmt_misc binfmt_misc /proc/sys/fs/binfmt_misc
update-binfmts --enable qemu-aarch64 2>/dev/null || true
# Flag F (the interpreter opened once, at registration): the chroot needs no copy of qemu.
if ! grep -q '^enabled' /proc/sys/fs/binfmt_misc/qemu-aarch64 2>/dev/null ||
   ! grep -q '^flags:.*F' /proc/sys/fs/binfmt_misc/qemu-aarch64; then
  echo "arm64_chroot_build: no usable qemu-aarch64 binfmt handler (see docs/ARM64.md)" >&2
  exit 1
fi

# --- the chroot --------------------------------------------------------------------------------
step "debootstrap"
if [ ! -e "$ROOT/.debootstrap-done" ]; then
  if [ -e "$ROOT/debootstrap" ]; then
    echo "arm64_chroot_build: $ROOT holds an unfinished debootstrap: remove it and rerun" >&2
    exit 1
  fi
  nice -n 19 debootstrap --arch=arm64 --variant=minbase bookworm "$ROOT" "$MIRROR"
  touch "$ROOT/.debootstrap-done"
fi
[ "$(in_chroot 'dpkg --print-architecture')" = arm64 ] || { echo "chroot is not arm64" >&2; exit 1; }

mounted=()
cleanup() {
  local m
  for ((i = ${#mounted[@]} - 1; i >= 0; i--)); do
    m="${mounted[$i]}"
    umount "$m" 2>/dev/null || umount -l "$m" 2>/dev/null || true
  done
}
trap cleanup EXIT
for fs in proc sys dev dev/pts; do
  if ! mountpoint -q "$ROOT/$fs"; then
    case "$fs" in
      proc) mount -t proc proc "$ROOT/proc" ;;
      sys) mount -t sysfs sys "$ROOT/sys" ;;
      *) mount --bind "/$fs" "$ROOT/$fs" ;;
    esac
    mounted+=("$ROOT/$fs")
  fi
done
cp -L /etc/resolv.conf "$ROOT/etc/resolv.conf"
cat > "$ROOT/etc/apt/sources.list" <<EOF
deb $MIRROR bookworm main
deb $MIRROR bookworm-updates main
deb http://deb.debian.org/debian-security bookworm-security main
EOF

step "packages"
mapfile -t wanted < <(grep -vE '^\s*(#|$)' "$REPO/scripts/deb-packages.txt")
install=()
for pkg in "${wanted[@]}" git; do  # git: the clone is made on the host, but handy inside
  [[ " $EXCLUDE " == *" $pkg "* ]] && continue
  install+=("$pkg")
done
missing=$(in_chroot "for p in ${install[*]}; do dpkg-query -W -f='\${Status}' \$p 2>/dev/null |
  grep -q 'install ok installed' || echo \$p; done")
# An interrupted earlier run may have left packages unpacked but not configured.
in_chroot "dpkg --configure -a"
if [ -n "$missing" ]; then
  echo "installing in the chroot: $(echo $missing | wc -w) packages"
  in_chroot "apt-get update && apt-get install -y --no-install-recommends $(echo $missing)"
fi
COMPILERS=""
if [ "${CROSS:-0}" = 1 ]; then
  # Debian's x86-64 cross compiler for arm64, unpacked into /opt/xgcc of the chroot (installing it
  # there would clash with the native arm64 gcc over /usr/bin/aarch64-linux-gnu-gcc-12). It runs
  # natively inside the chroot with the amd64 libraries it needs (multiarch), and finds the
  # chroot's arm64 headers and libraries in /usr/include/aarch64-linux-gnu and /usr/lib/aarch64-linux-gnu.
  XGCC=/opt/xgcc/usr/bin/aarch64-linux-gnu
  if [ ! -x "$ROOT$XGCC-g++-12" ]; then
    in_chroot "dpkg --add-architecture amd64 && apt-get update && apt-get install -y --no-install-recommends \
      libc6:amd64 libgcc-s1:amd64 libstdc++6:amd64 libgmp10:amd64 libisl23:amd64 libmpc3:amd64 \
      libmpfr6:amd64 libzstd1:amd64 zlib1g:amd64 libjansson4:amd64 libbinutils:amd64"
    mkdir -p "$ROOT/opt/xgcc-debs" "$ROOT/opt/xgcc"
    (cd "$ROOT/opt/xgcc-debs" && apt-get download cpp-12-aarch64-linux-gnu gcc-12-aarch64-linux-gnu \
      g++-12-aarch64-linux-gnu binutils-aarch64-linux-gnu libgcc-12-dev-arm64-cross \
      libstdc++-12-dev-arm64-cross libstdc++6-arm64-cross libgcc-s1-arm64-cross)
    for deb in "$ROOT"/opt/xgcc-debs/*.deb; do dpkg-deb -x "$deb" "$ROOT/opt/xgcc"; done
    # The cross binutils' own x86-64 libraries, where the amd64 loader looks by default.
    cp -an "$ROOT/opt/xgcc/usr/lib/x86_64-linux-gnu/." "$ROOT/usr/lib/x86_64-linux-gnu/"
  fi
  COMPILERS="-DCMAKE_C_COMPILER=$XGCC-gcc-12 -DCMAKE_CXX_COMPILER=$XGCC-g++-12"
fi

# --- the workspace -----------------------------------------------------------------------------
step "clone"
if [ "${FRESH:-0}" = 1 ]; then rm -rf "$ROOT$WS"; fi
if [ -d "$ROOT$WS/.git" ]; then
  git -C "$ROOT$WS" fetch -q origin "$BRANCH"
  git -C "$ROOT$WS" checkout -q -B "$BRANCH" FETCH_HEAD
else
  git clone -q --branch "$BRANCH" "$REPO" "$ROOT$WS"
fi
echo "commit: $(git -C "$ROOT$WS" log -1 --format="%h %s"), compiler: $([ "${CROSS:-0}" = 1 ] && echo "x86-64 cross g++" || echo "arm64 g++ under qemu")" | tee -a "$LOG"

# The Makefile's flags (its `build` target would also run install-deps.sh, whose list includes the
# excluded host tools: hence catkin_make directly).
CATKIN="catkin_make -DCMAKE_BUILD_TYPE=Release -DCATKIN_WHITELIST_PACKAGES= -DPYTHON_EXECUTABLE=/usr/bin/python3 $COMPILERS"
step "build"
in_chroot "cd $WS && mkdir -p devel/lib/python3/dist-packages && $CATKIN -j$JOBS > build.log 2>&1" ||
  { tail -40 "$ROOT$WS/build.log"; exit 1; }

step "build tests"
in_chroot "cd $WS && source devel/setup.bash && $CATKIN -j$JOBS tests > build_tests.log 2>&1" ||
  { tail -40 "$ROOT$WS/build_tests.log"; exit 1; }

step "gtests"
rm -rf "$ROOT$WS/build/test_results"
# The portability guard too, as `make test` runs it (counted in the same summary).
in_chroot "cd $WS && python3 scripts/check_portable.py --self-test \
  --junit build/test_results/portability/check_portable.xml" || true
targets=""
for pkg in $PACKAGES; do targets+=" run_tests_${pkg}_gtest"; done
in_chroot "cd $WS && source devel/setup.bash && export ROS_HOME=$WS/build/ros_home &&
  $CATKIN -j1 $targets > run_gtests.log 2>&1" || true
echo "gtests: $(/usr/bin/python3 "$REPO/scripts/test_summary.py" "$ROOT$WS/build/test_results" | tail -1)" | tee -a "$LOG"

if [ -n "$ROSTESTS" ]; then
  step "rostests"
  [ "$ROSTESTS" = all ] && ROSTESTS="$PACKAGES"
  targets=""
  for pkg in $ROSTESTS; do targets+=" run_tests_${pkg}_rostest"; done
  in_chroot "cd $WS && source devel/setup.bash && export ROS_HOME=$WS/build/ros_home &&
    $CATKIN -j1 $targets > run_rostests.log 2>&1" || true
  echo "gtests + rostests ($ROSTESTS): $(/usr/bin/python3 "$REPO/scripts/test_summary.py" \
    "$ROOT$WS/build/test_results" | tail -1)" | tee -a "$LOG"
fi
step ""
/usr/bin/python3 "$REPO/scripts/test_summary.py" "$ROOT$WS/build/test_results"
