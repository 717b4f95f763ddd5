#!/usr/bin/env bash
# `make roofline`: hgym's copy (the roofline `hgym bench lbm` judges kernels against: the faster
# of STREAM's loop and memcpy) beside STREAM's C copy (benchmarks/stream/copy.c, gcc -O3
# -march=native -fopenmp), alternating C, hgym, C, hgym ... with the same thread count, PAIRS
# pairs per thread count, on arrays of the same size. Prints every pair's ratio hgym / C and the
# median; memory bandwidth drifts from minute to minute, so only pairs measured together are
# compared. Exit 1 if a median is below 0.95: the roofline would flatter the kernels.
set -euo pipefail
HGYM=${HGYM:?set HGYM to the hgym binary}
C=${C_COPY:?set C_COPY to the compiled benchmarks/stream/copy.c}
PAIRS=${PAIRS:-5}
gbs() { sed -E 's/.*"copy_gbs": ?([0-9.]+).*/\1/'; }
# The array size hgym picks for this machine (at least twice the last-level cache each).
values=$("$HGYM" bench copy --json --threads 1 | sed -E 's/.*"values": ?([0-9]+).*/\1/')
status=0
for t in 2 1; do
  ratios=()
  line="threads $t:"
  for _ in $(seq "$PAIRS"); do
    c=$(OMP_NUM_THREADS=$t "$C" "$values" 10 | gbs)
    h=$("$HGYM" bench copy --json --threads "$t" | gbs)
    r=$(awk -v h="$h" -v c="$c" 'BEGIN { printf "%.3f", h / c }')
    ratios+=("$r")
    line="$line  C $c / hgym $h GB/s ($r)"
  done
  median=$(printf '%s\n' "${ratios[@]}" | sort -n | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }')
  echo "$line"
  echo "threads $t: hgym copy / C STREAM copy, median of $PAIRS pairs: $median"
  if awk -v m="$median" 'BEGIN { exit !(m < 0.95) }'; then
    echo "threads $t: hgym's copy is slower than STREAM's C copy; the roofline would flatter the kernels" >&2
    status=1
  fi
done
exit $status
