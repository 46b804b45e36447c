#!/usr/bin/env bash
# Runs every test program in $1 (default build/tests) and adds up their counts.
# The last line is "N passed, M failed, K skipped" (a skip is a test that cannot
# run here, as under a sanitizer; it does not fail the run); the exit status is
# non-zero on failure. A program that crashes or prints no summary counts as
# one failed test, and so does a folder with no test program in it.
set -u
dir=${1:-build/tests}
total_pass=0
total_fail=0
total_skip=0
programs=0
export GALLIUM_DRIVER=llvmpipe
for prog in "$dir"/test_*; do
    [ -x "$prog" ] || continue
    name=$(basename "$prog")
    programs=$((programs + 1))
    echo "== $name"
    log=$(mktemp)
    t0=$SECONDS
    "$prog" 2>&1 | tee "$log"
    status=${PIPESTATUS[0]}
    echo "   $name took $((SECONDS - t0)) s"
    summary=$(grep -E '^[0-9]+ passed, [0-9]+ failed(, [0-9]+ skipped)?$' "$log" | tail -n 1)
    rm -f "$log"
    if [ -z "$summary" ]; then
        echo "   $name ended without a summary (exit status $status)"
        total_fail=$((total_fail + 1))
        continue
    fi
    p=${summary%% passed*}
    f=${summary#*, }
    f=${f%% failed*}
    k=0
    case $summary in *skipped) k=${summary##*, }; k=${k%% skipped} ;; esac
    total_pass=$((total_pass + p))
    total_fail=$((total_fail + f))
    total_skip=$((total_skip + k))
    if [ "$status" -ne 0 ] && [ "$f" -eq 0 ]; then
        echo "   $name exited with status $status"
        total_fail=$((total_fail + 1))
    fi
done
if [ "$programs" -eq 0 ]; then
    echo "   no test program in $dir"
    total_fail=$((total_fail + 1))
fi
echo "$total_pass passed, $total_fail failed, $total_skip skipped"
[ "$total_fail" -eq 0 ]
