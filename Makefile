# mpmsdem — the two commands a user needs on a fresh Debian 12 machine:
#   make demo   install what is missing, build, install into YADE's Python, run the demo scene
#   make test   same set-up, then every test: ctest (C++), pytest (YADE level), scripts/checks
PY       ?= /usr/bin/python3
BUILD    ?= build
JOBS     ?= $(shell nproc)
# The build's package comes first. YADE's folder is not added: `import mpmsdem` finds it, as in a
# user's script (a folder computed here would be computed before `deps` installs YADE).
export PYTHONPATH := $(CURDIR)/$(BUILD)/python$(if $(PYTHONPATH),:$(PYTHONPATH))
export OMP_NUM_THREADS ?= $(JOBS)

.PHONY: all deps configure build install demo test test-cpp test-sanitize fuzz test-py checks bench bench-peers bench-scene-needs bench-coupling bench-memory clean

all: build

deps:
	@bash tools/install-deps.sh

$(BUILD)/CMakeCache.txt: | deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release -DPython3_EXECUTABLE=$(PY) -DMPMSDEM_PYTHON=$(PY)

configure: deps $(BUILD)/CMakeCache.txt

build: configure
	cmake --build $(BUILD) -j $(JOBS)

install: build
	cmake --install $(BUILD) > /dev/null

# The demo runs through the installed package, the way a user's `yade -x script.py` does.
demo: install
	env -u PYTHONPATH yade -n -j $(JOBS) -x examples/demo.py

# ctest runs JOBS tests at once, each with OMP_NUM_THREADS threads: more threads than cores.
# Threads that spin at OpenMP barriers then wait for descheduled ones at every barrier (two
# coupled tests of 4,000 short steps took 123 s and 450 s instead of 0.4 s each); passive
# waiting sleeps instead. Results do not depend on it.
test-cpp: build
	cd $(BUILD) && OMP_WAIT_POLICY=PASSIVE ctest --output-on-failure -j $(JOBS)

# The C++ tests again under AddressSanitizer (with LeakSanitizer) and UndefinedBehaviorSanitizer,
# in a build folder of their own (-O1 -g, NDEBUG as in the release build: the code under test is
# the release build's); any report fails the test that made it. The long tests of tools/sanitizers/long-tests.txt are left
# out unless SANITIZE_ALL=1 (why: that file; ctest names a parameterised test "NAME  # GetParam() = …").
SANBUILD     ?= build-sanitize
SANITIZE_ALL ?= 0
SANITIZE_SKIP = $(if $(filter 1,$(SANITIZE_ALL)),,-E '^($(shell grep -v '^\#' tools/sanitizers/long-tests.txt | paste -sd'|'))( |$$)')
test-sanitize: deps
	cmake -S . -B $(SANBUILD) -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG="-O1 -g -DNDEBUG" -DMPMSDEM_SANITIZE=ON \
	  -DPython3_EXECUTABLE=$(PY) -DMPMSDEM_PYTHON=$(PY) > /dev/null
	cmake --build $(SANBUILD) -j $(JOBS) --target test_sdem test_mpm test_coupling test_run
	cd $(SANBUILD) && OMP_WAIT_POLICY=PASSIVE \
	  ASAN_OPTIONS=detect_leaks=1:abort_on_error=0:halt_on_error=1 \
	  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
	  ctest --output-on-failure -j $(JOBS) $(SANITIZE_SKIP)

# Every reader of files from elsewhere (the scene JSON with its blocks, OBJ, STL, ESRI ASCII
# rasters, the coupled checkpoint and the front snapshot record) under libFuzzer with
# AddressSanitizer and UndefinedBehaviorSanitizer, in a build folder of its own (clang, -O1):
# every file of tests/fuzz/corpus/ replayed, then each target fuzzed for FUZZ_SECONDS, JOBS at
# a time. Any crash, leak, undefined behaviour, hang or exception other than the documented
# ParameterError / RuntimeFailure fails it (docs/extremes.md, "Fuzzing"). FUZZ_SECONDS=0: replay only.
FUZZBUILD    ?= build-fuzz
FUZZ_SECONDS ?= 20
FUZZ_CC      ?= clang-14
FUZZ_CXX     ?= clang++-14
fuzz: deps
	cmake -S . -B $(FUZZBUILD) -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG="-O1 -gline-tables-only" \
	  -DCMAKE_C_COMPILER=$(FUZZ_CC) -DCMAKE_CXX_COMPILER=$(FUZZ_CXX) \
	  -DMPMSDEM_DRIVER_ONLY=ON -DMPMSDEM_CUDA=OFF -DMPMSDEM_FUZZ=ON > /dev/null
	cmake --build $(FUZZBUILD) -j $(JOBS) --target fuzz_targets
	tests/fuzz/run.sh $(FUZZBUILD) $(FUZZ_SECONDS) $(JOBS)

# YADE scenes of a few bodies run fastest on one OpenMP thread (YADE's parallel loops cost
# more than they save there): JOBS test processes (pytest-xdist) of one thread each.
test-py: install
	OMP_NUM_THREADS=1 $(PY) -m pytest -q -n $(JOBS) tests/python

# The checks are independent single-threaded runs of a few minutes: JOBS at a time
# (tools/run_checks.py keeps each one's output whole and ends with a table of their times). The
# C++ driver in check_column_collapse uses all cores itself, beside another check: passive
# waiting at its barriers (see test-cpp).
checks: install
	OMP_NUM_THREADS=1 OMP_WAIT_POLICY=PASSIVE $(PY) tools/run_checks.py --jobs $(JOBS)

test: test-cpp test-sanitize fuzz test-py checks

bench: install
	OMP_NUM_THREADS=1 $(PY) scripts/bench/bench_sdem.py
	$(PY) scripts/bench/bench_mpm.py --build $(BUILD)

# Opt-in: our MPM CPU solver against a Taichi implementation of the same scheme (needs PyPI
# once, for .venv-peers/). Minutes of runs; not part of `make test`.
bench-peers: build
	$(PY) scripts/bench/bench_mpm_peers.py --build $(BUILD) --threads $(JOBS)

# Opt-in: each saving of "model only what the scene needs" (no flow, no blocks, fixed pairs,
# outputs) against the run it should cost the same as, in YADE and the driver, one thread
# (a few minutes); docs/benchmarks.md. Not part of `make test`.
bench-scene-needs: build
	OMP_NUM_THREADS=1 $(PY) scripts/bench/bench_scene_needs.py --build $(BUILD)

# Opt-in: what the MP-block coupling adds to the MPM step on the coarse §3.2 flume (goal <= 25 %),
# the driver, one thread (about a minute); docs/benchmarks.md. Not part of `make test`.
bench-coupling: install
	OMP_NUM_THREADS=1 $(PY) scripts/bench/bench_coupling_share.py --exe $(BUILD)/mpmsdem-run

# Opt-in: peak memory of whole driver runs with outputs and restarts at 10^6 points, both
# precisions (a few minutes, about 0.6 GB); docs/benchmarks.md. Not part of `make test`.
bench-memory: build
	$(PY) scripts/bench/bench_output_memory.py --exe $(BUILD)/mpmsdem-run --precisions double,float

clean:
	rm -rf $(BUILD)
