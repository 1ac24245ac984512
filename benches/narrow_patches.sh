#!/usr/bin/env bash
# Narrow patches merged (QualityOptions::narrow_patch_width) and the feature curves'
# median angle (HexOptions::feature_median_angle), one lattice each with the
# coverage step (HEX_PIN=0.6), as in BENCHMARKS.md "Narrow patches merged":
#   bash benches/narrow_patches.sh > narrow.txt
# Prints one line per run: model, voxels, median angle, narrow width, hex_probe's
# summary line, the feature-sheets stage's patch counts and the lattice's note
# (sheets compared / chosen, both meshes' figures), then the largest distances of
# the input's vertices to the kept mesh's boundary (benches/surface_gap.py).
set -u
cd "$(dirname "$0")/.."
# Drives the probe examples/hex_probe.rs, removed from the tree; restore it first:
#   git show 19585e7:examples/hex_probe.rs > examples/hex_probe.rs
[ -f examples/hex_probe.rs ] || { echo "examples/hex_probe.rs is not in the tree: git show 19585e7:examples/hex_probe.rs > examples/hex_probe.rs" >&2; exit 1; }
cargo build --release --example hex_probe >/dev/null 2>&1 || exit 1
P=target/release/examples/hex_probe
run() {
  local mesh=$1 res=$2 median=$3 width=$4
  out=$(HEX_PIN=0.6 HEX_MEDIAN=$median HEX_NARROW_PATCH=$width $P tests/data/meshes/$mesh voxel$res 0 2>&1)
  line=$(echo "$out" | grep -E "^voxel" | head -1)
  st=$(echo "$out" | grep -E "^   feature sheets [0-9]" | grep -oE '"(patches|narrow_patches_merged|corner_nodes|curve_nodes)":[0-9]+' | tr '\n' ' ')
  note=$(echo "$out" | grep -E "^   feature sheets: " | sed 's/^   feature sheets: //')
  echo "$mesh $res median=$median narrow=$width | $line | $st | $note"
  python3 benches/surface_gap.py tests/data/meshes/$mesh /tmp/voxel_probe.vtk 3 | sed 's/^/    /'
}
# hepta: its chamfers (45 degrees) and heptagon edges (51) are curves at a median of 40
for w in 0 0.75; do run hexgen_hepta.obj 12 40 $w; done
run hexgen_hepta.obj 12 60 0.75
# joint at 32 voxels (1.46x HexGen's elements): its 43-59 degree curves
for m in 60 40; do run hexgen_joint.obj 32 $m 0.75; done
# rod: its concave-corner faces (0.79-0.90 of the spacing) are not merged
for m in 60 40; do run hexgen_rod.obj 28 $m 0.75; done
