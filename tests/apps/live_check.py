#!/usr/bin/env python3
"""Checks esf live's stdout: every line one JSON frame with the fields the README names.

    live_check.py STDOUT [--lines N | --at-most N]
"""
import json
import sys


def main() -> int:
    path = sys.argv[1]
    lines = open(path, encoding="utf-8").read().splitlines()
    if len(sys.argv) == 4:
        n = int(sys.argv[3])
        if sys.argv[2] == "--lines" and len(lines) != n:
            print(f"{path}: {len(lines)} lines, expected {n}")
            return 1
        if sys.argv[2] == "--at-most" and not 1 <= len(lines) <= n:
            print(f"{path}: {len(lines)} lines, expected 1 to {n}")
            return 1
    previous = -1
    for number, line in enumerate(lines, 1):
        try:
            frame = json.loads(line)
        except json.JSONDecodeError as e:
            print(f"{path}:{number}: not JSON ({e}): {line[:80]}")
            return 1
        for key in ("frame", "time", "skipped", "objects", "tracks"):
            if key not in frame:
                print(f"{path}:{number}: no '{key}'")
                return 1
        if frame["frame"] != previous + 1:
            print(f"{path}:{number}: frame {frame['frame']} after {previous}")
            return 1
        previous = frame["frame"]
        ids = {t["id"] for t in frame["tracks"]}
        for t in frame["tracks"]:
            for key in ("id", "class", "confidence", "frames", "position"):
                if key not in t:
                    print(f"{path}:{number}: a track without '{key}'")
                    return 1
            if len(t["position"]) != 3 or not 1 <= t["frames"] <= frame["frame"] + 1:
                print(f"{path}:{number}: bad track {t}")
                return 1
        for o in frame["objects"]:
            if o["track"] not in ids:
                print(f"{path}:{number}: object of track {o['track']}, which is not listed")
                return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
