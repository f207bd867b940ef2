# adamesh — the two set-up commands are `make demo` and `make test`.
# Both install missing Debian packages first (scripts/install-deps.sh), then build with CMake presets.
.PHONY: all deps demo test bench bench-quick bench-full build clean fuzz sanitize

JOBS ?= 2
BIN  := build/release/apps/adamesh/adamesh

all: build

deps:
	@bash scripts/install-deps.sh

build: deps
	cmake --preset release >/dev/null
	cmake --build --preset release -j $(JOBS)

demo: build
	@bash scripts/demo.sh $(BIN)

test: deps
	cmake --preset test >/dev/null
	cmake --build --preset test -j $(JOBS)
	ctest --preset test -j $(JOBS)

bench:
	@bash scripts/install-deps.sh --bench
	cmake --preset release -DADAMESH_BUILD_BENCH=ON >/dev/null
	cmake --build --preset release -j $(JOBS)
	@bash bench/run.sh $(BENCH_ARGS)

bench-quick:
	$(MAKE) bench BENCH_ARGS=--quick

bench-full:
	@bash scripts/install-deps.sh --full
	$(MAKE) bench BENCH_ARGS=--full

# libFuzzer targets (clang-14, ASan+UBSan) run FUZZ_SECONDS each (docs/FUZZING.md).
FUZZ_SECONDS ?= 60
fuzz:
	@bash scripts/install-deps.sh --fuzz
	cmake --preset fuzz >/dev/null
	cmake --build --preset fuzz -j $(JOBS)
	FUZZ_SECONDS=$(FUZZ_SECONDS) bash fuzz/run.sh $(FUZZ_TARGETS)

# The CI sanitizer job alone (ASan+UBSan subset, TSan on the threaded stages; scripts/sanitize.sh).
sanitize: deps
	@bash scripts/sanitize.sh

clean:
	rm -rf build
