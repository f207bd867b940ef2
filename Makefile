# adamesh — the two set-up commands are `make demo` and `make test`.
# Both install missing Debian packages first (scripts/install-deps.sh), then build with CMake presets.
.PHONY: all deps demo test bench bench-quick bench-full build clean

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

clean:
	rm -rf build
