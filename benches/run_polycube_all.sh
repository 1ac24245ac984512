#!/usr/bin/env bash
# The polycube stage alone on every test mesh (automated mode, default options,
# embedded model): sddpm polycube MESH -o OUT/NAME, one line per mesh with the exit
# status, the seconds and the chosen polycube or the error.
# Usage: bash benches/run_polycube_all.sh [OUT] [NAME...]   (default build/polycube_all)
# POLYCUBE_ARGS="..." adds options to every run (e.g. "--visible --start-step 100").
set -uo pipefail
cd "$(dirname "$0")/.."
out=${1:-build/polycube_all}
shift || true
mkdir -p "$out"
cargo build --release -q
for f in tests/data/meshes/*.off tests/data/meshes/*.obj tests/data/meshes/*.stl; do
  n=$(basename "${f%.*}")
  if [ $# -gt 0 ] && [[ " $* " != *" $n "* ]]; then continue; fi
  start=$(date +%s.%N)
  # shellcheck disable=SC2086
  ./target/release/sddpm polycube "$f" -o "$out/$n" ${POLYCUBE_ARGS:-} > "$out/$n.log" 2>&1
  rc=$?
  printf "%-26s rc=%d %6.1f s  %s\n" "$n" "$rc" "$(echo "$(date +%s.%N) - $start" | bc)" "$(grep -m1 -i 'polycube:\|error' "$out/$n.log" | cut -c1-160)"
done
