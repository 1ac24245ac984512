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
echo "corpora: $(ls corpus/* | wc -l) files"
