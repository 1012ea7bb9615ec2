#!/usr/bin/env python3
"""ESF descriptors as features for scikit-learn: render every generated model, describe its
views in parallel, and cross-validate a classifier with whole models held out.

    python3 examples/python/sklearn_descriptors.py MESH_ROOT
    (MESH_ROOT from `esf generate -o MESH_ROOT --per-class 3`; needs python3-sklearn)
"""

import pathlib
import sys

import numpy as np

import esf

try:
    from sklearn.ensemble import RandomForestClassifier
    from sklearn.model_selection import GroupKFold, cross_val_score
    from sklearn.neighbors import KNeighborsClassifier
except ImportError:
    sys.exit("this example needs scikit-learn (Debian: python3-sklearn)")


def main(root):
    clouds, labels, groups = [], [], []
    for mesh in sorted(pathlib.Path(root).glob("*/*.ply")):
        for view in esf.render(mesh, level=1, distance=0.8, min_elevation=0, seed=1):
            if len(view.points) >= 100:
                clouds.append(view.points)
                labels.append(mesh.parent.name)
                groups.append(mesh.stem)
    X = esf.describe_batch(clouds, seed=0)  # (views, 640), all cores, GIL released
    y = np.array(labels)
    print(f"{len(X)} views of {len(set(groups))} models, {len(set(labels))} classes")
    folds = GroupKFold(n_splits=min(3, len(set(groups))))
    for name, model in [("1-NN, L1 (as esf)", KNeighborsClassifier(1, metric="manhattan")),
                        ("random forest", RandomForestClassifier(200, random_state=0))]:
        scores = cross_val_score(model, X, y, groups=groups, cv=folds)
        print(f"{name:<18} accuracy on held-out models {scores.mean():.1%}")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
