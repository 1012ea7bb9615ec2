# Convenience targets around CMake. `make demo` and `make test` install missing Debian packages
# first (scripts/install-deps.sh), so they work on a fresh Debian 12 machine.
BUILD ?= build
JOBS ?= $(shell nproc)
DEMO_ARGS ?=
WERROR ?= ON
CMAKE_FLAGS ?=
# The Python the esf module is built for and installed into (e.g. a venv's bin/python3).
PYTHON ?=

.PHONY: all deps configure build demo test bench python install-python format format-check clean

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

bench: build
	@$(BUILD)/bench/esf_bench_descriptor ../shared/data/real/pcl/milk_test.pcd ../shared/data/real/objects/*.pcd

format:
	@git ls-files '*.cpp' '*.hpp' '*.inl' | xargs clang-format -i

format-check:
	@git ls-files '*.cpp' '*.hpp' '*.inl' | xargs clang-format --dry-run --Werror

clean:
	@rm -rf $(BUILD) $(BUILD).configure.log
