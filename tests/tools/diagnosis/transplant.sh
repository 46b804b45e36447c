#!/bin/sh
# transplant.sh BUILD: which part of what turns with the model comes from the
# gather (docs/performance.md, "What turns with the model: the flight or the
# gather"). BUILD is a build of tests/tools/diagnosis/transplant.patch applied
# in a worktree of its own (never the project's build/), after
# `sh tests/tools/invariance.sh BUILD MESH` has left BUILD/invariance.
#
# For seeds 1 and 2 it runs the model's scene again, dumping every texel's dirt
# and hits at the end of the simulation as world points (WX_DUMP), four points
# a texel at random places in it (WX_DUMP_JITTER=4: points on the texel
# centres would be a grid, and a grid resampled by another one turned 30
# degrees makes a moire that both seeds share). It puts those same deposits,
# turned 30 degrees like the model, into the turned scene's maps through its
# collider (WX_REPLAY, no particle flies), and also, not turned, into the
# model's own maps (the control), then gathers each. What the turned replay
# differs from the control is what the gather and the texture do with the
# same deposits in the other camera grid; common_part.py keeps the part both
# seeds share. Printed: the simulated orientations' part (invariance.sh's own
# runs, which no switch touched), the control's against the model run here
# (the cost of the replay itself) and the turned replay's against the
# control. Extra arguments are environment settings every run here gets (the
# patch's switches, listed at its top: WX_NOCLEAN=1, WX_TEXP=P, WX_MAXR=F,
# ...).
set -eu
build=$1
shift
dir=$build/invariance
here=$(cd "$(dirname "$0")" && pwd)
[ -f "$dir/model.xml" ] && [ -f "$dir/model2/model_texture.exr" ] &&
    [ -f "$dir/turned2/turned_texture.exr" ] ||
    { echo "transplant.sh: run tests/tools/invariance.sh $build MESH first" >&2; exit 2; }
read cx cz < "$dir/centre"
out=$dir/transplant
rm -rf "$out"
mkdir -p "$out"
sed -e 's/rate="[0-9.e+-]*"/rate="2"/' "$dir/turned.xml" > "$dir/turned_replay.xml"
sed -e 's/rate="[0-9.e+-]*"/rate="2"/' "$dir/model.xml" > "$dir/model_replay.xml"
ex=$build/tools/exr_channel
channel=Y
grep -q 'absorption="1"' "$dir/model.xml" && channel=dirt.Y
for s in 1 2; do
    echo "transplant: seed $s" >&2
    (cd "$dir" && env "$@" WX_DUMP="$out/dump$s.bin" WX_DUMP_JITTER=4 WX_DUMP_SEED="$s" \
        ../weathering run model.xml --out "transplant/model$s" --seed "$s" -q)
    (cd "$dir" && env "$@" WX_CX="$cx" WX_CZ="$cz" WX_ANGLE=30 WX_REPLAY="$out/dump$s.bin" \
        ../weathering run turned_replay.xml --out "transplant/replay$s" -q)
    (cd "$dir" && env "$@" WX_CX="$cx" WX_CZ="$cz" WX_ANGLE=0 WX_REPLAY="$out/dump$s.bin" \
        ../weathering run model_replay.xml --out "transplant/control$s" -q)
    for r in simulated model replay control turned; do
        case $r in
        simulated) f=$dir/model$s/model_texture.exr ;;
        model) f=$out/model$s/model_texture.exr ;;
        replay) f=$out/replay$s/turned_texture.exr ;;
        control) f=$out/control$s/model_texture.exr ;;
        turned) f=$dir/turned$s/turned_texture.exr ;;
        esac
        $ex "$f" "$channel" "$out/$r$s.$channel.f32" > /dev/null
        $ex "$f" seen "$out/$r$s.seen.f32" > /dev/null
    done
done
echo "the model turned, as simulated (turned - model, seeds 1 and 2):"
python3 "$here/common_part.py" "$out/turned1" "$out/simulated1" "$out/turned2" "$out/simulated2" "$channel"
echo "the deposits put back in the model's own grid (control - model):"
python3 "$here/common_part.py" "$out/control1" "$out/model1" "$out/control2" "$out/model2" "$channel"
echo "the same deposits gathered in the turned grid (replay - control):"
python3 "$here/common_part.py" "$out/replay1" "$out/control1" "$out/replay2" "$out/control2" "$channel"
