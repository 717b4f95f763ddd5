#!/usr/bin/env bash
# `make nightly`: long checks refreshed under results/, then a summary of what changed since the
# last committed results. Every step runs even if an earlier one fails; the exit code is the
# number of failed steps (0 = all passed).
set -uo pipefail
cd "$(dirname "$0")/.."
HGYM=${HGYM:-${CARGO_TARGET_DIR:-$HOME/.cache/hgym-target}/release/hgym}
OUT=results/nightly
mkdir -p "$OUT"
LOG="$OUT/log.txt"
: > "$LOG"
failed=0
start=$(date +%s)
step() {
  local name=$1; shift
  local t0=$(date +%s)
  # The command as a user types it: `hgym ...`, not this machine's path to the binary.
  local shown="$*"
  [ "$1" = "$HGYM" ] && shown="hgym ${*:2}"
  echo "== $name: $shown" | tee -a "$LOG"
  if "$@" > "$OUT/$name.txt" 2>>"$LOG"; then status=ok; else status="FAILED ($?)"; failed=$((failed + 1)); fi
  echo "   $status in $(( $(date +%s) - t0 )) s" | tee -a "$LOG"
}
step validate-cylinder "$HGYM" validate cylinder --level default
step validate-pinball  "$HGYM" validate pinball --level default
step validate-square   "$HGYM" validate square --level default
step validate-kolmogorov "$HGYM" validate kolmogorov
step validate-channel "$HGYM" validate channel --level default
step bench-lbm        "$HGYM" bench lbm
step bench-refine     "$HGYM" bench refine
step bench-agents     "$HGYM" bench agents
step bench-kolmogorov "$HGYM" bench kolmogorov
step bench-channel    "$HGYM" bench channel
step bench-envs       "$HGYM" bench envs --quick
# Gymnasium's contract on every 3D ID at coarse (make test checks each family's first).
step contract-3d      cargo test --release --locked --test env3_contract -- --ignored
step bench-python     "$HGYM" bench python
for algo in ppo ddpg td3 gppo; do
  step "train-$algo" "$HGYM" train --env Kolmogorov_2D_Re40 --algo "$algo" --steps 2000 --out "$OUT/train"
done
# The fuzz targets of hostile input (tests/fuzz.rs, and the Hub replies in tests/hub_push.rs):
# 10^4 inputs each (make test runs 64, the Hub 512).
step fuzz env PROPTEST_CASES=10000 cargo test --release --locked --test fuzz --test hub_push
# Exact-solution tests too slow for make test (the channel's raw Orr-Sommerfeld rate on a fine grid).
step exact-slow cargo test --release --locked -p hgym-solvers --test channel_exact -- --ignored
step leaderboard "$HGYM" leaderboard
total=$(( $(date +%s) - start ))
{
  echo "# nightly $(date -u +%Y-%m-%dT%H:%MZ), $(git rev-parse --short HEAD 2>/dev/null), ${total} s, ${failed} failed step(s)"
  echo
  grep -E "^(==|   )" "$LOG"
  echo
  echo "## changed since the last committed results (git diff --stat -- results/)"
  git diff --stat -- results/ | tail -25
  echo
  echo "## leaderboard lines that changed"
  git diff -U0 -- results/LEADERBOARD.md | grep -E "^[-+]\|" || echo "(none)"
  echo
  echo "## validation: every case of every family"
  # Flow cases print `<case> [<family>] level <level> (...): PASS|FAIL|DIVERGED`; the Kolmogorov
  # case prints `kolmogorov_re40 (...)` and one `pass`/`FAIL` line per check.
  grep -hE "^[A-Za-z0-9_-]+ \[[a-z_]+\] level " "$OUT"/validate-*.txt | sed -E 's/ \(.*\): / /'
  grep -hE "^kolmogorov_[a-z0-9_]+ |^  (pass|FAIL) " "$OUT"/validate-kolmogorov.txt | sed -E 's/ \(.*//'
  echo
  echo "## failing cases"
  failing=$(
    grep -hE "^[A-Za-z0-9_-]+ \[[a-z_]+\] level .*: (FAIL|DIVERGED)" "$OUT"/validate-*.txt | sed -E 's/ \(.*\): / /'
    if grep -qE "^  FAIL " "$OUT"/validate-kolmogorov.txt; then echo "kolmogorov_re40 FAIL"; fi
  )
  echo "${failing:-(none)}"
  echo
  # The long results nightly leaves alone, and how far the code has moved since each was made.
  python3 scripts/results_age.py results
} > "$OUT/summary.md"
cat "$OUT/summary.md"
exit "$failed"
