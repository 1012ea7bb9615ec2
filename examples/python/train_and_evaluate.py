#!/usr/bin/env python3
"""Train on procedural models (`esf generate`) and evaluate on views rendered with another
seed, all from Python.

    python3 examples/python/train_and_evaluate.py WORKDIR [--esf PATH_TO_esf]
"""

import argparse
import csv
import pathlib
import shutil
import subprocess

import esf


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("workdir", type=pathlib.Path)
    parser.add_argument("--esf", default=shutil.which("esf") or "build/apps/esf/esf",
                        help="the esf command (for `esf generate`)")
    parser.add_argument("--per-class", type=int, default=2)
    args = parser.parse_args()

    meshes = args.workdir / "meshes"
    subprocess.run([args.esf, "generate", "-o", str(meshes), "--per-class", str(args.per_class)],
                   check=True, stdout=subprocess.DEVNULL)

    database = args.workdir / "generated.sqlite"

    def progress(p):
        print(f"\rtrain: {p.models_done}/{p.models_total} models, {p.views} views", end="")

    result = esf.train(meshes, database, level=1, progress=progress)  # Ctrl-C stops; rerun resumes
    print(f"\n{result['models_trained']} models trained, {result['models_existing']} already stored")

    # A test set: two views of every model from other cameras and noise, as PCD files + CSV.
    test_dir = args.workdir / "test"
    test_dir.mkdir(exist_ok=True)
    rows = []
    for mesh in sorted(meshes.glob("*/*.ply")):
        views = esf.render(mesh, level=0, distance=0.9, min_elevation=25, seed=99)
        for view in views[:2]:
            if len(view.points) >= 200:
                name = f"{mesh.stem}_{view.index}.pcd"
                esf.write_cloud(test_dir / name, view.points)
                rows.append((name, mesh.parent.name))
    test_set = test_dir / "labels.csv"
    with open(test_set, "w", newline="") as f:
        csv.writer(f).writerows([("file", "class"), *rows])

    report = esf.evaluate(database, test_set, k=10)  # what `esf eval DB CSV --json` prints
    overall = report["overall"]
    print(f"{overall['samples']} test views: 1-NN {overall['top1']:.1%}, "
          f"10-NN {overall['top10']:.1%}")
    for c in report["classes"]:
        print(f"  {c['class']:<14} 1-NN {c['top1']:.0%}  confused with {c['confused_with'] or '-'}")


if __name__ == "__main__":
    main()
