# zeroset: the two commands of the README, and a few helpers.
#   make demo   install what is missing, build, run the main job (pictures and a mesh in out/)
#   make test   install what is missing, build, run the whole test suite with ctest
#   make format format the C++ sources with clang-format (.clang-format)
JOBS ?= $(shell nproc)
BUILD ?= build
ASAN_BUILD ?= build-asan
CMAKE_FLAGS ?=

.PHONY: deps build demo test asan-configure test-asan fuzz bench format clean

deps:
	scripts/install-deps.sh

build: deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release $(CMAKE_FLAGS)
	cmake --build $(BUILD) -j $(JOBS)

demo: build
	scripts/demo.sh $(BUILD)/apps/cli/zeroset out

test: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS) --timeout 600

# The sanitizer build (clang, build-asan/): AddressSanitizer and UndefinedBehaviorSanitizer at
# -O1 -g1 (line tables for the reports), with libFuzzer's coverage counters so that the fuzz
# targets link the same libraries; without what only the Release build needs: the tests that
# open the window (label gui), the benchmarks and the Python module. test-asan runs every test
# but the package tests and the long mesh and viewer sweeps (labels package, mesh_heavy,
# viewer_heavy); fuzz runs the
# fuzz targets for FUZZ_SECONDS each: the surface language's parser, then scene files (JSON and
# SURFER's .jsurf).
ASAN_CMAKE_FLAGS = -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo \
	"-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG" -DZEROSET_SANITIZE=ON -DZEROSET_BUILD_FUZZ=ON \
	-DZEROSET_BUILD_BENCH=OFF -DZEROSET_BUILD_GUI_TESTS=OFF
FUZZ_SECONDS ?= 60

asan-configure: deps
	cmake -S . -B $(ASAN_BUILD) $(ASAN_CMAKE_FLAGS) $(CMAKE_FLAGS)

test-asan: asan-configure
	cmake --build $(ASAN_BUILD) -j $(JOBS)
	cd $(ASAN_BUILD) && LSAN_OPTIONS=suppressions=$(CURDIR)/tests/lsan.supp:print_suppressions=0 \
	      ctest --output-on-failure -j $(JOBS) --timeout 1200 -LE 'package|mesh_heavy|viewer_heavy'

fuzz: asan-configure
	cmake --build $(ASAN_BUILD) -j $(JOBS) --target parse_fuzz scene_fuzz
	mkdir -p $(ASAN_BUILD)/corpus && cp tests/fuzz/corpus/* $(ASAN_BUILD)/corpus/
	$(ASAN_BUILD)/tests/fuzz/parse_fuzz -max_total_time=$(FUZZ_SECONDS) -timeout=5 -max_len=512 \
	      -print_final_stats=1 $(ASAN_BUILD)/corpus
	mkdir -p $(ASAN_BUILD)/scene_corpus && cp tests/fuzz/scene_corpus/* $(ASAN_BUILD)/scene_corpus/
	$(ASAN_BUILD)/tests/fuzz/scene_fuzz -max_total_time=$(FUZZ_SECONDS) -timeout=5 -max_len=4096 \
	      -rss_limit_mb=2048 -print_final_stats=1 $(ASAN_BUILD)/scene_corpus

# Peer comparisons (installs the peer tools) and micro-benchmarks; writes docs/benchmarks.md.
bench: build
	scripts/install-deps.sh --peers
	scripts/bench.sh $(BUILD)

# Formats the C++ sources in place with clang-format and the repository's .clang-format.
FORMAT_DIRS ?= src include apps tests bench examples python/src
format:
	find $(FORMAT_DIRS) \( -name '*.cpp' -o -name '*.h' \) -print0 | xargs -0 clang-format -i

clean:
	rm -rf $(BUILD) $(ASAN_BUILD)
