#!/usr/bin/env bash
# TCV pass rate (and GOCC, Chamfer) of every per-epoch weight snapshot on the same
# held-in synthetic cases; writes OUT.csv (one row per snapshot epoch-N.sddpmw).
#   benches/tcv_vs_epoch.sh SNAPSHOT_DIR OUT [cases [eval-model options...]]
# default options: --steps 50 --start-step 200 --max 3
set -euo pipefail
dir=$1; out=$2; cases=${3:-12}
shift $(( $# < 3 ? $# : 3 ))
opts=("$@")
[ ${#opts[@]} -eq 0 ] && opts=(--steps 50 --start-step 200 --max 3)
bin=${SDDPM_BIN:-target/release/sddpm}
echo "epoch,cases,gocc,tcv,input_tcv,mean_chamfer,seconds" > "$out.csv"
for f in $(ls "$dir"/epoch-*.sddpmw | sort -t- -k2 -n); do
  e=$(basename "$f" .sddpmw); e=${e#epoch-}
  "$bin" eval-model --weights "$f" --cases "$cases" "${opts[@]}" | python3 -c "
import json,sys; j=json.load(sys.stdin); c=j['per_category']; n=sum(x['cells'] for x in c)
m=sum(x['mean_chamfer']*x['cells'] for x in c)/max(n,1)
print(f\"$e,{j['cases']},{j['gocc_passed']},{j['tcv_passed']},{j.get('input_tcv_passed','')},{m:.5f},{j['seconds']:.1f}\")" >> "$out.csv"
  tail -1 "$out.csv"
done
