# Convenience targets around CMake. `make demo` and `make test` install missing Debian packages
# first (scripts/install-deps.sh), so they work on a fresh Debian 12 machine.
BUILD ?= build
JOBS ?= $(shell nproc)
DEMO_ARGS ?=
WERROR ?= ON
CMAKE_FLAGS ?=
# The Python the esf module is built for and installed into (e.g. a venv's bin/python3).
PYTHON ?=
ESF_ASAN_OPTIONS ?= detect_leaks=1
ESF_UBSAN_OPTIONS ?= print_stacktrace=1:halt_on_error=1
SANITIZE_CTEST_ARGS ?=

.PHONY: all deps configure build demo test test-nopcl bench python install-python format format-check clean sanitize fuzz

all: build

deps:
	@scripts/install-deps.sh

configure: deps
	@cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release -DESF_WERROR=$(WERROR) $(if $(PYTHON),-DPython3_EXECUTABLE=$(abspath $(PYTHON))) $(CMAKE_FLAGS) > $(BUILD).configure.log || (cat $(BUILD).configure.log; exit 1)

build: configure
	@cmake --build $(BUILD) -j $(JOBS)

demo: configure
	@cmake --build $(BUILD) -j $(JOBS) --target esf_cli
	@$(BUILD)/apps/esf/esf demo $(DEMO_ARGS)

test: build
	@cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

# The Python module, importable with PYTHONPATH=$(BUILD)/python.
python: configure
	@cmake --build $(BUILD) -j $(JOBS) --target esf_python

# Installs the esf package into PYTHON's site-packages (make install-python PYTHON=venv/bin/python3).
install-python: python
	@cmake --install $(BUILD) --component python

# Without PCL: the library, the CLI and the tests (the baselines say how to get them), and the
# installed package used by a project outside esf (ctest package_consumer).
test-nopcl: deps
	@cmake -S . -B $(BUILD)-nopcl -DCMAKE_BUILD_TYPE=Release -DESF_WERROR=$(WERROR) -DESF_WITH_PCL=OFF -DESF_BUILD_BENCH=OFF -DESF_PYTHON=OFF > $(BUILD)-nopcl.configure.log || (cat $(BUILD)-nopcl.configure.log; exit 1)
	@cmake --build $(BUILD)-nopcl -j $(JOBS)
	@cd $(BUILD)-nopcl && ctest --output-on-failure -j $(JOBS)

