#!/usr/bin/env bash
# `make mpi`: the same validation case in one process (`hgym`) and split over 2 and 3 MPI ranks
# (`hgym-mpi` under mpirun); the force history of every step (forces.csv, shortest round-trip
# decimals) and the measured values must be identical. Exit 1 if they differ.
set -euo pipefail
: "${HGYM:?path to hgym}" "${HGYM_MPI:?path to hgym-mpi}" "${MPIRUN:=mpirun --allow-run-as-root --oversubscribe --bind-to none}"
case_file=${1:-tests/cases/sphere_mpi.toml}
name=$(sed -n 's/^name = "\(.*\)"/\1/p' "$case_file" | head -1)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
measured() { python3 -c 'import json,sys; r=json.load(open(sys.argv[1])); print(json.dumps([(q["name"], q["measured"]) for q in r["quantities"]]))' "$1"; }

"$HGYM" validate --case "$case_file" --level coarse --out "$work/one" >/dev/null
for np in 2 3; do
    $MPIRUN -np $np "$HGYM_MPI" validate --case "$case_file" --level coarse --out "$work/np$np" >/dev/null
    if ! cmp -s "$work/one/$name/forces.csv" "$work/np$np/$name/forces.csv"; then
        echo "MPI check FAILED: $np ranks give other forces than one process ($name/forces.csv)"
        diff <(head -5 "$work/one/$name/forces.csv") <(head -5 "$work/np$np/$name/forces.csv") || true
        exit 1
    fi
    if [ "$(measured "$work/one/$name.json")" != "$(measured "$work/np$np/$name.json")" ]; then
        echo "MPI check FAILED: $np ranks measure other values than one process"
        exit 1
    fi
    echo "MPI check: $np ranks give bitwise the forces of one process ($(wc -l < "$work/one/$name/forces.csv") samples of $name)"
done
