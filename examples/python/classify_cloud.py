#!/usr/bin/env python3
"""Classify a point cloud with a trained database, and describe it with ESF.

    python3 examples/python/classify_cloud.py DB CLOUD
    (DB from `esf train ... -o DB`; CLOUD a .pcd/.ply/.xyz file of one object)
"""

import sys

import esf


def main(database, cloud_path):
    points = esf.read_cloud(cloud_path)  # (N, 3) float32, finite points
    descriptor = esf.describe(points, seed=0)  # (640,), as `esf describe CLOUD`
    print(f"{cloud_path}: {len(points)} points, ESF sums to {descriptor.sum():.3f}")

    recognizer = esf.Recognizer(database)  # opened once, then reused for every query
    c = recognizer.classify(points, k=10)
    print(f"class {c.class_name} (confidence {c.confidence:.0%}), nearest view: model "
          f"{c.model}, view {c.view}, L1 distance {c.distance:.3f}")
    print("model -> camera pose of that view:")
    print(c.pose)
    for n in c.neighbours[:3]:
        print(f"  {n.class_name:<12} {n.model:<28} view {n.view:>3}  {n.distance:.3f}")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
