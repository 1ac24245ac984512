#!/usr/bin/env bash
# A measured fuzzing campaign: every target in turn (or JOBS at a time) for
# SECONDS each, then one table row per target (time, executions, crashes,
# timeouts, slow units, corpus size) for BENCHMARKS.md "Fuzzing".
#
#   bash fuzz/campaign.sh SECONDS [JOBS] [TARGETS...]
#   e.g. bash fuzz/campaign.sh 1800 1        # 30 min per target, one core
#
# Needs the nightly toolchain and cargo-fuzz 0.13.2. Logs go to
# fuzz/logs/<target>.log, crashes / timeouts / slow units to
# fuzz/artifacts/<target>/ (each crash becomes a regression test under
# tests/data/fuzz/, see docs/fuzzing.md).
set -euo pipefail
cd "$(dirname "$0")"
secs=${1:?usage: campaign.sh SECONDS [JOBS] [TARGETS...]}
jobs=${2:-1}
shift $(( $# >= 2 ? 2 : 1 ))
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(mesh_bytes text_formats weights ffi_inputs)
bash seed_corpus.sh
cargo +nightly fuzz build -O
mkdir -p logs
run_one() {
  local t=$1
  mkdir -p "artifacts/$t"
  # -timeout: a unit that runs longer is a finding (a hang), not just slow.
  cargo +nightly fuzz run -O "$t" "corpus/$t" -- \
    -max_total_time="$secs" -rss_limit_mb=4096 -timeout=300 -print_final_stats=1 \
    > "logs/$t.log" 2>&1 || true
}
running=0
for t in "${targets[@]}"; do
  run_one "$t" &
  running=$((running + 1))
  if [ "$running" -ge "$jobs" ]; then wait -n; running=$((running - 1)); fi
done
wait
echo "| target | time s | executions | exec/s | crashes | timeouts | slow units | corpus files |"
echo "|---|---:|---:|---:|---:|---:|---:|---:|"
for t in "${targets[@]}"; do
  log="logs/$t.log"
  runs=$(grep -oE 'stat::number_of_executed_units: *[0-9]+' "$log" | grep -oE '[0-9]+$' | tail -1)
  rate=$(grep -oE 'stat::average_exec_per_sec: *[0-9]+' "$log" | grep -oE '[0-9]+$' | tail -1)
  took=$(grep -oE 'Done [0-9]+ runs in [0-9]+ second' "$log" | grep -oE 'in [0-9]+' | grep -oE '[0-9]+' | tail -1)
  crashes=$(ls "artifacts/$t" 2>/dev/null | grep -c '^crash-' || true)
  timeouts=$(ls "artifacts/$t" 2>/dev/null | grep -c '^timeout-' || true)
  slow=$(ls "artifacts/$t" 2>/dev/null | grep -c '^slow-unit-' || true)
  corpus=$(ls "corpus/$t" | wc -l)
  echo "| $t | ${took:-?} | ${runs:-?} | ${rate:-?} | $crashes | $timeouts | $slow | $corpus |"
done