# The library, CLI and tests with AddressSanitizer + UndefinedBehaviorSanitizer (GCC), in their own
# build folder; runs the whole test suite. Any report fails the run (no recovery from UB).
# The instrumentation makes GCC 12 warn falsely that std::function members inside <regex> may be
# used uninitialised: that one warning is not an error here (the main build keeps it one).
# Under ASan, Eigen stops trusting malloc's alignment and frees with its own allocator; PCL's
# (uninstrumented) libraries trust it, so a PCL cloud freed by our code looked like a heap
# overflow. EIGEN_MALLOC_ALREADY_ALIGNED=1 makes our code allocate as PCL does.
# The PCL baselines module links the runtimes too (it is linked with --no-undefined). The Python
# module is left out: CPython would have to preload libasan to import it (`make test` runs the
# Python tests).
SANITIZE_BUILD ?= build-sanitize
SANITIZE_FLAGS := -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined
sanitize: deps
	@cmake -S . -B $(SANITIZE_BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DESF_WERROR=$(WERROR) \
		-DESF_BUILD_BENCH=OFF -DESF_PYTHON=OFF \
		-DCMAKE_CXX_FLAGS="$(SANITIZE_FLAGS) -Wno-error=maybe-uninitialized -DEIGEN_MALLOC_ALREADY_ALIGNED=1" \
		-DCMAKE_EXE_LINKER_FLAGS="$(SANITIZE_FLAGS)" -DCMAKE_MODULE_LINKER_FLAGS="$(SANITIZE_FLAGS)" \
		-DCMAKE_SHARED_LINKER_FLAGS="$(SANITIZE_FLAGS)" $(CMAKE_FLAGS) \
		> $(SANITIZE_BUILD).configure.log || (cat $(SANITIZE_BUILD).configure.log; exit 1)
	@cmake --build $(SANITIZE_BUILD) -j $(JOBS)
	@cd $(SANITIZE_BUILD) && ASAN_OPTIONS=$(ESF_ASAN_OPTIONS) UBSAN_OPTIONS=$(ESF_UBSAN_OPTIONS) \
		ctest --output-on-failure -j $(JOBS) $(SANITIZE_CTEST_ARGS)

# libFuzzer targets (fuzz/) built with clang, ASan and UBSan in their own build folder; each runs
# FUZZ_SECONDS on a corpus seeded by esf_fuzz_seeds. A crash, sanitizer report, leak, timeout or
# out-of-memory fails the run and leaves the input in $(FUZZ_BUILD)/artifacts/.
FUZZ_BUILD ?= build-fuzz
# Debian 12's clang 16 (clang 14, the default, cannot capture structured bindings in lambdas).
FUZZ_CC ?= clang-16
FUZZ_CXX ?= clang++-16
FUZZ_SECONDS ?= 60
# libFuzzer's random seed: fixed, so that a run is repeatable (set another to explore further).
FUZZ_SEED ?= 1
FUZZ_TARGETS := pcd lzf ply_cloud xyz depth_png test_set catalog scene_set database mesh kinect_recording
FUZZ_FLAGS := -fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer
fuzz:
	@scripts/install-deps.sh fuzz
	@CC=$(FUZZ_CC) CXX=$(FUZZ_CXX) cmake -S . -B $(FUZZ_BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo \
		-DESF_FUZZ=ON -DESF_BUILD_APPS=OFF -DESF_BUILD_TESTS=OFF -DESF_BUILD_BENCH=OFF \
		-DESF_WITH_PCL=OFF -DESF_PYTHON=OFF \
		-DCMAKE_CXX_FLAGS="$(FUZZ_FLAGS) -fsanitize=fuzzer-no-link" \
		-DCMAKE_EXE_LINKER_FLAGS="$(FUZZ_FLAGS)" $(CMAKE_FLAGS) \
		> $(FUZZ_BUILD).configure.log || (cat $(FUZZ_BUILD).configure.log; exit 1)
	@cmake --build $(FUZZ_BUILD) -j $(JOBS) --target esf_fuzz_seeds $(FUZZ_TARGETS:%=%_fuzz)
	@rm -rf $(FUZZ_BUILD)/seeds && mkdir -p $(FUZZ_BUILD)/artifacts
	@ASAN_OPTIONS=detect_leaks=0 $(FUZZ_BUILD)/fuzz/esf_fuzz_seeds $(FUZZ_BUILD)/seeds
	@set -e; for t in $(FUZZ_TARGETS); do \
		echo "== fuzz $$t ($(FUZZ_SECONDS) s)"; \
		mkdir -p $(FUZZ_BUILD)/corpus/$$t; \
		$(FUZZ_BUILD)/fuzz/$${t}_fuzz -seed=$(FUZZ_SEED) -max_total_time=$(FUZZ_SECONDS) -timeout=10 -rss_limit_mb=2048 \
			-print_final_stats=1 -artifact_prefix=$(FUZZ_BUILD)/artifacts/$$t- \
			$(FUZZ_BUILD)/corpus/$$t $(FUZZ_BUILD)/seeds/$$t > $(FUZZ_BUILD)/$$t.log 2>&1 \
			|| { tail -n 60 $(FUZZ_BUILD)/$$t.log; echo "esf: fuzz target $$t failed" >&2; exit 1; }; \
		grep -h "stat::number_of_executed_units\|^Done" $(FUZZ_BUILD)/$$t.log || true; \
	done

bench: build
	@$(BUILD)/bench/esf_bench_descriptor ../shared/data/real/pcl/milk_test.pcd ../shared/data/real/objects/*.pcd

format:
	@git ls-files '*.cpp' '*.hpp' '*.inl' | xargs clang-format -i

format-check:
	@git ls-files '*.cpp' '*.hpp' '*.inl' | xargs clang-format --dry-run --Werror

clean:
	@rm -rf $(BUILD) $(BUILD).configure.log $(SANITIZE_BUILD) $(SANITIZE_BUILD).configure.log \
		$(FUZZ_BUILD) $(FUZZ_BUILD).configure.log
