#!/usr/bin/env bash
# Seed the fuzz corpora from the test meshes (tests/data/meshes, copies of
# ../shared/meshes) and the project's own outputs. Idempotent.
set -euo pipefail
cd "$(dirname "$0")"
mkdir -p corpus/mesh_bytes corpus/text_formats corpus/weights corpus/ffi_inputs
i=0
for f in ../tests/data/meshes/*.{obj,stl,off} ../tests/data/meshes/bad/*; do
  [ -f "$f" ] || continue
  # keep seeds small: the fuzzer mutates, it does not need whole large meshes
  [ "$(stat -c %s "$f")" -le 300000 ] || continue
  case "$f" in *.obj) p='\x00';; *.stl) p='\x01';; *.off) p='\x02';; *) p='\x03';; esac
  { printf "$p"; cat "$f"; } > "corpus/mesh_bytes/seed$((i++))"
done
for f in ../tests/data/lsdyna/*.k; do [ -f "$f" ] && { printf '\x03'; cat "$f"; } > "corpus/text_formats/$(basename "$f")"; done
if [ -d ../target/hex-fixtures ]; then
  for f in ../target/hex-fixtures/*.vtu; do [ -f "$f" ] && { printf '\x01'; head -c 200000 "$f"; } > "corpus/text_formats/$(basename "$f")"; done
  for f in ../target/hex-fixtures/*.mesh; do [ -f "$f" ] && { printf '\x02'; head -c 200000 "$f"; } > "corpus/text_formats/$(basename "$f")"; done
fi
head -c 4096 ../models/default.sddpmw > corpus/weights/header_only
printf '\x01\x01\x00\x00\x00\x02\x00\x00\x00\x00\x00\x00\x00' > corpus/ffi_inputs/labels
printf '\x03cube,THC+Z,0,0,0,0,0,0,0,0,0,0' > corpus/ffi_inputs/string
# the C ABI cases added 2026-12-03: load options (6), weights bytes (7),
# polycube options and ratios (8), spline options and evaluation (9)
printf '\x06\x00\x00\x00\x00\x00\x00\x00\x00\x01\x10' > corpus/ffi_inputs/load_options
{ printf '\x07'; head -c 4096 ../models/default.sddpmw; } > corpus/ffi_inputs/weights_header
{ printf '\x08\x00\x19\x00\x00\x00\x02\x01\x00'; head -c 120 /dev/zero; } > corpus/ffi_inputs/polycube_options
{ printf '\x09'; head -c 64 /dev/zero; } > corpus/ffi_inputs/spline_eval
echo "corpora: $(ls corpus/* | wc -l) files"
