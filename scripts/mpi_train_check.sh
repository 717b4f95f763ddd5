#!/usr/bin/env bash
# `make mpi`: training, evaluation and an open-loop run of an environment (3D by default) in one process
# (`hgym`) and on 2 MPI ranks (`hgym-mpi` under mpirun, the flow split over the ranks, the rest
# run alike on every rank, files and output from rank 0 only). The trained policy, the curve's
# returns and the evaluation report (its --json output, which rank 1 must not repeat) must be
# identical. Exit 1 if they differ.
set -euo pipefail
: "${HGYM:?path to hgym}" "${HGYM_MPI:?path to hgym-mpi}" "${MPIRUN:=mpirun --allow-run-as-root --oversubscribe --bind-to none}"
config=${1:-tests/cases/mpi_train.toml}
env=${2:-Cylinder_3D_Re200}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export HGYM_CACHE="$work/cache"
# Scratch folders of ranks go here, so that the check at the end sees this run's only.
export TMPDIR="$work/tmp"
mkdir -p "$TMPDIR"
fail() { echo "MPI train check FAILED: $*"; exit 1; }
# The curve without its wall-clock column.
returns() { python3 -c 'import csv,sys; r=list(csv.DictReader(open(sys.argv[1]))); print([{k: v for k, v in row.items() if k != "wall_s"} for row in r])' "$1"; }
# A report without its timings.
report() { python3 -c 'import json,sys; r=json.loads(sys.stdin.read()); r.pop("manifest", None); r.pop("wall_s", None); print(json.dumps(r, sort_keys=True))'; }

"$HGYM" train --env $env --algo td3 --config "$config" --seed 3 --threads 1 --out "$work/one" >/dev/null 2>&1
$MPIRUN -np 2 -x RAYON_NUM_THREADS=1 "$HGYM_MPI" train --env $env --algo td3 --config "$config" --seed 3 --threads 1 --out "$work/np2" >/dev/null 2>&1
run=$env-td3-coarse/seed3
for f in policy.json; do
    cmp -s "$work/one/$run/$f" "$work/np2/$run/$f" || fail "2 ranks train another $f than one process"
done
[ "$(returns "$work/one/$run/curve.csv")" = "$(returns "$work/np2/$run/curve.csv")" ] || fail "2 ranks give other returns than one process (curve.csv)"
echo "MPI train check: 2 ranks train bitwise the policy of one process ($(($(wc -l < "$work/one/$run/curve.csv") - 1)) rounds of td3 on $env)"

one=$("$HGYM" eval --policy "$work/one/$run" --env $env --config "$config" --episodes 1 --threads 1 --json 2>/dev/null | report)
two=$($MPIRUN -np 2 "$HGYM_MPI" eval --policy "$work/one/$run" --env $env --config "$config" --episodes 1 --threads 1 --json 2>/dev/null | report)
[ "$one" = "$two" ] || fail "2 ranks evaluate otherwise than one process: $one against $two"
echo "MPI train check: the evaluation on 2 ranks prints the report of one process, once"

# Resume on 2 ranks: every rank continues from rank 0's checkpoint.
"$HGYM" train --resume "$work/one/$run" --steps 16 --threads 1 >/dev/null 2>&1
$MPIRUN -np 2 "$HGYM_MPI" train --resume "$work/np2/$run" --steps 16 --threads 1 >/dev/null 2>&1
cmp -s "$work/one/$run/policy.json" "$work/np2/$run/policy.json" || fail "2 ranks resume to another policy than one process"
echo "MPI train check: resumed on 2 ranks, bitwise the policy of one process"
# Bad input on every rank: the job ends with exit code 2, naming the problem once per rank.
set +e
err=$($MPIRUN -np 2 "$HGYM_MPI" train --env NoSuchFlow_3D --algo td3 --out "$work/bad" 2>&1 >/dev/null); code=$?
set -e
[ $code = 2 ] || fail "an unknown environment on 2 ranks exits with $code, not 2"
echo "$err" | grep -q "unknown environment ID 'NoSuchFlow_3D'" || fail "the unknown environment is not named: $err"
set +e
$MPIRUN -np 2 "$HGYM_MPI" leaderboard >/dev/null 2>&1; code=$?
set -e
[ $code = 2 ] || fail "a command that does not run on ranks exits with $code, not 2"
set +e
err=$($MPIRUN -np 2 "$HGYM_MPI" train --env $env --algo td3 --threads 2 --steps 4 --out "$work/threads" 2>&1 >/dev/null); code=$?
set -e
[ $code = 2 ] || fail "two environments on two threads per rank exit with $code, not 2"
echo "$err" | grep -q -- "--threads 1" || fail "the refusal of parallel environments does not name the fix: $err"
echo "MPI train check: bad input and commands that do not run on ranks exit 2"
ls "$TMPDIR" | grep -q "^hgym-rank" && fail "a rank left its scratch folder ($(ls "$TMPDIR" | grep "^hgym-rank" | head -1))"
exit 0
