# pathfarm: the two commands of the README, and the targets they are made of.
#   make demo   install what is missing, build, render a bundled scene, write EXR + PNG into out/
#   make test   install what is missing, build, run the test suite (what CI runs)
#   make test-long   the long statistical tests (CTest label "long") that `make test` leaves out
BUILD ?= build
JOBS ?= $(shell nproc)
CMAKE_FLAGS ?= -DCMAKE_BUILD_TYPE=Release

.PHONY: all deps build demo test test-long test-sanitize container-test bench format clean

all: build

deps:
	./scripts/install-deps.sh

build: deps
	cmake -S . -B $(BUILD) -G Ninja $(CMAKE_FLAGS)
	ninja -C $(BUILD) -j$(JOBS)

demo: build
	mkdir -p out
	./$(BUILD)/pathfarm render scenes/cornell-box/scene.xml --integrator path --spp 32 -o out/cornell-box.exr

test: build
	cd $(BUILD) && ctest --output-on-failure -j$(JOBS) --timeout 600 -LE long

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
	rm -rf $(BUILD) build-sanitize out
