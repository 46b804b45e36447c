#!/bin/sh
# regather.sh SRC DST BUILD: the gather's share of issue 25's turning test,
# fast. SRC is a folder tests/tools/invariance.sh left (BUILD/invariance/, with
# its four runs model1, model2, turned1, turned2 and their scenes); it is
# copied to DST, each run's folder is gathered again by BUILD/weathering
# (`weathering gather`, which reads the dirt maps the runs wrote: the same
# deposits, no flight), and the seeds' and orientations' differences are
# printed as invariance.sh prints them (tests/tools/invariance_compare.sh),
# each line with T = sqrt(orientations^2 - seeds^2), the part the turn adds
# to the seeds' noise. A gather variant (a temporary switch in a build kept
# aside) is judged in about 35 s for Spot instead of the two minutes of a
# whole test; the flight stays as SRC's build made it (docs/performance.md,
# "Turned, shifted, re-gathered").
set -eu
src=$1
dst=$2
build=$3
case $build in /*) ;; *) build=$(pwd)/$build ;; esac
tools=$(cd "$(dirname "$0")/.." && pwd)
rm -rf "$dst"
cp -r "$src" "$dst"
cd "$dst"
for m in model turned; do
    for s in 1 2; do
        "$build/weathering" gather "$m.xml" --out "$m$s" -q
    done
done
# As invariance.sh compares: its ABSORB=1 runs on the exposure's dirt.
channel=Y
grep -q 'absorption="1"' model.xml && channel=dirt.Y
sh "$tools/invariance_compare.sh" . "$build" "$channel" T
