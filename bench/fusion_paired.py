#!/usr/bin/env python3
"""Paired comparison of two fusion rules from fusion_study --per-sequence FILE: the difference in
objects named right (percentage points of OBJECTS, the true objects over all frames) with a 95 %
interval from resampling the sequences (seeded, 4000 resamples).

    fusion_paired.py FILE OBJECTS "RULE A" "RULE B"
"""
import random
import sys


def main() -> int:
    if len(sys.argv) != 5:
        print(__doc__.strip())
        return 1
    path, objects, a, b = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4]
    rows = {}
    for line in open(path, encoding="utf-8"):
        fields = line.rstrip("\n").split("\t")
        rows[fields[0]] = [int(x) for x in fields[1:]]
    for rule in (a, b):
        if rule not in rows:
            print(f"{path}: no rule '{rule}'")
            return 1
    diff = [x - y for x, y in zip(rows[a], rows[b])]
    n = len(diff)
    rng = random.Random(1)
    sums = sorted(sum(diff[rng.randrange(n)] for _ in range(n)) for _ in range(4000))
    points = lambda v: 100.0 * v / objects
    print(f"{a} - {b}: {points(sum(diff)):+.1f} points, 95 % interval "
          f"[{points(sums[100]):+.1f}, {points(sums[3899]):+.1f}] over {n} sequences")
    return 0


if __name__ == "__main__":
    sys.exit(main())
