#!/bin/sh
# Regenerates the seed corpus of tests/fuzz/corpus (already committed; run
# this only to rebuild it): real Blender renders re-encoded with every
# codec OpenEXR 3.1 writes, crafted broken headers (make_crafted.py) and
# scene descriptions. Needs blender, oiiotool and python3.
#
#   sh tests/fuzz/make_corpus.sh [BLENDER]
set -eu
blender=${1:-blender}
root=$(cd "$(dirname "$0")/../.." && pwd)
corpus=$root/tests/fuzz/corpus
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

"$blender" -b --factory-startup --python-exit-code 1 \
	--python "$root/blender_scripts/make_test_scene.py" -- \
	--out "$tmp" --size 16 --samples 1 >"$tmp/blender.log" 2>&1 ||
	{ cat "$tmp/blender.log"; exit 1; }

mkdir -p "$corpus/exr" "$corpus/scene" "$corpus/regressions"

# The three Blender files as they are: render-output naming (float ZIP,
# half PIZ) and File Output node naming.
cp "$tmp/render.exr" "$corpus/exr/blender_render_float_zip.exr"
cp "$tmp/render_half.exr" "$corpus/exr/blender_render_half_piz.exr"
cp "$tmp/fileout.exr" "$corpus/exr/blender_fileout_float_zip.exr"

# Small variants: the passes libsss reads, 8x8 cut from the middle, with
# Blender's pixel types (half light, float Depth and IndexMA).
L=ViewLayer
sub="$L.Combined.R,$L.Combined.G,$L.Combined.B,$L.Combined.A,$L.Depth.Z"
sub="$sub,$L.DiffCol.R,$L.DiffCol.G,$L.DiffCol.B,$L.DiffDir.R,$L.DiffDir.G"
sub="$sub,$L.DiffDir.B,$L.DiffInd.R,$L.DiffInd.G,$L.DiffInd.B,$L.IndexMA.X"
types="-d half -d $L.Depth.Z=float -d $L.IndexMA.X=float"
fsub="DiffCol.R,DiffCol.G,DiffCol.B,DiffDir.R,DiffDir.G,DiffDir.B"
fsub="$fsub,Depth.V,IndexMA.V,Position.X,Position.Y,Position.Z"
for c in none rle zips zip piz pxr24 b44 b44a; do
	# shellcheck disable=SC2086
	oiiotool "$tmp/render_half.exr" --ch "$sub" --cut 8x8+4+4 $types \
		--compression "$c" -o "$corpus/exr/render_8x8_half_$c.exr"
done
for c in none rle zip piz pxr24; do
	oiiotool "$tmp/fileout.exr" --ch "$fsub" --cut 8x8+4+4 -d float \
		--compression "$c" -o "$corpus/exr/fileout_8x8_float_$c.exr"
done
# Tiled (level 0 only is read), a mipmapped texture, an offset data
# window (a border render), and uint channels.
# shellcheck disable=SC2086
oiiotool "$tmp/render_half.exr" --ch "$sub" --cut 16x16 $types --tile 8 8 \
	--compression zip -o "$corpus/exr/render_16x16_tiled8_zip.exr"
# shellcheck disable=SC2086
oiiotool "$tmp/render_half.exr" --ch "$sub" --cut 8x8+4+4 $types \
	--tile 4 4 --compression piz -o "$corpus/exr/render_8x8_tiled4_piz.exr"
oiiotool "$tmp/fileout.exr" --ch "$fsub" --cut 8x8+4+4 -d float --tile 4 4 \
	--compression none -o "$corpus/exr/fileout_8x8_tiled4_none.exr"
oiiotool "$tmp/fileout.exr" --ch "DiffDir.R,DiffDir.G,DiffDir.B" \
	--cut 8x8+4+4 -d half --tile 4 4 --compression rle \
	-otex "$corpus/exr/fileout_8x8_mipmap_rle.exr"
# shellcheck disable=SC2086
oiiotool "$tmp/render_half.exr" --ch "$sub" --crop 6x6+5+3 $types \
	--compression zips -o "$corpus/exr/render_6x6_offset_window_zips.exr"
oiiotool "$tmp/fileout.exr" --ch "$fsub" --cut 4x4+6+6 -d float \
	-d IndexMA.V=uint32 --compression rle \
	-o "$corpus/exr/fileout_4x4_uint_index_rle.exr"
# DWA: OpenEXR 3.1's C API decodes neither (SSS_ERR_UNSUPPORTED).
cp "$root/tests/data/dwaa_32x32.exr" "$corpus/exr/dwaa_32x32.exr"

python3 "$root/tests/fuzz/make_crafted.py" "$corpus/exr"

# Scenes: the examples, Blender's, and broken variants.
cp "$root/examples/scenes/skin.json" "$corpus/scene/skin.json"
cp "$root/examples/scenes/all_profiles.json" "$corpus/scene/all_profiles.json"
cp "$tmp/scene.json" "$corpus/scene/blender_scene.json"
python3 "$root/tests/fuzz/make_crafted.py" --scenes "$corpus/scene" \
	"$root/examples/scenes/skin.json"
echo "corpus: $(find "$corpus" -type f | wc -l) files," \
	"$(du -sk "$corpus" | cut -f1) KiB"
