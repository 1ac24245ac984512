#!/usr/bin/env bash
# The automated mode on every test mesh, as `sddpm polycube MESH --auto` runs it
# (default options, embedded model), with a picture per part:
#   OUT/NAME_subregions.png  the input coloured by the chosen box's subregions
#   OUT/NAME_context.png     the verified polycube, each cell in its subregion's colour
# (examples/auto_pictures.rs), then one markdown row per mesh: genus, the chosen
# polycube or the refusal's reason, verified / candidates, seconds.
# BENCHMARKS.md "Real parts in the automated mode".
# Usage: bash benches/real_parts_auto.sh OUT [MESH_DIR]   (MESH_DIR default tests/data/meshes)
set -uo pipefail
cd "$(dirname "$0")/.."
out=${1:?usage: real_parts_auto.sh OUT [MESH_DIR]}
meshes=${2:-tests/data/meshes}
mkdir -p "$out"
cargo build --release -q --example auto_pictures
for f in "$meshes"/*.off "$meshes"/*.obj "$meshes"/*.stl; do
  [ -f "$f" ] || continue
  n=$(basename "${f%.*}")
  target/release/examples/auto_pictures "$f" "$out/$n" > "$out/$n.txt" 2>&1
done
python3 - "$out" <<'PY'
import os, re, sys
out = sys.argv[1]
print("| mesh | genus | polycube chosen (verified) | verified / candidates | s | pictures | why none verified |")
print("|---|---:|---|---:|---:|---|---|")
for t in sorted(x for x in os.listdir(out) if x.endswith(".txt")):
    n = t[:-4]
    text = open(os.path.join(out, t)).read()
    m = re.search(r"genus (\d+), (\d+) candidates, (\d+) verified, chosen (Some\(\"(.*?) under .*?\"\)|None) \(([\d.]+) s\)", text)
    if not m:
        print(f"| {n} | | | | | | {text.strip().splitlines()[-1][:200] if text.strip() else 'no output'} |")
        continue
    genus, cands, ver, chosen, secs = m.group(1), m.group(2), m.group(3), m.group(5), m.group(6)
    chosen = ",".join(l for l in chosen.split(",") if l != "null") if chosen else "—"
    pics = " ".join(f"[{k}]({n}_{k}.png)" for k in ("subregions", "context") if os.path.exists(os.path.join(out, f"{n}_{k}.png")))
    why = ""
    e = re.search(r"automated mode: (.*)", text)
    if e and chosen == "—":
        why = e.group(1)
        why = why.split(". To go on")[0]
        why = why[:260] + ("..." if len(why) > 260 else "")
    print(f"| {n} | {genus} | {chosen} | {ver} / {cands} | {secs} | {pics} | {why} |")
PY
