#!/usr/bin/env bash
# Runs every benchmark program of a bench build (`make bench`). Usage: bench/run.sh BUILD_DIR
set -euo pipefail
build=${1:-build-bench}
for program in "$build"/bench/bench_*; do
  [ -x "$program" ] || continue
  echo "== $(basename "$program")"
  "$program"
done
if [ -x bench/solve.sh ]; then bash bench/solve.sh "$build"; fi
