#!/usr/bin/env bash
# make test-cluster: the 2 x 2 tiles of a street as a Slurm job array on a real,
# one-node Slurm cluster on this machine (issue 29 item 3; docs/cluster.md).
# Usage: tests/cluster/run.sh [BUILD]   (BUILD: the build folder, default build)
# Starts munged, slurmctld and slurmd (Debian's; the Makefile installs them) in
# the background with tests/cluster/slurm.conf, every file of theirs in a temp
# folder, and stops them on exit whatever happens. Cuts tests/cluster/street.xml
# into 2 x 2 tiles with `weathering tiles --slurm` in BUILD/cluster-test/,
# submits them with the submit.sh that wrote (the job array, then the merge with
# afterok), polls squeue until both are gone (5 minutes at most) and checks that
# every job completed, that the merge wrote its outputs (byte-identical to a
# merge run here) and that the tiles' particles add up to the whole scene's.
# A cluster that cannot start fails the test with the daemons' logs.
# The last line is "N passed, M failed"; the exit status is non-zero on failure.
set -euo pipefail
cd "$(dirname "$0")/../.."
build=${1:-build}
weathering=$(cd "$build" && pwd)/weathering
out=$build/cluster-test
timeout=${WX_CLUSTER_TIMEOUT:-300}
export GALLIUM_DRIVER=llvmpipe
t0=$SECONDS
pass=0
fail=0
ok() {
    echo "ok   $*"
    pass=$((pass + 1))
}
bad() {
    echo "FAIL $*"
    fail=$((fail + 1))
}
finish() {
    echo "== test-cluster took $((SECONDS - t0)) s"
    echo "$pass passed, $fail failed"
    [ "$fail" -eq 0 ]
}

for tool in munged mungekey slurmctld slurmd sbatch squeue scontrol scancel; do
    if ! command -v "$tool" >/dev/null; then
        bad "$tool is missing: make test-cluster installs munge, slurmctld, slurmd and slurm-client"
        finish
        exit 1
    fi
done

