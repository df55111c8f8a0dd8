# zeroset: the two commands of the README, and a few helpers.
#   make demo   install what is missing, build, run the main job (pictures and a mesh in out/)
#   make test   install what is missing, build, run the whole test suite with ctest
#   make format format the C++ sources with clang-format (.clang-format)
JOBS ?= $(shell nproc)
BUILD ?= build
ASAN_BUILD ?= build-asan
FUZZ_BUILD ?= build-fuzz
CMAKE_FLAGS ?=

.PHONY: deps build demo test test-asan fuzz bench format clean

deps:
	scripts/install-deps.sh

build: deps
	cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release $(CMAKE_FLAGS)
	cmake --build $(BUILD) -j $(JOBS)

demo: build
	scripts/demo.sh $(BUILD)/apps/cli/zeroset out

test: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS) --timeout 600

# The tests again with AddressSanitizer and UndefinedBehaviorSanitizer, at -O1 -g1 (line tables
# for the reports), without the targets only the Release build needs: the tests that open the
# window (label gui), the package tests (label package), the benchmarks and the Python module.
ASAN_CMAKE_FLAGS = -DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG" \
	-DZEROSET_SANITIZE=ON -DZEROSET_BUILD_BENCH=OFF -DZEROSET_BUILD_GUI_TESTS=OFF
test-asan: deps
	cmake -S . -B $(ASAN_BUILD) $(ASAN_CMAKE_FLAGS) $(CMAKE_FLAGS)
	cmake --build $(ASAN_BUILD) -j $(JOBS)
	cd $(ASAN_BUILD) && LSAN_OPTIONS=suppressions=$(CURDIR)/tests/lsan.supp:print_suppressions=0 \
	      ctest --output-on-failure -j $(JOBS) --timeout 1200 -LE package

# Runs the fuzz targets (libFuzzer, clang) for FUZZ_SECONDS each: the surface language's
# parser, then scene files (JSON and SURFER's .jsurf).
FUZZ_SECONDS ?= 60
fuzz: deps
	CXX=clang++ cmake -S . -B $(FUZZ_BUILD) -DZEROSET_BUILD_FUZZ=ON -DZEROSET_BUILD_TESTS=OFF \
	      -DZEROSET_BUILD_BENCH=OFF -DZEROSET_BUILD_VIEWER=OFF -DZEROSET_BUILD_PYTHON=OFF \
	      -DZEROSET_BUILD_EXAMPLES=OFF -DCMAKE_BUILD_TYPE=RelWithDebInfo \
	      "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG"
	cmake --build $(FUZZ_BUILD) -j $(JOBS) --target parse_fuzz scene_fuzz
	mkdir -p $(FUZZ_BUILD)/corpus && cp tests/fuzz/corpus/* $(FUZZ_BUILD)/corpus/
	$(FUZZ_BUILD)/tests/fuzz/parse_fuzz -max_total_time=$(FUZZ_SECONDS) -timeout=5 -max_len=512 \
	      -print_final_stats=1 $(FUZZ_BUILD)/corpus
	mkdir -p $(FUZZ_BUILD)/scene_corpus && cp tests/fuzz/scene_corpus/* $(FUZZ_BUILD)/scene_corpus/
	$(FUZZ_BUILD)/tests/fuzz/scene_fuzz -max_total_time=$(FUZZ_SECONDS) -timeout=5 -max_len=4096 \
	      -rss_limit_mb=2048 -print_final_stats=1 $(FUZZ_BUILD)/scene_corpus

# Peer comparisons (installs the peer tools) and micro-benchmarks; writes docs/benchmarks.md.
bench: build
	scripts/install-deps.sh --peers
	scripts/bench.sh $(BUILD)

# Formats the C++ sources in place with clang-format and the repository's .clang-format.
FORMAT_DIRS ?= src include apps tests bench examples
format:
	find $(FORMAT_DIRS) \( -name '*.cpp' -o -name '*.h' \) -print0 | xargs -0 clang-format -i

clean:
	rm -rf $(BUILD) $(ASAN_BUILD) $(FUZZ_BUILD)
