#!/usr/bin/env python3
"""docs/paper-results.md "Scalability": the polycube stage of the main job, grouped
by the input's genus, from the report.json files `bash benches/run_main_job.sh OUT`
wrote ("diffused" from report.json, or, for runs before that field, from the
candidates.json of `sddpm polycube MESH -o POLYCUBE_OUT/NAME` with the same options).
Usage: python3 benches/scalability_table.py OUT [POLYCUBE_OUT]; OUT may also be a
folder of `bash benches/run_polycube_all.sh` (the polycube stage alone, its own
times)."""
import json, os, sys

out = sys.argv[1] if len(sys.argv) > 1 else "build/runs"
cls = lambda g: "simple (genus 0–1)" if g <= 1 else ("medium (genus 2)" if g == 2 else "complex (genus 3+)")
rows = []
for n in sorted(os.listdir(out)):
    p = os.path.join(out, n, "report.json")
    if not os.path.exists(p):
        continue
    d = json.load(open(p))
    pc, a = d["polycube"], d["polycube"].get("auto") or {}
    cjp = os.path.join(out, n, "candidates.json")
    if not a and os.path.exists(cjp):  # a `sddpm polycube` folder: the search is in candidates.json
        a = json.load(open(cjp)).get("auto") or {}
    boxes = a.get("boxes", [])
    cands = pc.get("candidates", [])
    ver = pc.get("verified")
    kept = pc.get("diffused")
    if kept is None and len(sys.argv) > 2:
        cj = json.load(open(os.path.join(sys.argv[2], n, "candidates.json")))
        kept = sum(1 for c in cj["candidates"] if c["stage"] in ("gocc", "tcv", "verified"))
    rows.append(dict(name=n, g=d["input"]["genus"], tris=d["input"]["triangles"], tets=a.get("volume_tetrahedra", 0),
                     boxes=sum(1 for b in boxes if b.get("candidates", 0) > 0), gc=sum(b.get("candidates", 0) for b in boxes),
                     kept=kept, ver=ver, s=sec if not isinstance(sec := d["seconds"]["polycube"], dict) else sec["total"]))
rows.sort(key=lambda r: (r["g"] > 1, r["g"] > 2, -(r["ver"] > 0), r["s"]))
print("| class | mesh | genus | triangles | temporary volume (tets) | boxes with candidates | genus-consistent global candidates | diffused in the global stage | verified | polycube s |")
print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")
for r in rows:
    print(f"| {cls(r['g'])} | {r['name']} | {r['g']} | {r['tris']} | {r['tets']:,} | {r['boxes']} | {r['gc']} | {r['kept']} | {r['ver']} | {r['s']:.1f} |")
print()
print("| class | meshes | mean genus-consistent candidates | mean diffused | verified / diffused | inputs with a verified polycube | mean polycube s |")
print("|---|---:|---:|---:|---:|---:|---:|")
for c in dict.fromkeys(cls(r["g"]) for r in rows):
    g = [r for r in rows if cls(r["g"]) == c]
    k, v = sum(r["kept"] for r in g), sum(r["ver"] for r in g)
    print(f"| {c} | {len(g)} | {sum(r['gc'] for r in g) / len(g):.0f} | {k / len(g):.1f} | {v}/{k} ({100 * v / max(k, 1):.0f} %) | {sum(r['ver'] > 0 for r in g)}/{len(g)} | {sum(r['s'] for r in g) / len(g):.1f} |")
