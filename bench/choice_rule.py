#!/usr/bin/env python3
"""Verification's choice among its candidates, judged offline (BENCHMARKS.md, "The choice among
the candidates").

Reads the CSVs of build/bench/choice_study (one row per object and candidate fitted, 6
candidates each) and counts, per set, the objects whose chosen candidate is of the true class:

  * the default rule (the highest score less the shape term among the first 3 candidates) and
    the same over all 6;
  * an oracle (some candidate among the first 3 / 6 is of the true class);
  * the default rule plus w x one more feature, for each feature and w in +-0.05, 0.1, 0.2;
  * with --train, a conditional logit over every feature (softmax over an object's candidates,
    fitted by gradient descent on the objects of the --train sets whose candidates disagree),
    judged on every set.

    bench/choice_rule.py [--train pg0,pgs0] NAME=FILE.csv ...
"""
import argparse
import collections
import csv
import math
import sys

import numpy as np

FEATURES = ["compared", "inliers", "support", "violations", "rms_cm", "abs_ln_scale",
            "relative_distance", "class_votes", "knn_class", "rank", "verified", "shape_term"]


def load(path):
    """Per object (in file order): features (candidates x features), true-class flags."""
    objects = collections.OrderedDict()
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            objects.setdefault((row["scene"], row["object"]), []).append(row)
    out = []
    for rows in objects.values():
        rows.sort(key=lambda r: int(r["candidate"]))
        x = []
        for r in rows:
            inliers, support = float(r["inliers"]), float(r["support"])
            violations, shape = float(r["violations"]), float(r["shape_term"])
            d, d1 = float(r["distance"]), float(r["nearest_distance"])
            x.append([0.5 * (inliers + support) - violations - shape, inliers, support,
                      violations, float(r["rms_mm"]) / 10.0, abs(math.log(float(r["scale"]))),
                      d / d1 - 1.0 if d1 > 0 else 0.0, int(r["class_votes"]) / 10.0,
                      int(r["knn_class"]), int(r["candidate"]), int(r["verified"]), shape])
        out.append((np.array(x), np.array([r["candidate_class"] == r["class"] for r in rows])))
    return out


def right(objects, w, candidates):
    return sum(int(y[int(np.argmax(x[:candidates] @ w))]) for x, y in objects)


def default_rule():
    w = np.zeros(len(FEATURES))
    w[0] = 1.0
    return w


def fit_logit(objects, candidates=3, l2=1e-2, iterations=400, rate=0.3):
    data = [(x[:candidates], y[:candidates]) for x, y in objects
            if y[:candidates].any() and not y[:candidates].all()]
    stacked = np.vstack([x for x, _ in data])
    mean, spread = stacked.mean(axis=0), stacked.std(axis=0) + 1e-9
    w = default_rule() * spread
    for _ in range(iterations):
        gradient = np.zeros_like(w)
        for x, y in data:
            z = (x - mean) / spread
            s = z @ w
            p = np.exp(s - s.max())
            p /= p.sum()
            q = np.where(y, p / p[y].sum(), 0.0)
            gradient -= z.T @ (q - p)
        w -= rate * (gradient / len(data) + l2 * w)
    return w / spread


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--train", default="", help="comma-separated set names to fit a logit on")
    parser.add_argument("sets", nargs="+", help="NAME=choice_study.csv")
    args = parser.parse_args()
    sets = collections.OrderedDict()
    for item in args.sets:
        name, _, path = item.partition("=")
        if not path:
            sys.exit(f"choice_rule.py: error: {item}: expected NAME=FILE.csv")
        sets[name] = load(path)

    def line(tag, w, candidates=3):
        cells = " ".join(f"{n} {right(o, w, candidates)}" for n, o in sets.items())
        print(f"{tag:32s} {cells}")

    print("objects".ljust(32), " ".join(f"{n} {len(o)}" for n, o in sets.items()))
    for n in (3, 6):
        print(f"oracle, {n} candidates".ljust(32),
              " ".join(f"{k} {sum(int(y[:n].any()) for _, y in o)}" for k, o in sets.items()))
    line("default rule, 3 candidates", default_rule(), 3)
    line("default rule, 6 candidates", default_rule(), 6)
    for i, feature in enumerate(FEATURES[1:], start=1):
        for v in (-0.2, -0.1, -0.05, 0.05, 0.1, 0.2):
            w = default_rule()
            w[i] = v
            line(f"+ {v} x {feature}", w)
    if args.train:
        train = [o for n in args.train.split(",") for o in sets[n]]
        for n in (3, 6):
            w = fit_logit(train, n)
            line(f"logit on {args.train}, {n} cand.", w, n)
            print("  weights:", " ".join(f"{f} {v:.2f}" for f, v in zip(FEATURES, w)))


if __name__ == "__main__":
    main()