# The daemons' folder: key, sockets, pid files, state, spool and logs. munged
# wants its socket's folder open to all and its key's folder closed to others.
tmp=$(mktemp -d /tmp/weathering-cluster.XXXXXX)
chmod 755 "$tmp"
mkdir -p "$tmp/run" "$tmp/munge" "$tmp/state" "$tmp/spool" "$tmp/log"
chmod 700 "$tmp/munge"
pids=()
jobs_submitted=()
# Each daemon's log file, or what it printed when it could not open one.
show_logs() {
    local d f
    for d in munged slurmctld slurmd; do
        f=$tmp/log/$d.log
        [ -s "$f" ] || f=$tmp/log/$d.out
        [ -s "$f" ] || continue
        echo "---- $f (last 40 lines; all in $out/daemon-logs/)"
        tail -n 40 "$f"
    done
}
stop() {
    local status=$?
    set +e
    # Jobs still queued or running are cancelled, and given 20 s to end while
    # slurmd is there to stop their steps.
    if [ ${#jobs_submitted[@]} -gt 0 ]; then
        local ids
        ids=$(IFS=,; echo "${jobs_submitted[*]}")
        scancel "${jobs_submitted[@]}" 2>/dev/null
        for _ in $(seq 40); do
            [ -n "$(squeue -h -j "$ids" -t PD,CF,R,CG,S -o %i 2>/dev/null)" ] || break
            sleep 0.5
        done
    fi
    # Last started, first stopped: slurmd, slurmctld, munged.
    for ((i = ${#pids[@]} - 1; i >= 0; i--)); do
        kill "${pids[i]}" 2>/dev/null
    done
    for pid in "${pids[@]}"; do
        for _ in $(seq 50); do
            kill -0 "$pid" 2>/dev/null || break
            sleep 0.1
        done
        kill -KILL "$pid" 2>/dev/null
        wait "$pid" 2>/dev/null
    done
    # A job step whose slurmd went first waits for it for ever, ignoring
    # SIGTERM: ours are the slurmstepd processes with a file open in $tmp.
    local p fd
    for p in /proc/[0-9]*; do
        [ "$(cat "$p/comm" 2>/dev/null)" = slurmstepd ] || continue
        for fd in "$p"/fd/*; do
            case $(readlink "$fd" 2>/dev/null) in
            "$tmp"/*)
                echo "stopping a job step left behind: pid ${p#/proc/}"
                kill -KILL "${p#/proc/}" 2>/dev/null
                break
                ;;
            esac
        done
    done
    mkdir -p "$out"
    rm -rf "$out/daemon-logs"
    cp -r "$tmp/log" "$out/daemon-logs" 2>/dev/null
    rm -rf "$tmp"
    exit "$status"
}
trap stop EXIT
# Fails the test now: the daemons' logs, then the summary.
die() {
    bad "$*"
    show_logs
    finish || true
    exit 1
}

# Two free ports on the loopback (nothing answers there).
free_port() {
    local p=$1
    while (exec 3<>"/dev/tcp/127.0.0.1/$p") 2>/dev/null; do
        p=$((p + 1))
    done
    echo "$p"
}
ctld_port=$(free_port $((20000 + $$ % 20000)))
slurmd_port=$(free_port $((ctld_port + 1)))
host=$(hostname -s)
sed -e "s|@TMP@|$tmp|g" -e "s|@HOST@|$host|g" -e "s|@CPUS@|$(nproc)|g" \
    -e "s|@CTLD_PORT@|$ctld_port|g" -e "s|@SLURMD_PORT@|$slurmd_port|g" \
    tests/cluster/slurm.conf > "$tmp/slurm.conf"
export SLURM_CONF=$tmp/slurm.conf

echo "== a one-node cluster on $host: munged, slurmctld (port $ctld_port), slurmd (port $slurmd_port) in $tmp"
mungekey -c -k "$tmp/munge/munge.key" > "$tmp/log/mungekey.out" 2>&1 || die "mungekey could not make a key"
munged -F --socket="$tmp/run/munge.socket" --key-file="$tmp/munge/munge.key" \
    --pid-file="$tmp/run/munged.pid" --seed-file="$tmp/munge/munged.seed" \
    --log-file="$tmp/log/munged.log" > "$tmp/log/munged.out" 2>&1 &
pids+=($!)
for _ in $(seq 50); do
    [ -S "$tmp/run/munge.socket" ] && break
    sleep 0.1
done
[ -S "$tmp/run/munge.socket" ] || die "munged did not start"
slurmctld -D -f "$tmp/slurm.conf" > "$tmp/log/slurmctld.out" 2>&1 &
pids+=($!)
slurmd -D -f "$tmp/slurm.conf" -N "$host" > "$tmp/log/slurmd.out" 2>&1 &
pids+=($!)
state=""
for _ in $(seq 60); do
    state=$(sinfo -h -n "$host" -o %t 2>/dev/null || true)
    [ "$state" = idle ] && break
    for pid in "${pids[@]}"; do
        kill -0 "$pid" 2>/dev/null || die "a daemon (pid $pid) stopped while the cluster started"
    done
    sleep 0.5
done
[ "$state" = idle ] || die "the node $host is not idle after 30 s (state '$state')"
ok "the cluster started: node $host idle ($(sinfo -h -n "$host" -o %c) CPUs)"

# The tiles, with the Slurm scripts, and the whole scene's particles to match.
rm -rf "$out"
mkdir -p "$out"
cp tests/cluster/street.xml tests/cluster/street.obj "$out/"
(cd "$out" && "$weathering" tiles street.xml --tiles 2 2 --halo 4 --out tiles --slurm -q) ||
    die "weathering tiles street.xml --tiles 2 2 --halo 4 --out tiles --slurm"
(cd "$out" && "$weathering" run street.xml --out whole --stats whole.json -q) ||
    die "weathering run street.xml --out whole --stats whole.json"
scenes=("$out"/tiles/tile_*.xml)
ok "weathering tiles wrote ${#scenes[@]} tile scenes and the Slurm scripts"

submitted=$("$out/tiles/submit.sh") || die "tiles/submit.sh: sbatch refused the jobs"
echo "$submitted"
tiles_job=$(echo "$submitted" | sed -n 's/^tiles: job \([0-9]*\); merge: job \([0-9]*\)$/\1/p')
merge_job=$(echo "$submitted" | sed -n 's/^tiles: job \([0-9]*\); merge: job \([0-9]*\)$/\2/p')
if [ -z "$tiles_job" ] || [ -z "$merge_job" ]; then
    die "submit.sh did not name its two jobs"
fi
jobs_submitted=("$tiles_job" "$merge_job")
ok "submit.sh submitted the job array $tiles_job and the merge $merge_job (afterok)"

# No accounting, so no sacct: squeue lists the jobs until they end, and scontrol
# keeps their end state for MinJobAge seconds.
t=$SECONDS
while [ -n "$(squeue -h -t PD,CF,R,CG,S -j "$tiles_job,$merge_job" -o %i 2>/dev/null)" ]; do
    [ $((SECONDS - t)) -lt "$timeout" ] || {
        squeue -j "$tiles_job,$merge_job"
        die "the jobs did not end within $timeout s"
    }
    sleep 1
done
jobs_submitted=()
ok "both jobs ended in $((SECONDS - t)) s"
ended=$(scontrol -o show job "$tiles_job" | grep -c 'JobState=COMPLETED .*ExitCode=0:0' || true)
if [ "$ended" -eq 4 ]; then
    ok "the 4 tasks of the job array completed with exit status 0"
else
    scontrol -o show job "$tiles_job" | grep -o 'ArrayTaskId=[^ ]*\|JobState=[^ ]*\|ExitCode=[^ ]*' |
        paste -d ' ' - - - || true
    bad "$ended of the 4 tasks of the job array completed with exit status 0"
fi
if scontrol -o show job "$merge_job" | grep -q 'JobState=COMPLETED .*ExitCode=0:0'; then
    ok "the merge job completed with exit status 0"
else
    scontrol -o show job "$merge_job" | grep -o 'JobState=[^ ]*\|Reason=[^ ]*\|ExitCode=[^ ]*' |
        paste -d ' ' - - - || true
    bad "the merge job did not complete"
fi
for log in "$out"/tiles/logs/*.log; do
    if [ -s "$log" ]; then
        echo "---- $log"
        cat "$log"
    fi
done

# The merge's outputs, and the same merge run here: byte-identical.
missing=""
for f in mask.exr mask.png street_texture.exr street_texture.png; do
    [ -s "$out/tiles/merged/$f" ] || missing="$missing $f"
done
if [ -z "$missing" ]; then
    ok "the merge wrote mask.exr, mask.png, street_texture.exr and street_texture.png"
else
    bad "the merge did not write:$missing"
fi
if (cd "$out/tiles" && "$weathering" merge . --out merged-here -q) &&
    cmp "$out/tiles/merged/mask.exr" "$out/tiles/merged-here/mask.exr" &&
    cmp "$out/tiles/merged/street_texture.exr" "$out/tiles/merged-here/street_texture.exr"; then
    ok "the cluster's merge equals weathering merge run here, byte for byte"
else
    bad "the cluster's merge differs from weathering merge run here"
fi

# No particle counted twice or lost: the tiles' tile_particles add up to the
# whole run's particles_emitted (rate 40000 x 1 s).
# "KEY": N of a --stats file; nothing when the file or the key is missing.
stat_value() { { sed -n "s/^ *\"$2\": *\([0-9]*\),*$/\1/p" "$1" 2>/dev/null || true; } | head -n 1; }
sum=0
for ix in 0 1; do
    for iz in 0 1; do
        n=$(stat_value "$out/tiles/tile_${ix}_${iz}.json" tile_particles)
        echo "     tile_${ix}_${iz}: ${n:-no tile_particles in its stats file} particles"
        sum=$((sum + ${n:-0}))
    done
done
whole=$(stat_value "$out/whole.json" particles_emitted)
if [ "$sum" -eq "${whole:--1}" ] && [ "$sum" -eq 40000 ]; then
    ok "the tiles' particles add up to the whole scene's: $sum"
else
    bad "the tiles' particles add up to $sum, the whole scene emits ${whole:-?} (40000 expected)"
fi
[ "$fail" -eq 0 ] || show_logs
finish
