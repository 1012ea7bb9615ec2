#!/usr/bin/env python3
"""esf.describe from Python against the C++ call on the same 20,000-point float32 cloud.

    PYTHONPATH=build/python python3 bench/python_describe_bench.py [--repeats N] [--rounds R]

The C++ side is build/bench/esf_bench_descriptor (one reused EsfEstimator, single thread, best
of N) on the same points written to a PCD file; the Python side is esf.describe on the array,
best of N. Rounds of the two alternate, so that both meet the same load. Both use the fast
sampler, 20,000 samples, seed 0. Ends with "ratio: X" = Python time / C++ time.
"""

import argparse
import pathlib
import subprocess
import sys
import tempfile
import time

import numpy as np

import esf

REPO = pathlib.Path(__file__).resolve().parents[1]


def cloud(n=20000, seed=0):
    """A box-shaped partial view: three faces of a 20 x 12 x 8 cm box, seen from one corner."""
    rng = np.random.default_rng(seed)
    u, v = rng.uniform(0, 1, (2, n))
    face = rng.integers(0, 3, n)
    size = np.array([0.20, 0.12, 0.08])
    points = np.zeros((n, 3))
    for f, (a, b, c) in enumerate([(0, 1, 2), (0, 2, 1), (1, 2, 0)]):
        sel = face == f
        points[sel, a] = u[sel] * size[a]
        points[sel, b] = v[sel] * size[b]
        points[sel, c] = size[c]
    points += rng.normal(0, 0.001, points.shape)
    return np.ascontiguousarray(points, dtype=np.float32)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=30)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--bench", default=str(REPO / "build" / "bench" / "esf_bench_descriptor"))
    args = parser.parse_args()

    points = cloud()
    assert esf.as_points(points) is points  # float32, C-contiguous: no copy
    esf.describe(points)  # warm-up: the estimator workspace is made once and reused

    def python_best(array):
        best = float("inf")
        for _ in range(args.repeats):
            start = time.perf_counter()
            esf.describe(array)
            best = min(best, time.perf_counter() - start)
        return best * 1e3

    as_float64 = points.astype(np.float64)

    with tempfile.TemporaryDirectory() as tmp:
        path = pathlib.Path(tmp) / "cloud20k.pcd"
        esf.write_cloud(path, points)

        def cpp_best():
            out = subprocess.run([args.bench, "--repeats", str(args.repeats), str(path)],
                                 capture_output=True, text=True, check=True).stdout
            row = next(line for line in out.splitlines() if "cloud20k.pcd" in line)
            return float(row.split()[3])  # file, points, pcl ms, esf ms, ...

        # Rounds alternate between the two, so that both meet the same machine load.
        python_ms, float64_ms, cpp_ms = float("inf"), float("inf"), float("inf")
        for _ in range(args.rounds):
            python_ms = min(python_ms, python_best(points))
            float64_ms = min(float64_ms, python_best(as_float64))
            cpp_ms = min(cpp_ms, cpp_best())
    print(f"esf {esf.__version__}, {len(points)} points float32, "
          f"best of {args.rounds} x {args.repeats} runs each")
    print(f"C++   EsfEstimator::compute   {cpp_ms:8.3f} ms")
    print(f"Python esf.describe           {python_ms:8.3f} ms")
    print(f"  the same from float64       {float64_ms:8.3f} ms (converted to float32 per call)")
    print(f"ratio: {python_ms / cpp_ms:.3f}")


if __name__ == "__main__":
    sys.exit(main())
