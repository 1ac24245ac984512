#!/usr/bin/env bash
# Mesh-load benchmark, both sides in one run on the same files:
#   ours:  TriMesh::load + check() + genus      (benches/mesh_load.rs)
#   CGAL:  read_polygon_mesh + V-E+F + volume   (benches/cgal_mesh_bench.cpp, built by CMake)
# Usage: bash benches/run_mesh_bench.sh [REPEATS]   (default 7). Needs the CMake
# project configured in build/ (bash .ci/test-all.sh does it). Writes
# build/mesh_bench_{ours,cgal}.csv and the markdown table build/mesh_bench.md, and prints it.
set -euo pipefail
cd "$(dirname "$0")/.."
reps=${1:-7}
mapfile -t files < <(ls tests/data/meshes/*.off tests/data/meshes/*.obj tests/data/meshes/*.stl | sort)
cargo bench --bench mesh_load --no-run
cmake --build build --target cgal_mesh_bench -j2 >/dev/null
cargo bench -q --bench mesh_load -- "$reps" "${files[@]}" > build/mesh_bench_ours.csv
build/cgal_mesh_bench "$reps" "${files[@]}" > build/mesh_bench_cgal.csv
python3 - "$reps" > build/mesh_bench.md <<'PY'
import csv, sys
ours = list(csv.DictReader(open("build/mesh_bench_ours.csv")))
cgal = {r["file"]: r for r in csv.DictReader(open("build/mesh_bench_cgal.csv"))}
print("| mesh | triangles | ours: load (ms) | ours: check (ms) | ours: load+check+genus (ms) | CGAL: read+chi+volume (ms) | CGAL / ours |")
print("|---|---:|---:|---:|---:|---:|---:|")
to = tc = 0.0
for r in ours:
    o, c = float(r["total_seconds"]), float(cgal[r["file"]]["seconds"])
    to += o; tc += c
    print(f"| {r['file']} | {r['triangles']} | {float(r['load_seconds'])*1e3:.2f} | {float(r['check_seconds'])*1e3:.2f} | {o*1e3:.2f} | {c*1e3:.2f} | {c/o:.2f} |")
print(f"| **all** | | | | {to*1e3:.1f} | {tc*1e3:.1f} | {tc/to:.2f} |")
print(f"\nMedian of {sys.argv[1]} runs per file; ratio > 1 means ours is faster.")
PY
cat build/mesh_bench.md
