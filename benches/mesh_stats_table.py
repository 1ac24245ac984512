#!/usr/bin/env python3
"""The paper's mesh statistics table from the main job's report.json files
(docs/paper-results.md "Mesh statistics"), with HexGen's reference meshes beside
ours where they exist (counts and minimum scaled Jacobian measured by
`cargo bench --bench hex`, BENCHMARKS.md "Side by side with HexGen").

    python3 benches/mesh_stats_table.py build/runs
"""
import glob
import json
import sys

HEXGEN = {
    "hexgen_hepta": ("1259 / 944", 0.242),
    "hexgen_rod": ("1815 / 1280", 0.319),
    "hexgen_joint": ("7512 / 6144", 0.100),
    "hexgen_rockerarm": ("6880 / 5696", 0.101),
}
out = sys.argv[1] if len(sys.argv) > 1 else "build/runs"
print("| model | input vertices / triangles | genus | polycube meshed | deepest level | output vertices / elements | min SJ | mean SJ | Hausdorff | HexGen vertices / elements | HexGen min SJ |")
print("|---|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|")
for f in sorted(glob.glob(f"{out}/*/report.json")):
    n = f.split("/")[-2]
    r = json.load(open(f))
    i, h, pc = r["input"], r["hex"], r["polycube"]
    dom = h.get("domain", "polycube")
    labels = ",".join(x for x in pc["names"].split(",") if x != "null")
    poly = labels if dom == "polycube" else f"— ({dom} fallback)"
    lvl = h["level"] if dom == "polycube" else "— (lattice)"
    hg = HEXGEN.get(n, ("—", None))
    print(f"| {n} | {i.get('vertices')} / {i.get('triangles')} | {i.get('genus')} | {poly} | {lvl} | {h.get('vertices')} / {h['elements']} | {h['min_scaled_jacobian']:.3f} | {h['mean_scaled_jacobian']:.3f} | {100*h['hausdorff_relative']:.2f} % | {hg[0]} | {'—' if hg[1] is None else f'{hg[1]:.3f}'} |")
