#!/bin/sh
# seed.sh TARGET CORPUS: copies the shipped inputs of a fuzz target into its
# corpus folder (docs/reliability.md). Run from the repository's root.
set -eu
target=$1
corpus=$2
mkdir -p "$corpus"
case "$target" in
    fuzz_scene) seeds="xml_scenes/*.xml tests/data/*.xml tests/bad/*.xml tests/bad/run/*.xml tests/bad/mesh/*.xml tests/bad/gather/*.xml" ;;
    fuzz_exr) seeds="maps/*.exr tests/data/*.exr tests/bad/maps/*.exr" ;;
    *) echo "seed.sh: unknown target $target" >&2; exit 2 ;;
esac
for f in $seeds; do
    [ -f "$f" ] || continue
    # One file per distinct seed, named after its path.
    cp "$f" "$corpus/seed_$(echo "$f" | tr '/' '_')"
done
