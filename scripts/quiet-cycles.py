#!/usr/bin/env python3
"""How often the AS-i cycles of a run repeat: the measure of what a bus that computed whole
quiet cycles at once (no slave's input or output changed since the cycle before) could skip.

Reads a trace in JSON lines (`asi-lift run SCENARIO --until 60s --trace t.jsonl`) and prints,
for the Data_Exchanges of normal operation: how many carry the same output and input nibbles as
the same slave's exchange before, how many cycles repeat the cycle before exactly (every
exchange's output and input), and for each address the shortest period in cycles after which
its exchanges repeat at least 90 % of the time (a handshake's word, an analog transfer, a
safety code table).

    python3 scripts/quiet-cycles.py t.jsonl
"""

import json
import sys


def main(path):
    cycles, cycle = [], []
    last, same, exchanges = {}, 0, 0
    first = None
    with open(path, encoding="utf-8") as f:
        for line in f:
            r = json.loads(line)
            q = r["request"]
            if r.get("phase") != "data" or q.get("call") != "Data_Exchange":
                continue
            a = q["address"]
            key = (a, q["info"], (r.get("response") or {}).get("data"))
            # A cycle's data stage starts again at its lowest address.
            first = a if first is None else min(first, a)
            if a == first and cycle:
                cycles.append(tuple(cycle))
                cycle = []
            cycle.append(key)
            exchanges += 1
            same += last.get(a) == key[1:]
            last[a] = key[1:]
    if not cycles:
        sys.exit(f"{path}: no Data_Exchange of normal operation")
    n = len(cycles)
    repeats = sum(1 for i in range(1, n) if cycles[i] == cycles[i - 1])
    print(f"{exchanges} Data_Exchanges, {same} ({100 * same / exchanges:.1f} %) the same "
          "output and input as the slave's exchange before")
    print(f"{n} cycles, {repeats} ({100 * repeats / n:.1f} %) the same as the cycle before")
    for a in sorted(last):
        seq = [next((k[1:] for k in c if k[0] == a), None) for c in cycles]
        period = next(
            (p for p in range(1, min(n // 2, 400))
             if sum(seq[i] == seq[i - p] for i in range(p, n)) >= 0.9 * (n - p)),
            None,
        )
        print(f"address {a:2}: repeats after {period} cycles" if period
              else f"address {a:2}: no period below {min(n // 2, 400)} cycles")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: quiet-cycles.py TRACE.jsonl")
    main(sys.argv[1])
