#!/usr/bin/env bash
# Feature sheets (QualityOptions::feature_sheets) on / off, one lattice each: HexGen's
# four with the coverage step (HEX_PIN=0.6) as in BENCHMARKS.md "At HexGen's
# element counts", the other parts with the library's defaults:
#   bash benches/feature_sheets.sh > sheets.txt
# Prints one line per run: model, voxels, sheets, hex_probe's summary line, the
# feature-sheets stage's details, and the lattice's note (whether the mesh with
# the sheets was compared with the one without, which was kept, and both meshes'
# figures when compared).
set -u
cd "$(dirname "$0")/.."
# Drives the probe examples/hex_probe.rs, removed from the tree; restore it first:
#   git show 19585e7:examples/hex_probe.rs > examples/hex_probe.rs
[ -f examples/hex_probe.rs ] || { echo "examples/hex_probe.rs is not in the tree: git show 19585e7:examples/hex_probe.rs > examples/hex_probe.rs" >&2; exit 1; }
cargo build --release --example hex_probe >/dev/null 2>&1 || exit 1
P=target/release/examples/hex_probe
run() {
  local mesh=$1 res=$2 pin=${3:-0}
  for s in 0 1; do
    out=$(HEX_PIN=$pin HEX_SHEETS=$s $P tests/data/meshes/$mesh voxel$res 0 2>&1)
    line=$(echo "$out" | grep -E "^voxel" | head -1)
    st=$(echo "$out" | grep -E "^   feature sheets [0-9]" | sed 's/.*{/{/' | cut -c1-400)
    note=$(echo "$out" | grep -E "^   feature sheets: " | sed 's/^   feature sheets: //')
    echo "$mesh $res pin=$pin sheets=$s | $line | $st | $note"
  done
}
# HexGen's four at about HexGen's element counts, and a finer lattice
run hexgen_hepta.obj 12 0.6; run hexgen_hepta.obj 20 0.6
run hexgen_rod.obj 28 0.6; run hexgen_rod.obj 36 0.6
run hexgen_joint.obj 32 0.6
run hexgen_rockerarm.obj 32 0.6
# the other parts with sharp features at the fallback's first lattice
for m in cinolib_cube_minus_sphere.obj mambo_B0.obj cgal_pinion.off cgal_dragknob.off cgal_spool.off cgal_joint.off cinolib_3holes.obj hexgen_bust.obj trimesh_round.stl cgal_eight.off cgal_hole.off; do
  run $m 24
done
