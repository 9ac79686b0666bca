#!/bin/sh
# The random walk's light through back-lit slabs over a grid of albedo and
# thickness / mean free path (blender_scripts/measure_transmission.py's
# slab mode), for scripts/fit_transmission4.py:
#
#   sh scripts/measure_transmission4.sh BLENDER OUT [RESOLUTION] [RW_SPP] \
#       [METHOD] [SETS] [LIGHT]
#
# METHOD: RANDOM_WALK_SKIN (the default) or RANDOM_WALK (4.x's plain Random
# Walk, the default of a new material); SETS: which of a - e to run (all);
# LIGHT: back (the default: transmission, slab.json) or front (the same
# slabs lit only from the front: reflected light against thickness,
# slab_front.json).
#
# Four slab colours, each channel's albedo paired with a radius (the slab's
# 1, 0.5, 0.25 times Subsurface) so that the three mean free paths are
# close; per colour a list of thicknesses in units of that path.
# Writes OUT/SET/slab.json per colour (a - d the grid, e a check).
set -eu
blender=$1
out=$2
res=${3:-64x64}
spp=${4:-1024}
method=${5:-RANDOM_WALK_SKIN}
sets=${6:-abcde}
light=${7:-back}
root=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$out"
"$blender" -b --factory-startup --python-exit-code 1 \
	--python "$root/blender_scripts/build_scene.py" -- --kind slab \
	--out "$out/slab.blend" >"$out/build.log" 2>&1
# name  albedo R,G,B  Subsurface  mean free path (m)  t / l
run() {
	name=$1 albedo=$2 sub=$3 l=$4
	shift 4
	case $sets in *"$name"*) ;; *) return 0 ;; esac
	ts=$(for x in "$@"; do echo "$x $l"; done |
		awk '{printf "%s%.6g", (NR > 1 ? "," : ""), $1 * $2}')
	SSS_LIB=$root/build/libsss.so "$blender" -b --factory-startup \
		--python-exit-code 1 \
		--python "$root/blender_scripts/measure_transmission.py" -- \
		--scene "$out/slab.blend" --out "$out/$name" --slab-sweep "$ts" \
		--slab-subsurface "$sub" --slab-albedo "$albedo" \
		--slab-method "$method" --slab-light "$light" \
		--resolution "$res" --rw-samples "$spp" --samples 128 \
		>"$out/$name.log" 2>&1 || { tail -n 30 "$out/$name.log"; exit 1; }
}
low="0.25 0.5 1 1.5 2 3 4 5.5 7.5 10 14"
run a 0.4,0.2,0.05 0.02 0.0072 $low
run b 0.5,0.3,0.1 0.02 0.0053 $low
run c 0.8,0.7,0.6 0.05 0.0030 0.25 0.5 1 2 3 4.5 6.5 9 13 18 25 35
run d 0.95,0.9,0.8 0.05 0.00085 0.25 0.5 1 2 4 7 11 16 23 32 45 64 90
# The head scene's skin colour (build_scene.py --kind head), Subsurface
# 0.08: a check between the grid's albedos, not fitted.
run e 0.8,0.55,0.45 0.08 0.0068 0.25 0.5 1 2 3 4.5 6.5 9 13 18
