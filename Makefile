# The workspace's commands. `make demo` and `make test` are the two a user needs; both install what is
# missing and build first. catkin and rostest must run on Debian's python (/usr/bin/python3, which has
# catkin_pkg), not on a pyenv python that may come first in PATH.
SHELL := /bin/bash
export PATH := /usr/bin:/bin:/usr/sbin:/sbin:$(PATH)
export ROS_HOME := $(CURDIR)/build/ros_home
export ROSCONSOLE_FORMAT := [$${severity}] [$${time}] [$${node}]: $${message}
export PYTHONDONTWRITEBYTECODE := 1
# Loopback only (README "Network"): with the bind guard that devel/setup.bash preloads, every server socket
# of every ROS process is on 127.0.0.1. On a robot's private network set ROS_IP to the robot's address.
export ROS_IP := 127.0.0.1
unexport ROS_HOSTNAME

BUILD_TYPE ?= Release
# Two compile jobs more than cores: on a machine busy with other work a build gets its share per process,
# so with two CPU hogs beside it -j4 gets ~2/3 of two cores where -j2 gets 1/2 (an idle machine loses nothing).
JOBS ?= $(shell echo $$(( $$(nproc) + 2 )))
CATKIN_MAKE_SERIAL := catkin_make -DCMAKE_BUILD_TYPE=$(BUILD_TYPE) -DCATKIN_WHITELIST_PACKAGES="" -DPYTHON_EXECUTABLE=/usr/bin/python3
CATKIN_MAKE := $(CATKIN_MAKE_SERIAL) -j$(JOBS)
SETUP := source $(CURDIR)/devel/setup.bash

.PHONY: deps build test demo campaign bench eval report tune ablate lint clean fuzz-serial fuzz-messages firmware flash-firmware

deps:
	@scripts/install-deps.sh

# devel/lib/python3/dist-packages must exist when cmake first configures: catkin writes the
# environment that `run_tests` uses (build/catkin_generated/setup_cached.sh) then, with PYTHONPATH
# only if that folder exists. Without it, on a fresh clone, python rostests cannot import docking_msgs.
build: deps
	@mkdir -p devel/lib/python3/dist-packages
	$(CATKIN_MAKE)
	@touch $(BUILT)

# make tune builds only when a file under src/ is newer than the last build (a catkin_make that finds
# nothing to do still takes a minute on this machine).
BUILT := devel/.built
$(BUILT): $(shell find src -type f -not -name '*.pyc' 2>/dev/null) scripts/deb-packages.txt
	@$(MAKE) --no-print-directory build

# Builds and runs every gtest and rostest, then prints one line `N passed, N failed`.
test: build
	@rm -rf build/test_results
	@scripts/check_portable.sh --self-test --junit build/test_results/portability/check_portable.xml || true  # counted below
	@$(SETUP) && $(CATKIN_MAKE) tests > build/build_tests.log 2>&1 || { tail -40 build/build_tests.log; echo "0 passed, 1 failed"; exit 1; }
	@# One test at a time: the simulator tests must not compete with each other for the two cores.
	@$(SETUP) && $(CATKIN_MAKE_SERIAL) -j1 run_tests 2>&1 | tee build/run_tests.log | grep -E '^\[ +(OK|FAILED) +\]|^\[[a-z_]+\.rosunit-.*\]\[|^ \* RESULT' || true
	@/usr/bin/python3 scripts/test_summary.py build/test_results

demo: build
	@$(SETUP) && scripts/run_demo.sh

campaign: build
	@$(SETUP) && scripts/run_campaign.sh

bench: build
	@$(SETUP) && scripts/run_bench.sh

eval: build
	@$(SETUP) && scripts/run_eval.sh

# docs/PERFORMANCE.md from what make demo, campaign, eval, bench and ablate wrote under results/: their figures are
# merged into docs/performance-figures.json (a row not measured again keeps its own date and commit), then rendered
# (scripts/report/make_report.py). Needs no build.
report:
	@/usr/bin/python3 scripts/report/make_report.py

