#!/usr/bin/env bash
# usage: bench/bitcheck.sh BASE_BIN NEW_BIN OUTDIR
# Renders a fixed set of scenes (the RGB and media references, scenes/, shared course scenes) with two
# binaries at 96x96, 4 spp, seed 3, and cmp-s the EXRs: the check that a refactoring changed
# no image. SHARED overrides where ../shared is.
set -u
B=$1; N=$2; O=$3; mkdir -p $O
ROOT=$(cd "$(dirname "$0")/.." && pwd); SH=${SHARED:-$ROOT/../shared}
S=$SH/scenes; R=$SH/references/scenes; M=$ROOT/scenes
scenes=(
 "$R/bench-cbox.xml" "$R/cbox-specular.xml" "$R/envmap-materials.xml" "$R/lights.xml" "$R/veach-plates.xml"
 "$R/media-fog.xml" "$R/media-homogeneous.xml" "$R/media-heterogeneous.xml"
 "$M/cornell-box.xml" "$M/many-lights.xml" "$M/ceng795/cornell_phong.json" "$M/ceng795/textures.json"
 "$M/comp30019/showcase.txt" "$M/comp30019/dof.txt" "$M/cs184/floor_sphere.dae"
 "$S/nori/pa5/cbox/cbox_mis.xml" "$S/nori/pa4/cbox/cbox-whitted.xml"
 "$S/standard/bitterli-cornell-box/mitsuba/scene_v3.xml" "$S/standard/mitsuba-cbox/cbox.xml"
 "$S/ceng795/xml/cornellbox_jaroslav_glossy_area_sphere.xml" "$S/ceng795/xml/brdf_torrancesparrow.xml"
)
extra=$(find $S/ceng795 -name "*.json" | grep -i "textur\|bump\|normal\|perlin" | head -6)
extra2=$(find $S/aalto -name "*.obj" | head -3)
fail=0; n=0
for s in "${scenes[@]}" $extra $extra2; do
  [ -f "$s" ] || { echo "missing $s"; continue; }
  k=$(echo "$s" | md5sum | cut -c1-8)
  a=(--spp 4 --seed 3 -q --res 96x96)
  $B render "$s" "${a[@]}" -o $O/$k-b.exr >/dev/null 2>$O/$k-b.err; rb=$?
  $N render "$s" "${a[@]}" -o $O/$k-n.exr >/dev/null 2>$O/$k-n.err; rn=$?
  n=$((n+1))
  if [ $rb -ne $rn ]; then echo "EXIT DIFF $rb $rn $s"; fail=1; continue; fi
  if [ $rb -ne 0 ]; then echo "both failed ($rb): $s: $(head -c 200 $O/$k-n.err)"; continue; fi
  if cmp -s $O/$k-b.exr $O/$k-n.exr; then echo "same  $s"; else echo "DIFF  $s"; fail=1; fi
done
echo "scenes: $n, fail=$fail"
