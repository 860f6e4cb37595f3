# semantic_exploration entry points. Each target installs what is missing
# (scripts/setup.sh), builds (scripts/build.sh) and then does its job.
#   make run     one simulated semantic exploration, writes a report to results/
#   make test    every test (gtest, pytest, rostest); ends with "N passed, N failed, N skipped"
#   make test-sanitize  the core gtests built with -fsanitize=address,undefined (part of make test)
#   make bench   every benchmark; JSON lines under results/bench/
#   make experiments  N runs x {classic, semantic} x scenes -> plots and report (long; deterministic runs)
#   make build   build only, without the core gtest programs (BUILD_TYPE=Debug for a debug build)
BUILD_TYPE ?= Release
export BUILD_TYPE

.PHONY: run test test-sanitize bench experiments build setup clean

run:
	bash scripts/run_exploration.sh $(ARGS)

test:
	bash scripts/run_tests.sh

test-sanitize: setup
	bash scripts/run_sanitize.sh

bench:
	bash scripts/run_benchmarks.sh

build: setup
	bash scripts/build.sh

setup:
	bash scripts/setup.sh

clean:
	rm -rf .colcon

experiments:
	bash scripts/run_exploration.sh --experiments $(ARGS)
