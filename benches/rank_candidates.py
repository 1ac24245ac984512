#!/usr/bin/env python3
"""Re-rank the automated mode's verified candidates offline, by several rules.

Input: the JSON lines `RECOVERY_DUMP=FILE cargo run --release --example recovery`
writes (one line per kept candidate: group, case, context, stage, score, whether its
solid is the truth's, per-cell geometric fits, per-cell target / nearest-other PCD);
plain or gzipped.

For each rule, the number of cases per group whose lowest-ranked verified candidate is
the truth. The diffusion and verification are those of the run; only the choice among
its verified candidates changes (the candidates that reached diffusion are the run's,
so a rule that also changes which candidates are kept must be measured by a run).

    python3 benches/rank_candidates.py docs/data/ranking/s6000_retry.jsonl.gz
"""
import collections
import gzip
import json
import sys

GROUPS = ["simple", "medium", "complex"]


def cell_fits(r):
    return [v for v in r["cell_fit"] if v is not None]


def mean(v):
    return sum(v) / len(v)


def pcd_ratios(r):
    return [t / o for t, o in zip(r["pcd_target"], r["pcd_other"]) if t is not None and o is not None]


RULES = {
    "run's score": lambda r: r["score"],
    "worst cell fit": lambda r: r["fit"],
    "mean cell fit": lambda r: mean(cell_fits(r)),
    "worst + mean": lambda r: r["fit"] + mean(cell_fits(r)),
    "rms cell fit": lambda r: mean([v * v for v in cell_fits(r)]) ** 0.5,
    "mean fit + mean PCD": lambda r: mean(cell_fits(r)) + r["pcd_mean"],
    "worst fit + mean PCD": lambda r: r["fit"] + r["pcd_mean"],
    "mean PCD target / nearest other": lambda r: mean(pcd_ratios(r)),
}


def main(path):
    opener = gzip.open if path.endswith(".gz") else open
    with opener(path, "rt") as f:
        rows = [json.loads(line) for line in f]
    cases = collections.defaultdict(list)
    for r in rows:
        cases[(r["group"], r["case"])].append(r)
    total = collections.Counter()
    truth_verified = collections.Counter()
    hits = {k: collections.Counter() for k in RULES}
    for (g, _), rs in cases.items():
        total[g] += 1
        ver = [r for r in rs if r["stage"] == "Verified"]
        truth_verified[g] += any(r["truth"] for r in ver)
        if not ver:
            continue
        for k, key in RULES.items():
            hits[k][g] += min(ver, key=key)["truth"]
    groups = [g for g in GROUPS if total[g]]
    print("| rule | " + " | ".join(f"{g} ({total[g]})" for g in groups) + " |")
    print("|---|" + "---:|" * len(groups))
    print("| true solid verified | " + " | ".join(str(truth_verified[g]) for g in groups) + " |")
    for k in RULES:
        print(f"| {k} | " + " | ".join(str(hits[k][g]) for g in groups) + " |")


if __name__ == "__main__":
    main(sys.argv[1])
