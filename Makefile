# The two commands a newcomer needs: `make demo` and `make test`. Both install what is missing first.
BUILD ?= build
JOBS ?= 2
CMAKE_FLAGS ?=

.PHONY: all deps configure build demo test bench-build bench goals clean

all: build

deps:
	@bash scripts/install-deps.sh

configure: deps
	@cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release $(CMAKE_FLAGS) > /dev/null

build: configure
	@cmake --build $(BUILD) -j$(JOBS)

demo: build
	@$(BUILD)/apps/aarad/aarad solve cornell --out out/cornell

test: build
	@cd $(BUILD) && ctest --output-on-failure -j$(JOBS)

bench-build: deps
	@cmake -S . -B $(BUILD)-bench -DCMAKE_BUILD_TYPE=Release -DAARAD_BUILD_TESTS=OFF -DAARAD_BUILD_BENCH=ON > /dev/null
	@cmake --build $(BUILD)-bench -j$(JOBS)

bench: bench-build
	@bash bench/run.sh $(BUILD)-bench

goals: bench-build
	@bash bench/goals.sh $(BUILD)-bench

clean:
	@rm -rf $(BUILD) $(BUILD)-bench