# Each rule switched off in turn, measured on held-out data (scripts/ablate/ablate.py): ABLATE_ARGS, e.g.
#   make ablate ABLATE_ARGS="--rules arbiter_consistency --suites replay"
# The held-out runs are recorded once by scripts/ablate/record_heldout.py (about 2 min each).
ablate: build
	@$(SETUP) && scripts/ablate/ablate.py $(ABLATE_ARGS)

# Replays BAG losslessly with two configurations or a sweep and compares them per source (docs/TUNING.md):
#   make tune BAG=/tmp/b.bag SET="disparity_detector.yaml:median_kernel_px=5"     (A = config/, B = A + SET)
#   make tune BAG=/tmp/b.bag SWEEP="mono_pose_visible.yaml:fast_threshold=5,10,20" [SET=...] [OUT=dir]
#   make tune BAG=/tmp/both.bag IMAGES=raw,compressed     (what JPEG recording costs: a bag of record.launch images:=both)
# SET: edits separated by spaces (no spaces inside a value: [1,2]). Output: OUT (default results/tune/<date-time>/).
# PORT: the ROS master's port for the replays (default: a free one per replay). Builds only if src/ changed.
BAG ?=
SET ?=
SWEEP ?=
IMAGES ?=
OUT ?=
PORT ?=
tune: $(BUILT)
	@test -n "$(BAG)" || { echo "make tune: BAG=file.bag is required (docs/TUNING.md)"; exit 2; }
	@$(SETUP) && scripts/tune/tune_replay.py --bag "$(BAG)" $(foreach edit,$(SET),--set "$(edit)") \
		$(if $(SWEEP),--sweep "$(SWEEP)") $(if $(IMAGES),--images "$(IMAGES)") $(if $(OUT),--out "$(OUT)") \
		$(if $(PORT),--port "$(PORT)")

# Seeded fuzz of omni_base's serial stream decoder (src/omni_base/README.md, "Serial fuzz harness"):
# 1 M random streams checked for its invariants, 2 M corrupted zero-duty frames that must never decode
# to a non-zero duty. About 40 s; exits non-zero on any violation. Builds only omni_base (and the
# messages it needs), on one core: the program is ROS-free.
FUZZ_INPUTS ?= 1000000
FUZZ_CORRUPTIONS ?= 2000000
FUZZ_SEED ?= 12
# Randomized message campaign against the running closed loop (docs/design/reliability.md): FUZZ_PER_TOPIC
# malformed messages on each of 15 input topics, then a docking (2000 took 2 min 45 s). `make test` runs it
# with 400 per topic (every random choice of the generator occurs by message 261 of its topic).
FUZZ_PER_TOPIC ?= 5000
fuzz-messages: build
	@$(SETUP) && rostest docking_planner message_fuzz.test per_topic:=$(FUZZ_PER_TOPIC)

fuzz-serial: deps
	@mkdir -p devel/lib/python3/dist-packages build
	@$(CATKIN_MAKE_SERIAL) -DCATKIN_WHITELIST_PACKAGES="docking_msgs;docking_settings;omni_base" -j1 fuzz_serial_decoder > build/build_fuzz_serial.log 2>&1 || { tail -40 build/build_fuzz_serial.log; exit 1; }
	devel/lib/omni_base/fuzz_serial_decoder --inputs $(FUZZ_INPUTS) --corruptions $(FUZZ_CORRUPTIONS) --seed $(FUZZ_SEED)

# The motor board's firmware (src/motor_board_firmware/README.md): build/motor_board_firmware/firmware/motor_board.hex
# (`make build` builds it too), and flashing it: make flash-firmware PORT=/dev/ttyACM0 [UPLOAD_BAUD=57600] [PROGRAMMER=usbasp]
FIRMWARE_MAKE = $(MAKE) -C src/motor_board_firmware/firmware BUILD_DIR=$(CURDIR)/build/motor_board_firmware/firmware \
	$(if $(PORT),PORT=$(PORT)) $(if $(UPLOAD_BAUD),UPLOAD_BAUD=$(UPLOAD_BAUD)) $(if $(PROGRAMMER),PROGRAMMER=$(PROGRAMMER))
firmware: deps
	@$(FIRMWARE_MAKE)

flash-firmware: firmware
	@$(FIRMWARE_MAKE) flash

lint: deps
	@$(SETUP) && catkin_lint -W1 --strict src

clean:
	rm -rf build devel install results
