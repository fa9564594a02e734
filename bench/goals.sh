#!/usr/bin/env bash
# Measures every goal the issues set their benchmarks (docs/benchmarks.md, "Where the goals stand") and prints
# one table: the goal, what this machine measured, and whether it is met. About two minutes on two cores.
# Usage: bench/goals.sh BUILD_DIR (a Release build with -DAARAD_BUILD_BENCH=ON; `make goals` builds and runs it).
set -euo pipefail
trap 'echo "goals.sh: line $LINENO failed: $BASH_COMMAND" >&2' ERR
build=${1:-build-bench}
bench=$build/bench
for program in bench_raster bench_hierarchy bench_formfactor bench_solve; do
  [ -x "$bench/$program" ] ||
    { echo "goals.sh: $bench/$program is missing; build with -DAARAD_BUILD_BENCH=ON" >&2; exit 2; }
done
# One core for the per-shot ratios, as docs/benchmarks.md measures them, when taskset is there.
one_core=()
command -v taskset > /dev/null && one_core=(taskset -c 1)

# Column `column` (a header name) of the CSV rows of Google Benchmark output on stdin whose name matches `pattern`:
# "name value" per row, the name without its quotes.
csv() {
  awk -F, -v pattern="$1" -v column="$2" '
    /^name,/ { for (i = 1; i <= NF; ++i) { h = $i; gsub(/"/, "", h); at[h] = i }; next }
    /^"BM_/ { name = $1; gsub(/"/, "", name); if (name ~ pattern) print name, $(at[column]) }'
}
# A row of the goal table: goal, measured, met.
row() { printf '| %s | %s | %s |\n' "$1" "$2" "$3"; }
# "yes" when the awk expression $1 holds, else "no".
verdict() { awk "BEGIN { exit !($1) }" && echo yes || echo no; }

echo "measuring (about two minutes) ..." >&2
raster=$("$bench/bench_raster" --benchmark_filter='(aarad|freetype)_convex$' --benchmark_min_time=1 \
  --benchmark_repetitions=5 --benchmark_report_aggregates_only=true --benchmark_format=csv 2>/dev/null)
aarad_rate=$(csv '_aarad_convex_median$' items_per_second <<< "$raster" | awk '{print $2}')
freetype_rate=$(csv '_freetype_convex_median$' items_per_second <<< "$raster" | awk '{print $2}')
raster_ratio=$(awk -v a="$aarad_rate" -v f="$freetype_rate" 'BEGIN { printf "%.2f", a / f }')
raster_error=$(awk '$1 == "aarad" { print $2; exit }' <<< "$raster")

# Medians of five: one refinement to 10^4 leaves takes about 10 ms, where a hiccup of the machine shows.
hierarchy=$("$bench/bench_hierarchy" --benchmark_filter='BM_Refine' --benchmark_repetitions=5 \
  --benchmark_report_aggregates_only=true --benchmark_format=csv 2>/dev/null)
split_ratio() {  # largest over smallest median time per split of one refinement
  csv "^$1/.*_median\$" ns_per_split <<< "$hierarchy" |
    awk 'NR == 1 { lo = hi = $2 } { if ($2 < lo) lo = $2; if ($2 > hi) hi = $2 } END { printf "%.2f", hi / lo }'
}
uniform_ratio=$(split_ratio BM_RefineUniform)
adaptive_ratio=$(split_ratio BM_RefineAdaptiveBalanced)
leaf_bytes=$(csv '^BM_Refine.*_median$' heap_bytes_per_leaf <<< "$hierarchy" |
  awk '{ if ($2 > m) m = $2 } END { printf "%.0f", m }')

# Two runs: Google Benchmark's CSV output takes one set of counters per run, and BM_Shot's differ from BM_Pair's.
formfactor() {
  "${one_core[@]}" "$bench/bench_formfactor" --benchmark_filter="$1" --benchmark_repetitions=3 \
    --benchmark_report_aggregates_only=true --benchmark_format=csv 2>/dev/null
}
shot_ms=$(formfactor 'BM_Shot/aa/1/100/' | csv '_median$' real_time | awk '{printf "%.2f", $2}')
shots=$(formfactor 'BM_Pair')
pair() { csv "^BM_Pair/$1/.*_median\$" aa/classical <<< "$shots" | awk '{printf "%s%.2f", sep, $2; sep = " / "}'; }
cornell_pairs=$(pair 0)
office_pairs=$(pair 1)
worst_pair=$(csv '^BM_Pair/.*_median$' aa/classical <<< "$shots" | awk '{ if ($2 > m) m = $2 } END { print m }')

# bench_solve prints a Markdown table; a cell reads "0.36 s, 894 shots, 1588 el." or "0.230 % / 1.428 % (0.4 s)".
solve=$("$bench/bench_solve" --scenes office,cornell --methods aa-hemicube:100 --budget 400)
solve_row=$(grep '^| aa-hemicube | 100 ' <<< "$solve")
cornell_cell=$(awk -F' [|] ' '{print $6}' <<< "$solve_row")
office_cell=$(awk -F' [|] ' '{print $7}' <<< "$solve_row")
furnace=$("$bench/bench_solve" --scenes furnace --methods aa-hemicube:100,hemicube:1200 --budget 400)
furnace_cell() { grep "^| $1 | $2 " <<< "$furnace" | awk -F' [|] ' '{print $8}' | sed 's/ |$//'; }
aa_furnace=$(furnace_cell aa-hemicube 100)
classical_furnace=$(furnace_cell hemicube 1200)
seconds() {  # the number before the first "s" of a cell
  awk '{ for (i = 1; i <= NF; ++i) if ($(i + 1) ~ /^s[,)]?$/) { gsub(/[(]/, "", $i); print $i; exit } }' <<< "$1"
}
rms() { awk '{print $1}' <<< "$1"; }

echo
echo "| goal | measured | met |"
echo "|---|---|---|"
row "exact rasterizer at least 2x FreeType's throughput on convex polygons (issue 2)" "${raster_ratio}x" \
  "$(verdict "$raster_ratio >= 2")"
row "coverage error below 1e-9 (issue 2)" "$raster_error" "$(verdict "$raster_error < 1e-9")"
row "time per split within 1.5x from 10^4 to 10^6 leaves (issue 4)" \
  "uniform ${uniform_ratio}x, adaptive ${adaptive_ratio}x" \
  "$(verdict "$uniform_ratio <= 1.5 && $adaptive_ratio <= 1.5")"
row "under 1 KiB per leaf (issue 4)" "at most $leaf_bytes heap bytes" "$(verdict "$leaf_bytes < 1024")"
row "AA shot at N = 100 over 16 000 receivers under 20 ms (issue 3)" "$shot_ms ms" "$(verdict "$shot_ms < 20")"
row "AA shot at most 1.3x a classical one at N = 100 / 300 / 1000 (issue 3)" \
  "Cornell box $cornell_pairs, office_16k $office_pairs" "$(verdict "$worst_pair <= 1.3")"
row "Cornell box, AA N = 100, to 1 % in under 2 s (issue 5)" "$cornell_cell" \
  "$(verdict "$(seconds "$cornell_cell") < 2")"
row "office, AA N = 100, to 1 % in under 30 s (issue 5)" "$office_cell" "$(verdict "$(seconds "$office_cell") < 30")"
row "furnace: AA N = 100 more accurate than classical N = 1200, and faster (issue 5)" \
  "AA $aa_furnace; classical $classical_furnace" \
  "$(verdict "$(rms "$aa_furnace") < $(rms "$classical_furnace") && \
$(seconds "$aa_furnace") < $(seconds "$classical_furnace")")"
