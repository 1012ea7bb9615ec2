#!/usr/bin/env python3
"""Paired comparison of two runs of `esf eval DB --scenes CSV --json` over the same scenes: for
each object, whether it was found as one cluster, named right and posed right (ADD-S) in run A
and in run B; the objects each run got that the other did not, and a two-sided sign test of
those changes (the chance of a split at least this uneven if neither run were better).

    scenes_paired.py A.json[,A2.json...] B.json[,B2.json...] [A'.json[,...] B'.json[,...] ...]

Several files on a side (comma-separated, e.g. the folds of a proving ground) are taken together;
objects are matched by scene file and object id, and both sides must hold the same objects.
Further pairs (e.g. the same two settings trained with other seeds) are pooled: each pair's
objects count once per pair, so a rule judged over three training seeds is tested on all their
changes together.
"""
import json
import math
import sys


def load(paths: str) -> dict:
    objects = {}
    for path in paths.split(","):
        with open(path, encoding="utf-8") as f:
            for o in json.load(f)["objects"]:
                objects[(o["scene"], o["object_id"])] = o
    return objects


def sign_test(gained: int, lost: int) -> float:
    n = gained + lost
    if n == 0:
        return 1.0
    tail = sum(math.comb(n, i) for i in range(min(gained, lost) + 1)) / 2.0**n
    return min(1.0, 2.0 * tail)


def main() -> int:
    args = sys.argv[1:]
    if not args or args[0] in ("-h", "--help") or len(args) % 2 != 0:
        print(__doc__.strip())
        return 0 if args and args[0] in ("-h", "--help") else 1
    a, b = {}, {}
    for pair in range(len(args) // 2):
        run_a, run_b = load(args[2 * pair]), load(args[2 * pair + 1])
        if run_a.keys() != run_b.keys():
            print(f"pair {pair + 1}: the runs hold different objects ({len(run_a)} and "
                  f"{len(run_b)})", file=sys.stderr)
            return 2
        a.update({(pair, *k): o for k, o in run_a.items()})
        b.update({(pair, *k): o for k, o in run_b.items()})
    measures = {
        "found": lambda o: o["outcome"] == "found",
        "named right": lambda o: bool(o["correct"]),
        "posed right": lambda o: bool(o.get("pose_correct")),
    }
    pairs = len(args) // 2
    print(f"{len(a)} objects" + (f" in {pairs} pairs of runs" if pairs > 1 else ""))
    for name, right in measures.items():
        gained = sum(1 for k in a if not right(a[k]) and right(b[k]))
        lost = sum(1 for k in a if right(a[k]) and not right(b[k]))
        total_a = sum(1 for k in a if right(a[k]))
        print(f"{name:12} A {total_a:5d}  B {total_a + gained - lost:5d}  "
              f"B gains {gained:4d}, loses {lost:4d}  sign test p = {sign_test(gained, lost):.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
