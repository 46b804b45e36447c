#!/usr/bin/env bash
# Runs every test program in $1 (default build/tests) and adds up their counts.
# The last line is "N passed, M failed, K skipped" (a skip is a test that cannot
# run here, as under a sanitizer; it does not fail the run); the exit status is
# non-zero on failure. A program that crashes or prints no summary counts as
# one failed test, and so does a folder with no test program in it.
#
# The programs run $WX_TEST_JOBS at a time (default: the number of cores), the
# longest of the last run first ($1/.times keeps each program's seconds), so
# that the whole-scene programs overlap the many short ones; each program's
# output is printed whole, in name order, when it has finished. Before the
# total come the ten slowest tests (each test of a second or more prints its
# time).
set -u
dir=${1:-build/tests}
jobs=${WX_TEST_JOBS:-$(nproc 2>/dev/null || echo 1)}
[ "$jobs" -ge 1 ] 2>/dev/null || jobs=1
total_pass=0
total_fail=0
total_skip=0
export GALLIUM_DRIVER=llvmpipe
logs=$(mktemp -d)
trap 'rm -rf "$logs"' EXIT

programs=()
for prog in "$dir"/test_*; do
    [ -x "$prog" ] && programs+=("$prog")
done

# The order to start them in: the longest of the last run first, new ones
# (no time yet) before the known short ones. make test-fast (WX_FAST) keeps its
# own times: the whole-scene tests take no time there.
times_file=$dir/.times
case ${WX_FAST:-0} in 0 | "") ;; *) times_file=$dir/.times-fast ;; esac
# With no times (a first run, as in CI), the programs of whole-scene runs
# start first, the longest first.
guess="test_shipped_scenes 3000 test_analytic 2000 test_run 2000 test_masks 2000 test_preset 2000"
start_order=$(for prog in ${programs[@]+"${programs[@]}"}; do
    name=$(basename "$prog")
    seconds=$(awk -v n="$name" '$1 == n { print $2 }' "$times_file" 2>/dev/null)
    if [ -z "$seconds" ]; then
        seconds=$(echo "$guess" | awk -v n="$name" '{ for (i = 1; i < NF; i += 2) if ($i == n) print $(i + 1) }')
    fi
    echo "${seconds:-1000} $prog"
done | sort -k1,1nr -k2 | cut -d' ' -f2-)

# Starts every program, at most $jobs at once; each leaves NAME.log, then
# NAME.status (its exit status) and NAME.seconds.
(
    while IFS= read -r prog; do
        [ -n "$prog" ] || continue
        while [ "$(jobs -rp | wc -l)" -ge "$jobs" ]; do
            wait -n
        done
        name=$(basename "$prog")
        (
            t0=$SECONDS
            "$prog" >"$logs/$name.log" 2>&1
            status=$?
            echo $((SECONDS - t0)) >"$logs/$name.seconds"
            echo "$status" >"$logs/$name.status"
        ) &
    done <<<"$start_order"
    wait
) &
runner=$!

: >"$logs/times"
for prog in ${programs[@]+"${programs[@]}"}; do
    name=$(basename "$prog")
    echo "== $name"
    while [ ! -e "$logs/$name.status" ]; do
        if ! kill -0 "$runner" 2>/dev/null && [ ! -e "$logs/$name.status" ]; then
            break
        fi
        sleep 0.2
    done
    cat "$logs/$name.log" 2>/dev/null
    status=$(cat "$logs/$name.status" 2>/dev/null || echo 255)
    seconds=$(cat "$logs/$name.seconds" 2>/dev/null || echo 0)
    echo "$name $seconds" >>"$logs/times"
    echo "   $name took $seconds s"
    summary=$(grep -E '^[0-9]+ passed, [0-9]+ failed(, [0-9]+ skipped)?$' "$logs/$name.log" 2>/dev/null | tail -n 1)
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
wait "$runner" 2>/dev/null
cp "$logs/times" "$times_file" 2>/dev/null
if [ "${#programs[@]}" -eq 0 ]; then
    echo "   no test program in $dir"
    total_fail=$((total_fail + 1))
fi
slowest=$(for prog in ${programs[@]+"${programs[@]}"}; do
    name=$(basename "$prog")
    sed -nE "s/^  (ok|FAIL)  +([A-Za-z0-9_]+) \(([0-9.]+) s\)$/\3 $name \2/p" "$logs/$name.log" 2>/dev/null
done | sort -k1,1nr | head -n 10)
if [ -n "$slowest" ]; then
    echo "== the slowest tests (seconds, program, test)"
    echo "$slowest" | sed 's/^/   /'
fi
echo "$total_pass passed, $total_fail failed, $total_skip skipped"
[ "$total_fail" -eq 0 ]
