#!/usr/bin/env bash
# Runs every benchmark program of a bench build (`make bench`): the rasterizer, form-factor and hierarchy
# micro-benchmarks, then bench_solve (the solver table of docs/benchmarks.md; each solve capped at 600 s).
# Usage: bench/run.sh BUILD_DIR
set -euo pipefail
build=${1:-build-bench}
for program in "$build"/bench/bench_*; do
  [ -x "$program" ] || continue
  echo "== $(basename "$program")"
  "$program"
done
