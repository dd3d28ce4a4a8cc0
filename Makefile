# pathfarm: the two commands of the README, and the targets they are made of.
#   make demo   install what is missing, build, render a bundled scene, write EXR + PNG into out/
#   make test   install what is missing, build, run the test suite (what CI runs)
#   make test-long   the long statistical tests (CTest label "long") that `make test` leaves out
#   make fuzz   the libFuzzer targets for FUZZ_SECONDS each (build-fuzz; `make test` runs them briefly)
#   make soak   the farm under chaos for SOAK_SECONDS (scripts/soak.sh; a short run is in `make test`)
BUILD ?= build
JOBS ?= $(shell nproc)
CMAKE_FLAGS ?= -DCMAKE_BUILD_TYPE=Release

.PHONY: all deps build demo test test-long test-sanitize fuzz-build fuzz fuzz-smoke soak container-test bench format clean

all: build

deps:
	./scripts/install-deps.sh

build: deps
	cmake -S . -B $(BUILD) -G Ninja $(CMAKE_FLAGS)
	ninja -C $(BUILD) -j$(JOBS)

demo: build
	mkdir -p out
	./$(BUILD)/pathfarm render scenes/cornell-box/scene.xml --integrator path --spp 32 -o out/cornell-box.exr

test: build fuzz-smoke
	cd $(BUILD) && ctest --output-on-failure -j$(JOBS) --timeout 600 -LE long

# Fuzzing (issue 18): the targets of fuzz/ built with clang, libFuzzer, ASan and UBSan in build-fuzz.
# `make test` runs each on its regression inputs and FUZZ_RUNS generated inputs; `make fuzz` for
# FUZZ_SECONDS each, printing executions and coverage.
FUZZ_SECONDS ?= 60
FUZZ_RUNS ?= 300
FUZZ_TARGETS = fuzz_scene_xml fuzz_mesh fuzz_image fuzz_bundle fuzz_master_requests
fuzz-build: deps
	CC=clang CXX=clang++ cmake -S . -B build-fuzz -G Ninja -DPATHFARM_FUZZ=ON -DCMAKE_BUILD_TYPE=Fuzz \
	  -DCMAKE_CXX_FLAGS_FUZZ="-O1 -gline-tables-only" -DCMAKE_C_FLAGS_FUZZ="-O1 -gline-tables-only"
	ninja -C build-fuzz -j$(JOBS) $(FUZZ_TARGETS)

fuzz-smoke: fuzz-build
	./scripts/fuzz.sh smoke $(FUZZ_RUNS)

fuzz: fuzz-build
	./scripts/fuzz.sh run $(FUZZ_SECONDS)

# The soak (issue 18): master and workers under a chaos loop for SOAK_SECONDS (default 20 minutes).
SOAK_SECONDS ?= 1200
soak: build
	PATHFARM_SOAK_SECONDS=$(SOAK_SECONDS) ./$(BUILD)/test_farm_soak

test-long: build
	cd $(BUILD) && ctest --output-on-failure -j$(JOBS) --timeout 3600 -L long

# The bad-input corpus (loader and CLI), the loader, shape and mesh-reader tests under
# AddressSanitizer + UndefinedBehaviorSanitizer.
SANITIZE_TESTS = test_bad_input test_loader test_shapes test_scene
test-sanitize: deps
	cmake -S . -B build-sanitize -G Ninja -DCMAKE_BUILD_TYPE=Debug -DPATHFARM_SANITIZE=ON
	ninja -C build-sanitize -j$(JOBS) pathfarm $(SANITIZE_TESTS)
	cd build-sanitize && for t in $(SANITIZE_TESTS); do \
	  PATHFARM_CLI=$$PWD/pathfarm ASAN_OPTIONS=detect_leaks=0 UBSAN_OPTIONS=print_stacktrace=1 ./$$t || exit 1; done

# The farm in containers (issue 8): builds the image from deploy/Dockerfile with podman, runs a master and
# two workers on a podman network and a `pathfarm compare` across them (scripts/container-test.sh). Not
# part of `make test`: it compiles the project inside the image build (see deploy/README.md for its duration).
container-test:
	./scripts/container-test.sh

bench: build
	./$(BUILD)/bench_pathtracer scenes/cornell-box/scene.xml scenes/veach-bidir/scene.xml

format:
	clang-format -i $$(git ls-files '*.cpp' '*.h')

clean:
	rm -rf $(BUILD) build-sanitize build-fuzz out
