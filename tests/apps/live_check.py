#!/usr/bin/env python3
"""Checks esf live's stdout: every line one JSON frame with the fields the README names.

    live_check.py STDOUT [--lines N | --at-most N]
"""
import json
import math
import sys


def good_pose(pose) -> bool:
    """16 finite numbers, row-major, a rigid motion (times a scale) over 0 0 0 1."""
    if not isinstance(pose, list) or len(pose) != 16:
        return False
    if not all(isinstance(x, (int, float)) and math.isfinite(x) for x in pose):
        return False
    return pose[12:] == [0, 0, 0, 1]


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
        for t in frame["tracks"]:
            if "fit" in t and not (good_pose(t["fit"].get("pose")) and t["fit"].get("model")
                                   and 0 <= t["fit"].get("score", -1) <= 1):
                print(f"{path}:{number}: a track with a bad fit {t['fit']}")
                return 1
        for o in frame["objects"]:
            if "fit" in o and not (good_pose(o.get("pose")) and o.get("model")
                                   and isinstance(o.get("verified"), bool)
                                   and set(o["fit"]) == {"inliers", "support", "violations",
                                                         "rms_mm"}):
                print(f"{path}:{number}: an object with a bad fit {o}")
                return 1
            if o["track"] not in ids:
                print(f"{path}:{number}: object of track {o['track']}, which is not listed")
                return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
