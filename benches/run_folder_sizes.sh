#!/usr/bin/env bash
# The size of `sddpm run`'s output folder on every test mesh at default options:
#   sddpm run MESH -o OUT/NAME -q
# then one markdown row per mesh: the folder's bytes (du --apparent-size, every
# file), the largest files from report.json's manifest, and the total report.json
# states ("files_bytes"). BENCHMARKS.md "Run folder size".
# Usage: bash benches/run_folder_sizes.sh [OUT] [MESH_DIR]
#   OUT default build/sizes; MESH_DIR default tests/data/meshes.
#   SDDPM=path picks the binary (default target/release/sddpm, built first);
#   MESHES="cinolib_torus hexgen_rod" runs only those; TABLE_ONLY=1 runs nothing
#   and prints the table of the folders OUT already holds (OUT may be several
#   folders separated by ':', each with its status.txt).
set -uo pipefail
cd "$(dirname "$0")/.."
out=${1:-build/sizes}
meshes=${2:-tests/data/meshes}
bin=${SDDPM:-target/release/sddpm}
if [ -n "${TABLE_ONLY:-}" ]; then meshes=/nonexistent; fi
[ -n "${SDDPM:-}" ] || [ -n "${TABLE_ONLY:-}" ] || cargo build --release -q
[ -n "${TABLE_ONLY:-}" ] || mkdir -p "$out"
for f in "$meshes"/*.off "$meshes"/*.obj "$meshes"/*.stl; do
  [ -f "$f" ] || continue
  n=$(basename "${f%.*}")
  if [ -n "${MESHES:-}" ] && [[ " $MESHES " != *" $n "* ]]; then continue; fi
  rm -rf "${out:?}/$n"
  start=$(date +%s.%N)
  if "$bin" run "$f" -o "$out/$n" -q 2> "$out/$n.err"; then rc=0; else rc=$?; fi
  echo "$n $rc $(echo "$(date +%s.%N) - $start" | bc)" >> "$out/status.txt"
done
python3 - "$out" <<'PY'
import json, os, sys
status = {}
for out in sys.argv[1].split(":"):
    for line in open(os.path.join(out, "status.txt")):
        n, rc, s = line.split()
        status[n] = (int(rc), float(s), out)
mb = lambda b: f"{b / 1e6:.2f}"
print("| mesh | elements | basis functions | folder MB | spline.bext | spline.vtu | report.html | hex files | other | files | s |")
print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
total = 0
for n in sorted(status):
    rc, s, out = status[n]
    p = os.path.join(out, n, "report.json")
    if rc != 0 or not os.path.exists(p):
        print(f"| {n} | exit {rc} | | | | | | | | | {s:.0f} |")
        continue
    r = json.load(open(p))
    d = os.path.join(out, n)
    folder = sum(os.path.getsize(os.path.join(d, x)) for x in os.listdir(d))
    total += folder
    sizes = {f["name"]: f["bytes"] for f in r["files"]}
    assert r["files_bytes"] == folder, (n, r["files_bytes"], folder)
    hexf = sum(v for k, v in sizes.items() if k.startswith("hex.") and not k.endswith(".png"))
    named = sizes.get("spline.bext", 0) + sizes.get("spline.vtu", 0) + sizes.get("report.html", 0) + hexf
    sp = r.get("spline") or {}
    print(f"| {n} | {r['hex']['elements']} | {sp.get('basis_functions', '-')} | {mb(folder)} | {mb(sizes.get('spline.bext', 0))} | {mb(sizes.get('spline.vtu', 0))} | "
          f"{mb(sizes.get('report.html', 0))} | {mb(hexf)} | {mb(folder - named)} | {len(sizes)} | {s:.1f} |")
print(f"\nAll folders: {mb(total)} MB")
PY
