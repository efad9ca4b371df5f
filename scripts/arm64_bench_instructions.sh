#!/usr/bin/env bash
# Instructions per frame of the perception stages on arm64 (the stages `make bench` counts on x86-64 with
# callgrind, scripts/bench_instructions.py), on an x86-64 Debian 12 host without an arm64 machine.
#
#   scripts/arm64_bench_instructions.sh            # as root (apt-get download/update only; no package is installed)
#
# Method: Debian 12's own arm64 valgrind (3.19, callgrind) runs under qemu-aarch64-static (user mode, CPU model
# cortex-a72, the Raspberry Pi 4's: ARMv8.0 with NEON, no dot product, no LSE atomics; QEMU_CPU=cortex-a76 for a Pi 5
# class CPU) on bench_mono and bench_disparity cross-compiled for arm64 with Debian's x86-64 g++-12 cross compiler
# (GCC 12.2.0, the same as the arm64 native g++) and catkin's Release flags (-O3 -DNDEBUG, shared core libraries),
# linked against Debian 12's arm64 OpenCV 4.6, yaml-cpp, apriltag and reference BLAS/LAPACK. The stages, frames and
# divisors are bench_instructions.py's (scripts/arm64_bench_instructions.py imports them); the count is callgrind's
# count of guest (arm64) instructions between marks that an LD_PRELOAD shim (scripts/arm64_bench_shims/) places
# around the library calls the bench programs make (MonoPoseEstimator::process; cvtColor + rectifyWindow, detect,
# confirmByAppearance, and the span between them that is computeDisparity), not --toggle-collect: arm64 callgrind's
# call-stack tracking, on which --toggle-collect and inclusive costs rest, is not reliable (see the .py). The same
# programs and shims are built for x86-64 from the same clone and counted with the host's callgrind, so both columns
# come from one commit; on x86 the shim counts equal bench_instructions.py's --toggle-collect counts.
# Checks (2026-12-06): a test stage (OpenCV blur, Canny, resize, StereoBM, corners; 45 M instructions) counted by
# this arm64 valgrind under qemu and by qemu's own one-instruction-per-block exec trace (qemu -singlestep -d
# exec,nochain, counted from the function's entry to its return address): 44,965,285 against 44,989,941 (0.05 %);
# the same on x86: host callgrind 56,413,907, qemu-x86_64 -cpu max trace 56,413,320.
#
# No chroot, no ROS and no package scripts under emulation: a private apt state (APT_CONFIG, arm64 only) downloads
# the needed arm64 packages and their dependencies (~370 .deb, 200 MB) and unpacks them into a sysroot with
# dpkg-deb -x; the cross compiler's .debs are unpacked beside it (as scripts/arm64_chroot_build.sh CROSS=1 does).
# The far stage's input is the simulator's raw pair of eval_far_3m_on at t = 1 s, rendered by the workspace's x86
# devel/lib/docking_sim/sim_render (so `make build` must have run; without it the far stage is skipped), the
# same pixels for both architectures.
#
# Time on this 2-core machine, everything under nice 19 beside other work (load 5-7): sysroot download and unpack
# 40 s, cross compiler 5 s, build arm64 ~3 min (JOBS=1; ~1.5 min with 2), x86 ~2.5 min, x86 counts ~3.5 min (one
# job), arm64 counts ~35-45 min with two jobs at once (wall, one stage a run: mono_ir 3 min, mono_tracking_near 4,
# mono_tracking ~8, mono_full 9, the far stage at full resolution 15, most of it bench_disparity's instrumented
# setup). STAGES=mono_ir DISPARITY= SKIP_X86=1 on a fresh WORK: 7 min in all.
#
# Environment: WORK (default /work/arm64-bench: outside the repository), STAGES (default
# mono_full,mono_tracking,mono_tracking_near,mono_ir), DISPARITY (default full; also tracking,window), JOBS (2),
# QEMU_CPU (cortex-a72), MIRROR (http://deb.debian.org/debian), SKIP_X86=1 (arm64 only).
# Output: $WORK/results/{x86,arm64}.json ({"stages": {NAME: {"instructions_per_frame_M", "frames"}}}) and a table.
set -euo pipefail
export PATH=/usr/bin:/bin:/usr/sbin:/sbin:$PATH
REPO="$(cd "$(dirname "$0")/.." && git rev-parse --show-toplevel)"
WORK="${WORK:-/work/arm64-bench}"
MIRROR="${MIRROR:-http://deb.debian.org/debian}"
STAGES="${STAGES:-mono_full,mono_tracking,mono_tracking_near,mono_ir}"
DISPARITY="${DISPARITY-full}"
JOBS="${JOBS:-2}"
export QEMU_CPU="${QEMU_CPU:-cortex-a72}"
case "$WORK" in "$REPO"|"$REPO"/*) echo "arm64_bench_instructions: WORK must be outside the repository" >&2; exit 1;; esac
SYSROOT=$WORK/sysroot XGCC=$WORK/xgcc SRC=$WORK/src
LOW="nice -n 19 ionice -c3"
mkdir -p "$WORK/results"
LOG=$WORK/results/steps.log
step_start=$(date +%s) step_name=""
step() {  # step NAME: logs the previous step's wall time
  local now; now=$(date +%s)
  [ -z "$step_name" ] || echo "$(date -Is) $step_name: $((now - step_start)) s" | tee -a "$LOG"
  step_name=$1 step_start=$now
  [ -z "$1" ] || echo "== $1"
}
for tool in qemu-aarch64-static valgrind callgrind_annotate dpkg-deb apt-get g++; do
  command -v $tool >/dev/null || { echo "arm64_bench_instructions: $tool missing (qemu-user-static, valgrind, g++)" >&2; exit 1; }
done

# --- arm64 sysroot: Debian 12 arm64 packages unpacked, nothing configured -----------------------------------------
step "arm64 sysroot"
PACKAGES="libopencv-core-dev libopencv-imgproc-dev libopencv-imgcodecs-dev libopencv-calib3d-dev
  libopencv-features2d-dev libopencv-flann-dev libopencv-video-dev libopencv-videoio-dev libyaml-cpp-dev
  libapriltag-dev libeigen3-dev libc6-dev libstdc++-12-dev valgrind"
if [ ! -e "$SYSROOT/.done" ]; then
  A=$WORK/apt
  mkdir -p $A/state/lists/partial $A/cache/archives/partial $A/etc/sources.list.d $A/etc/apt.conf.d $A/etc/preferences.d
  touch $A/state/status
  key="signed-by=/usr/share/keyrings/debian-archive-keyring.gpg"
  cat > $A/etc/sources.list <<EOF
deb [arch=arm64 $key] $MIRROR bookworm main
deb [arch=arm64 $key] $MIRROR bookworm-updates main
deb [arch=arm64 $key] http://deb.debian.org/debian-security bookworm-security main
EOF
  cat > $A/apt.conf <<EOF
APT::Architecture "arm64";
APT::Architectures { "arm64"; };
Dir::State "$A/state";
Dir::State::status "$A/state/status";
Dir::Cache "$A/cache";
Dir::Etc::SourceList "$A/etc/sources.list";
Dir::Etc::SourceParts "$A/etc/sources.list.d";
Dir::Etc::Parts "$A/etc/apt.conf.d";
Dir::Etc::Preferences "$A/etc/preferences";
Dir::Etc::PreferencesParts "$A/etc/preferences.d";
APT::Install-Recommends "false";
EOF
  # An empty status file: apt resolves the whole dependency closure (libc6 included) and only downloads it.
  APT_CONFIG=$A/apt.conf $LOW apt-get -q update >/dev/null
  APT_CONFIG=$A/apt.conf $LOW apt-get -q install -y -d $PACKAGES >/dev/null
  rm -rf "$SYSROOT" && mkdir -p "$SYSROOT"
  for deb in $A/cache/archives/*.deb; do $LOW dpkg-deb -x "$deb" "$SYSROOT"; done
  # Merged /usr as a debootstrapped system has it, and absolute links made relative to the sysroot.
  for d in bin sbin lib; do
    if [ -d "$SYSROOT/$d" ] && [ ! -L "$SYSROOT/$d" ]; then
      cp -a "$SYSROOT/$d/." "$SYSROOT/usr/$d/" && rm -rf "${SYSROOT:?}/$d" && ln -s usr/$d "$SYSROOT/$d"
    fi
  done
  (cd "$SYSROOT" && find . -type l | while read -r l; do
    t=$(readlink "$l"); case "$t" in /*) ln -sfn "$(realpath -m --relative-to="$(dirname "$l")" ".$t")" "$l";; esac
  done)
  # The alternatives that the BLAS and LAPACK postinst scripts would set (the reference ones, as on the x86 host).
  L=$SYSROOT/usr/lib/aarch64-linux-gnu
  ln -sfn blas/libblas.so.3 $L/libblas.so.3; ln -sfn lapack/liblapack.so.3 $L/liblapack.so.3
  touch "$SYSROOT/.done"
fi

step "cross compiler"
if [ ! -x "$XGCC/usr/bin/aarch64-linux-gnu-g++-12" ]; then
  mkdir -p "$WORK/xgcc-debs" "$XGCC"
  (cd "$WORK/xgcc-debs" && $LOW apt-get -q download cpp-12-aarch64-linux-gnu gcc-12-aarch64-linux-gnu \
    g++-12-aarch64-linux-gnu binutils-aarch64-linux-gnu libgcc-12-dev-arm64-cross libstdc++-12-dev-arm64-cross \
    libstdc++6-arm64-cross libgcc-s1-arm64-cross >/dev/null)
  for deb in "$WORK"/xgcc-debs/*.deb; do dpkg-deb -x "$deb" "$XGCC"; done
fi

step "clone"
if [ -d "$SRC/.git" ]; then
  git -C "$SRC" fetch -q "$REPO" HEAD && git -C "$SRC" checkout -q --detach FETCH_HEAD
else
  git clone -q "$REPO" "$SRC"
fi
echo "commit: $(git -C "$SRC" log -1 --format='%h %s' | cut -c1-100)" | tee -a "$LOG"

# --- the bench programs, catkin's flags (build/docking_perception/CMakeFiles/*/flags.make), without catkin -------------
build() {  # build ARCH OUT
  local arch=$1 out=$2 cxx ar inc libdir P=$SRC/src/docking_perception
  if [ "$arch" = arm64 ]; then
    cxx="$XGCC/usr/bin/aarch64-linux-gnu-g++-12 --sysroot=$SYSROOT" ar=$XGCC/usr/bin/aarch64-linux-gnu-ar
    inc="-isystem $SYSROOT/usr/include/opencv4 -isystem $SYSROOT/usr/include/eigen3"
    libdir=$SYSROOT/usr/lib/aarch64-linux-gnu
  else
    cxx=g++ ar=ar inc="-isystem /usr/include/opencv4 -isystem /usr/include/eigen3" libdir=/usr/lib/x86_64-linux-gnu
  fi
  local flags="-O3 -DNDEBUG -Wall -Wextra -std=gnu++17 -I$P/include -I$out/include -I$SRC/src/docking_settings/include $inc"
  # The package's settings structs, generated from their declarations as docking_settings_generate() does.
  local declaration
  for declaration in $P/settings/*.yaml; do
    python3 $SRC/src/docking_settings/scripts/generate_settings.py "$declaration" "$out/include/$(python3 -c \
      "import sys, yaml; print(yaml.safe_load(open(sys.argv[1]))['cpp']['header'])" "$declaration")" "$declaration"
  done
  local cv="-lopencv_videoio -lopencv_imgcodecs -lopencv_video -lopencv_calib3d -lopencv_features2d -lopencv_flann
    -lopencv_imgproc -lopencv_core -lyaml-cpp -lapriltag"
  # The sources of docking_perception_mono_core and _disparity_core (cmake/mono_pose.cmake, cmake/disparity.cmake).
  local mono disp pids=() f
  mono=$(sed -n '/^set(MONO_CORE_SOURCES/,/)/p' $P/cmake/mono_pose.cmake | grep -o 'src/[^ )]*\.cpp')
  disp=$(sed -n '/^add_library(docking_perception_disparity_core/,/)/p' $P/cmake/disparity.cmake | grep -o 'src/[^ )]*\.cpp')
  mkdir -p "$out/obj"
  compile() {  # compile SRC OBJ EXTRA...: JOBS at once
    local s=$1 o=$2; shift 2
    $LOW $cxx $flags "$@" -c "$s" -o "$o" &
    pids+=($!)
    if [ ${#pids[@]} -ge "$JOBS" ]; then wait "${pids[0]}"; pids=("${pids[@]:1}"); fi
  }
  for f in $mono; do compile $P/$f $out/obj/mono_$(basename $f .cpp).o -fPIC -Ddocking_perception_mono_core_EXPORTS; done
  # The settings' range checks (docking_settings_core's), linked into the mono core as catkin links it.
  compile $SRC/src/docking_settings/src/setting_info.cpp $out/obj/mono_setting_info.o -fPIC
  for f in $disp; do compile $P/$f $out/obj/disp_$(basename $f .cpp).o -fPIC; done
  compile $P/test/mono/synthetic_scene.cpp $out/obj/synthetic_scene.o
  compile $P/test/disparity/synthetic_stereo.cpp $out/obj/synthetic_stereo.o
  compile $P/test/mono/bench_mono.cpp $out/obj/bench_mono.o -I$P/test/mono
  compile $P/src/disparity/bench_disparity.cpp $out/obj/bench_disparity.o -I$P/test/disparity \
    -DDISPARITY_CONFIG_DIR=\"$SRC/config\"
  for f in "${pids[@]}"; do wait "$f"; done
  local l="-L$libdir -Wl,-rpath-link,$libdir"
  $cxx -shared -fPIC -O3 -o $out/libdocking_perception_mono_core.so $out/obj/mono_*.o $l $cv
  $cxx -shared -fPIC -O3 -o $out/libdocking_perception_disparity_core.so $out/obj/disp_*.o $l $cv
  rm -f $out/*.a
  $ar qc $out/libmono_synthetic.a $out/obj/synthetic_scene.o
  $ar qc $out/libdisparity_synthetic.a $out/obj/synthetic_stereo.o
  $cxx -O3 -o $out/bench_mono $out/obj/bench_mono.o -Wl,-rpath,$out $out/libmono_synthetic.a \
    $out/libdocking_perception_mono_core.so $l $cv
  $cxx -O3 -o $out/bench_disparity $out/obj/bench_disparity.o -Wl,-rpath,$out \
    $out/libdocking_perception_disparity_core.so $out/libdisparity_synthetic.a $out/libdocking_perception_mono_core.so $l $cv
  # The shims that mark the stages for callgrind (arm64_bench_instructions.py; valgrind/callgrind.h from the
  # valgrind package: the sysroot's for arm64, the host's for x86).
  for f in mono_shim far_shim; do
    $cxx -O2 -std=gnu++17 -shared -fPIC -I$P/include -I$out/include -I$SRC/src/docking_settings/include $inc \
      -o $out/$f.so $REPO/scripts/arm64_bench_shims/$f.cpp -ldl
  done
}
step "build arm64"
(export LD_LIBRARY_PATH=$XGCC/usr/lib/x86_64-linux-gnu  # the cross binutils' own libraries
 build arm64 $WORK/out-arm64)
if [ "${SKIP_X86:-0}" != 1 ]; then
  step "build x86"
  build x86 $WORK/out-x86
fi

step "far pair"
FAR=()
if [ -n "$DISPARITY" ]; then
  if [ -x "$REPO/devel/lib/docking_sim/sim_render" ]; then
    mkdir -p $WORK/frames
    $LOW "$REPO/devel/lib/docking_sim/sim_render" --config $SRC/config --scenario eval_far_3m_on --time 1.0 \
      --out $WORK/frames/far3m >/dev/null
    FAR=(--far-left $WORK/frames/far3m_stereo_left.png --far-right $WORK/frames/far3m_stereo_right.png)
  else
    echo "no devel/lib/docking_sim/sim_render (make build): the far stage is skipped" | tee -a "$LOG"
    DISPARITY=""
  fi
fi

# The arm64 valgrind under qemu: Debian's launcher logic by hand (the tool binary with --tool, its library folder,
# the launcher's path for the client), the guest's LD_PRELOAD through qemu's QEMU_SET_ENV.
cat > $WORK/valgrind-arm64 <<EOF
#!/usr/bin/env bash
export QEMU_LD_PREFIX=$SYSROOT QEMU_CPU=$QEMU_CPU VALGRIND_LIB=$SYSROOT/usr/libexec/valgrind VALGRIND_LAUNCHER=/usr/bin/valgrind
if [ -n "\${GUEST_LD_PRELOAD:-}" ]; then export QEMU_SET_ENV="LD_PRELOAD=\$GUEST_LD_PRELOAD"; fi
exec $LOW qemu-aarch64-static "\$VALGRIND_LIB/callgrind-arm64-linux" "\$@"
EOF
chmod +x $WORK/valgrind-arm64

COUNT="/usr/bin/python3 $REPO/scripts/arm64_bench_instructions.py"
if [ "${SKIP_X86:-0}" != 1 ]; then
  step "x86 counts"
  $COUNT $WORK/results/x86.json --bin $WORK/out-x86 --config $SRC/config --valgrind "$LOW valgrind" \
    --mono-shim $WORK/out-x86/mono_shim.so --far-shim $WORK/out-x86/far_shim.so --stages "$STAGES" --disparity "$DISPARITY" "${FAR[@]}" --jobs "$JOBS"
fi
step "arm64 counts"
compare=(); [ -e $WORK/results/x86.json ] && compare=(--compare $WORK/results/x86.json)
$COUNT $WORK/results/arm64.json --bin $WORK/out-arm64 --config $SRC/config --valgrind $WORK/valgrind-arm64 \
  --mono-shim $WORK/out-arm64/mono_shim.so --far-shim $WORK/out-arm64/far_shim.so --shim-env GUEST_LD_PRELOAD --stages "$STAGES" --disparity "$DISPARITY" \
  "${FAR[@]}" --jobs "$JOBS" "${compare[@]}"
step ""
