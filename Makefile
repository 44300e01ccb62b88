# cram-plans — one-command setup, build, test, demo and benchmarks.
# Every target works on a fresh Debian bookworm machine as root.

SHELL := /bin/bash
# Debian's python3 and cmake before any pyenv shims (ROS tools, CMake modules).
export PATH := /usr/bin:/bin:/usr/sbin:/sbin:$(PATH)
export ROS_HOME ?= $(CURDIR)/.ros
export ROS_MASTER_URI ?= http://127.0.0.1:11311
export ROS_IP ?= 127.0.0.1
export CL_SOURCE_REGISTRY := $(CURDIR)//:/usr/share/roslisp//:/usr/share/common-lisp/ros//:

PACKAGES := sbcl cl-cffi cl-alexandria cl-fiveam cl-cxml cl-puri cl-ppcre \
  cl-bordeaux-threads cl-trivial-garbage cl-yason \
  g++ make cmake pkg-config \
  libbullet-dev liburdfdom-dev libeigen3-dev libosmesa6-dev \
  liborocos-kdl-dev libkdl-parser-dev libassimp-dev libpng-dev liburdfdom-tools \
  python3-roslaunch python3-rosparam python3-rostopic python3-rosnode rosout rosbash python3-rospy \
  roslisp cl-std-msgs cl-geometry-msgs cl-tf2-msgs cl-sensor-msgs cl-visualization-msgs cl-nav-msgs \
  python3-tf2-msgs python3-nav-msgs python3-visualization-msgs \
  python3-actionlib python3-move-base-msgs python3-trajectory-msgs python3-tf2-ros \
  cl-actionlib cl-actionlib-msgs cl-move-base-msgs cl-trajectory-msgs libtf2-dev libtf2-ros-dev ros-robot-state-publisher joint-state-publisher \
  rviz xvfb imagemagick x11-apps cl-hunchentoot libjs-three chromium \
  emacs-nox slime cl-swank
BENCH_PACKAGES := swi-prolog-nox
SLURM_PACKAGES := slurm-wlm munge

SBCL := sbcl --noinform --non-interactive --no-userinit --no-sysinit \
        --eval '(require :asdf)'
NATIVE_LIB := projection/native/build/libcram_native.so
OUT ?= out

.PHONY: all setup setup-bench build native lisp test demo bench check-native check-slurm clean

all: build

# Install the Debian packages the project needs; quick when all are present.
setup:
	@missing=$$(dpkg-query -W -f='$${Package} $${Status}\n' $(PACKAGES) 2>/dev/null \
	   | awk '$$NF=="installed"{print $$1}' | sort | comm -13 - <(tr ' ' '\n' <<< "$(PACKAGES)" | grep . | sort)); \
	if [ -n "$$missing" ]; then \
	  echo "setup: installing $$(wc -w <<< "$$missing") Debian packages"; \
	  apt-get update && DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends $(PACKAGES); \
	else echo "setup: all $(words $(PACKAGES)) Debian packages present"; fi
	@mkdir -p "$(ROS_HOME)"

setup-bench: setup
	@dpkg-query -W -f='$${Status}\n' $(BENCH_PACKAGES) 2>/dev/null | grep -q 'ok installed' || \
	  (apt-get update && DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends $(BENCH_PACKAGES))

.setup-done: Makefile
	$(MAKE) setup
	@touch $@

native: .setup-done
	$(MAKE) -C projection/native

lisp: native
	$(SBCL) --eval '(asdf:load-system "cram-plans")' \
	        --eval '(asdf:load-system "cram-plans/tests")'

# ... and the saved SBCL core that tools/cram-plans-run and its campaign workers start from
build: lisp
	tools/cram-plans-run --build-core

# The suites run in one image (4 GB of heap: the household, REPL and campaign suites together
# hold more than SBCL's default 1 GB at their peak).
# Inside the README test (tests/readme-tests.lisp, which runs the README's `make test` block
# while this target's suites run it), only build.
test: build
	@mkdir -p "$(ROS_HOME)"
	@if [ -n "$$CRAM_PLANS_README_TEST" ]; then \
	  echo "make test: built; the suites are not started again inside the README test"; \
	else sbcl --dynamic-space-size 4096 $(wordlist 2,100,$(SBCL)) --load tests/run.lisp; fi

demo: build
	@mkdir -p $(OUT)
	$(SBCL) --load tools/demo.lisp --eval '(cram-plans-demo:main "$(OUT)")'

bench: build setup-bench
	$(SBCL) --load tests/bench/run.lisp

check-native: native
	$(MAKE) -C projection/native check

# A private single-node Slurm on this machine runs a campaign as a job array (tools/slurm/);
# installs slurm-wlm and munge when missing.
check-slurm: build
	@missing=$$(dpkg-query -W -f='$${Package} $${Status}\n' $(SLURM_PACKAGES) 2>/dev/null \
	   | awk '$$NF=="installed"{print $$1}' | sort | comm -13 - <(tr ' ' '\n' <<< "$(SLURM_PACKAGES)" | grep . | sort)); \
	if [ -n "$$missing" ]; then \
	  echo "check-slurm: installing $$missing"; \
	  apt-get update && DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends $(SLURM_PACKAGES); \
	fi
	tests/slurm-check.sh

clean:
	$(MAKE) -C projection/native clean
	rm -rf $(OUT) .setup-done
