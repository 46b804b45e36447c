#!/usr/bin/env bash
# output_hashes.sh [BUILD] > hashes.txt: SHA-256 of every output file of every
# shipped scene (`make run SCENE=...`, all cores), of the two small runnable test
# scenes in tests/sanitize/, and of the fixtures the tools regenerate (the
# thesis box maps, the default building's mesh, the bad maps). A restructuring
# that changes no behaviour leaves this list unchanged (issue 14). Run from the
# repository's root; writes into $BUILD/hashes/.
set -euo pipefail
build=${1:-build}
work=$build/hashes
rm -rf "$work"
mkdir -p "$work/maps" "$work/meshes" "$work/bad_maps"
make -s BUILD="$build" "$build/weathering" "$build/libweathering.a" >&2
for scene in xml_scenes/*.xml; do
    name=$(basename "$scene" .xml)
    "$build/weathering" run "$scene" --out "$work/run/$name" -q
done
for scene in tests/sanitize/valgrind.xml tests/sanitize/valgrind_bake.xml; do
    name=$(basename "$scene" .xml)
    "$build/weathering" run "$scene" --out "$work/run/$name" -q
done
libs="-lOpenEXRCore-3_1 -lxml2 -lassimp -lOSMesa -lpng -lm -lpthread"
cc -std=c11 -O2 -D_POSIX_C_SOURCE=200809L $(ls -d src src/* 2>/dev/null | grep -v '\.' | sed 's/^/-I/') \
    -I/usr/include/OpenEXR tests/tools/gen_thesis_maps.c "$build/libweathering.a" $libs \
    -o "$work/gen_thesis_maps"
"$work/gen_thesis_maps" "$work/maps" > /dev/null
cc -o "$work/gen_building" tests/tools/gen_building.c
"$work/gen_building" "$work/meshes" > /dev/null
cc -std=c11 -D_POSIX_C_SOURCE=200809L $(ls -d src src/* 2>/dev/null | grep -v '\.' | sed 's/^/-I/') \
    -I/usr/include/OpenEXR tests/bad/maps/make_bad_maps.c "$build/libweathering.a" $libs \
    -o "$work/make_bad_maps"
"$work/make_bad_maps" "$work/bad_maps" > /dev/null
(cd "$work" && find run maps meshes bad_maps -type f | LC_ALL=C sort | xargs sha256sum)
