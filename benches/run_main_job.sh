#!/usr/bin/env bash
# The main job on every test mesh (automated mode, default options, embedded model):
#   sddpm run MESH -o OUT/NAME -q
# then one markdown row per mesh from its report.json (BENCHMARKS.md "Main job").
# Usage: bash benches/run_main_job.sh [OUT]   (default build/runs). Prints the table.
set -uo pipefail
cd "$(dirname "$0")/.."
out=${1:-build/runs}
mkdir -p "$out"
cargo build --release -q
for f in tests/data/meshes/*.off tests/data/meshes/*.obj tests/data/meshes/*.stl; do
  n=$(basename "${f%.*}")
  start=$(date +%s.%N)
  if ./target/release/sddpm run "$f" -o "$out/$n" -q 2> "$out/$n.err"; then rc=0; else rc=$?; fi
  echo "$n $rc $(echo "$(date +%s.%N) - $start" | bc)" >> "$out/status.txt"
done
python3 - "$out" <<'PY'
import json, os, sys
out = sys.argv[1]
status = {}
for line in open(os.path.join(out, "status.txt")):
    n, rc, s = line.split()
    status[n] = (int(rc), float(s))
print("| mesh | tris | g | polycube | verified | ver./cand. | meshed | level | elements | min SJ | mean SJ | inverted | Hausdorff | spline det J <= 0 | s |")
print("|---|---:|---:|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
for n in sorted(status):
    rc, s = status[n]
    p = os.path.join(out, n, "report.json")
    if rc != 0 or not os.path.exists(p):
        err = open(os.path.join(out, n + ".err")).read().strip().splitlines()
        msg = err[-1][:160] if err else f"exit {rc}"
        print(f"| {n} | | | refused: {msg} | | | | | | | | | | | {s:.0f} |")
        continue
    r = json.load(open(p))
    pc, h, sp = r["polycube"], r["hex"], r.get("spline") or {}
    labels = ",".join(x for x in pc["names"].split(",") if x != "null")
    dom = h.get("domain", "polycube")
    if dom != "polycube":
        # every polycube mesh folded: the grid-based fallback's mesh was kept
        labels = f"**{dom}** (polycube {labels} folded)"
    tris = r["input"].get("triangles", "")
    g = r["input"].get("genus", pc.get("genus", ""))
    meshed = len(h.get("candidates_meshed") or [])
    bad = sp.get("negative_jacobian_elements", "")
    print(f"| {n} | {tris} | {g} | {labels} | {'yes' if pc['verified_choice'] else 'no'} | {pc['verified']}/{pc['candidates']} | {meshed} | {h['level']} | {h['elements']} | {h['min_scaled_jacobian']:.3f} | {h['mean_scaled_jacobian']:.3f} | {h['inverted']} | {100*h['hausdorff_relative']:.2f} % | {bad} | {s:.0f} |")
PY
