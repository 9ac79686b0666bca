# One farm task: a chunk of frames of a Blender shot with screen-space SSS.
#
#   bash sss_chunk.sh SHOT.blend OUTPUT_DIR FRAMES SAMPLES METHOD BLENDER SSS \
#       CHECKOUT [ADDON_PY]
#
# FRAMES: 1-10 or 1-3,7. SAMPLES: 0 keeps the scene's. METHOD: scene (the
# .blend's) or one of sss --help's. BLENDER, SSS: commands on PATH or full
# paths. CHECKOUT: a libsss checkout built with make, or "" for the add-on
# installed in Blender. ADDON_PY: sss_addon.py (default: beside this file).
# Blender renders the passes of the frames that have neither passes nor
# output (OUTPUT_DIR/passes/NAME_####.exr and NAME_####_scene.json), then
# sss --resume scatters every frame into OUTPUT_DIR/NAME_####.exr: run again,
# it redoes only what is missing. Exit status 1 when a frame failed (its
# message is printed); the other frames are still written. The OpenJD
# template embeds this file (tests/farm/test_farm.py checks the copy).
set -u
blend=$1 outdir=$2 frames=$3 samples=$4 method=$5 blender=$6 sss=$7
checkout=$8 addon=${9:-$(dirname "$0")/sss_addon.py}
name=$(basename "$blend" .blend)
passes="$outdir/passes/${name}_####.exr"
output="$outdir/${name}_####.exr"
at() { printf '%s%04d%s' "${1%%####*}" "$2" "${1##*####}"; }
list=()
IFS=, read -ra parts <<<"$frames"
for part in "${parts[@]}"; do
    for ((f = ${part%%-*}; f <= ${part##*-}; f++)); do list+=("$f"); done
done
render=""
for f in "${list[@]}"; do
    [ -e "$(at "$passes" "$f")" ] || [ -e "$(at "$output" "$f")" ] ||
        render="$render,$f"
done
status=0
if [ -n "$render" ]; then
    opts=()
    [ "$samples" -gt 0 ] && opts+=(--samples "$samples")
    [ "$method" != scene ] && opts+=(--method "$method")
    "$blender" -b "$blend" --python-exit-code 1 --python "$addon" -- \
        "$checkout" --passes "$passes" --done "$output" \
        --frames "${render#,}" "${opts[@]}" || status=1
else
    echo "frames $frames: every frame has its passes or output; no render"
fi
for f in "${list[@]}"; do
    p=$(at "$passes" "$f") o=$(at "$output" "$f")
    if [ -e "$p" ]; then
        "$sss" "$p" -o "$o" --scene "${p%.exr}_scene.json" --resume ||
            status=1
    elif [ -e "$o" ]; then
        echo "$o: exists (its passes were removed), skipped"
    else
        echo "frame $f: no passes to scatter (the render failed)" >&2
        status=1
    fi
done
exit $status
