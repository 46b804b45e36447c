#!/usr/bin/env bash
# run.sh BUILD MPI_BUILD: `make test-mpi` (docs/scale-out.md). Small scenes run
# by the normal program (BUILD/weathering) and by the MPI one
# (MPI_BUILD/weathering) under `mpirun -np N` for N = 1, 2, 3 and 4, with more
# ranks than cores (--oversubscribe). Each MPI run must write the same files,
# byte for byte (SHA-256), as the normal run, and rank 0 alone may print: what
# the normal run prints. Outputs in BUILD/mpi-test/. One check
# per scene and rank count, and one for the printing; the last line is
# "N passed, M failed", the exit status non-zero on failure.
#
# The scenes: the two tiny ones of tests/sanitize/ (maps given; maps baked) and
# tests/mpi/tank.xml (four substances, three iterations with ageing and a frame
# after each, two cameras of two depth layers, derived masks).
set -u
build=${1:-build}
mpi_build=${2:-$build-mpi}
cd "$(dirname "$0")/../.."
work=$build/mpi-test
rm -rf "$work"
mkdir -p "$work"
export GALLIUM_DRIVER=llvmpipe
# Open MPI refuses root unless told (CI runs as root).
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
mpirun=(mpirun --oversubscribe)
scenes=(tests/sanitize/valgrind.xml tests/sanitize/valgrind_bake.xml tests/mpi/tank.xml)
pass=0
fail=0

# SHA-256 of every file under $1, by path relative to it.
hashes() {
    (cd "$1" && find . -type f | LC_ALL=C sort | xargs sha256sum)
}

for scene in "${scenes[@]}"; do
    name=$(basename "$scene" .xml)
    ref=$work/$name/normal
    if ! "$build/weathering" run "$scene" --out "$ref" -q; then
        echo "FAIL $name: the normal program failed"
        fail=$((fail + 4))
        continue
    fi
    hashes "$ref" > "$work/$name/normal.sha256"
    for np in 1 2 3 4; do
        out=$work/$name/np$np
        t0=$(date +%s.%N)
        if ! "${mpirun[@]}" -np "$np" "$mpi_build/weathering" run "$scene" --out "$out" -q \
            > "$work/$name/np$np.log" 2>&1; then
            echo "FAIL $name -np $np: mpirun failed"
            tail -n 20 "$work/$name/np$np.log"
            fail=$((fail + 1))
            continue
        fi
        seconds=$(echo "$(date +%s.%N) - $t0" | bc)
        hashes "$out" > "$work/$name/np$np.sha256"
        if cmp -s "$work/$name/normal.sha256" "$work/$name/np$np.sha256"; then
            printf 'ok   %-16s -np %d: %d files as the normal run (%.1f s)\n' "$name" "$np" \
                "$(wc -l < "$work/$name/normal.sha256")" "$seconds"
            pass=$((pass + 1))
        else
            echo "FAIL $name -np $np: outputs differ from the normal run's:"
            diff "$work/$name/normal.sha256" "$work/$name/np$np.sha256" | head -n 20
            fail=$((fail + 1))
        fi
    done
done

# Rank 0 alone prints: with 3 ranks, what the normal program prints (stdout
# line for line but the times; stderr, its warnings, byte for byte).
scene=tests/sanitize/valgrind_bake.xml
"$build/weathering" run "$scene" --out "$work/print0" > "$work/print0.out" 2> "$work/print0.err"
if "${mpirun[@]}" -np 3 "$mpi_build/weathering" run "$scene" --out "$work/print" \
    > "$work/print.out" 2> "$work/print.err" &&
    [ "$(grep -c '^run done in' "$work/print.out")" -eq 1 ] &&
    [ "$(wc -l < "$work/print.out")" -eq "$(wc -l < "$work/print0.out")" ] &&
    cmp -s "$work/print0.err" "$work/print.err"; then
    echo "ok   only rank 0 prints"
    pass=$((pass + 1))
else
    echo "FAIL only rank 0 prints: stdout and stderr of 3 ranks were:"
    cat "$work/print.out" "$work/print.err"
    fail=$((fail + 1))
fi

echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
