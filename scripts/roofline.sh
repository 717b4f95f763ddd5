#!/usr/bin/env bash
# `make roofline`: hgym's copy loop (the roofline `hgym bench lbm` judges kernels against) beside
# STREAM's C copy (benchmarks/stream/copy.c, gcc -O3 -march=native -fopenmp), alternating
# C, hgym, C, hgym ... with the same thread count, PAIRS pairs per thread count. Prints every
# pair's ratio hgym / C and the median; memory bandwidth drifts from minute to minute, so only
# pairs measured together are compared.
set -euo pipefail
HGYM=${HGYM:?set HGYM to the hgym binary}
C=${C_COPY:?set C_COPY to the compiled benchmarks/stream/copy.c}
PAIRS=${PAIRS:-5}
gbs() { sed -E 's/.*"copy_gbs": ?([0-9.]+).*/\1/'; }
for t in 2 1; do
  ratios=()
  line="threads $t:"
  for _ in $(seq "$PAIRS"); do
    c=$(OMP_NUM_THREADS=$t "$C" | gbs)
    h=$("$HGYM" bench copy --json --threads "$t" | gbs)
    r=$(awk -v h="$h" -v c="$c" 'BEGIN { printf "%.3f", h / c }')
    ratios+=("$r")
    line="$line  C $c / hgym $h GB/s ($r)"
  done
  median=$(printf '%s\n' "${ratios[@]}" | sort -n | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }')
  echo "$line"
  echo "threads $t: hgym copy / C STREAM copy, median of $PAIRS pairs: $median"
done
