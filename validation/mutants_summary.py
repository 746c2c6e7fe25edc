#!/usr/bin/env python3
"""Summarises cargo-mutants runs for validation/reports/mutants.md (standard library only).

    python3 validation/mutants_summary.py target/mutants/*/mutants.out

Prints, per source file, the mutants tested and how each run ended (caught, missed,
unviable, timeout, or a run that failed for another reason, e.g. a killed test process),
then every missed, timed-out or failed mutant. A mutant tested in several runs (a later
run with `--iterate` after new tests) counts with its last outcome: give the runs oldest
first."""
import json
import sys
from collections import OrderedDict

KINDS = {"CaughtMutant": "caught", "MissedMutant": "missed", "Unviable": "unviable",
         "Timeout": "timeout", "Failure": "failed"}


def main(dirs):
    last = OrderedDict()
    for d in dirs:
        with open(f"{d}/outcomes.json", encoding="utf-8") as f:
            outcomes = json.load(f)["outcomes"]
        for o in outcomes:
            scenario = o["scenario"]
            if not isinstance(scenario, dict):
                continue  # the baseline
            m = scenario["Mutant"]
            name = m["name"] if "name" in m else (
                f'{m["file"]}:{m["span"]["start"]["line"]}:{m["span"]["start"]["column"]}: '
                f'replace {m.get("function", {}).get("function_name", "?")} -> {m["replacement"]}')
            last[name] = (m["file"], KINDS.get(o["summary"], o["summary"]))
    files = OrderedDict()
    for file, kind in last.values():
        files.setdefault(file, {k: 0 for k in KINDS.values()})[kind] += 1
    print("| file | tested | caught | missed | unviable | timeout | run failed |")
    print("|---|---|---|---|---|---|---|")
    total = {k: 0 for k in KINDS.values()}
    for file, c in sorted(files.items()):
        print(f"| {file} | {sum(c.values())} | {c['caught']} | {c['missed']} | "
              f"{c['unviable']} | {c['timeout']} | {c['failed']} |")
        for k in total:
            total[k] += c[k]
    print(f"| **all** | {sum(total.values())} | {total['caught']} | {total['missed']} | "
          f"{total['unviable']} | {total['timeout']} | {total['failed']} |")
    print()
    for name, (_, kind) in last.items():
        if kind in ("missed", "timeout", "failed"):
            print(f"* {kind}: `{name}`")


if __name__ == "__main__":
    main(sys.argv[1:])
