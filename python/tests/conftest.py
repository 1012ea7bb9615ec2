"""Fixtures of the esf Python tests: the esf command (ESF_CLI), the shared real data (ESF_DATA,
default ../shared/data beside the repository), and a small database trained on generated
models in a temporary folder."""

import csv
import os
import pathlib
import subprocess

import numpy as np
import pytest

import esf

REPO = pathlib.Path(__file__).resolve().parents[2]


def _cli_path():
    env = os.environ.get("ESF_CLI")
    if env:
        return pathlib.Path(env)
    return REPO / "build" / "apps" / "esf" / "esf"


@pytest.fixture(scope="session")
def cli():
    """Runs the esf command; skips when it has not been built."""
    path = _cli_path()
    if not path.is_file():
        pytest.skip(f"esf command not found at {path} (set ESF_CLI)")

    def run(*args, check=True):
        return subprocess.run([str(path), *map(str, args)], capture_output=True, text=True,
                              check=check)

    return run


@pytest.fixture(scope="session")
def data_dir():
    path = pathlib.Path(os.environ.get("ESF_DATA", REPO.parent / "shared" / "data"))
    if not (path / "real" / "objects").is_dir():
        pytest.skip(f"shared data not found at {path} (set ESF_DATA)")
    return path


@pytest.fixture(scope="session")
def meshes(tmp_path_factory, cli):
    """Procedural meshes of the ten classes, one model each (esf generate)."""
    root = tmp_path_factory.mktemp("meshes")
    cli("generate", "-o", root, "--per-class", 1, "--seed", 3)
    return root


@pytest.fixture(scope="session")
def database(tmp_path_factory, meshes):
    """A small database (view sphere level 0: the cameras above each model) of `meshes`."""
    path = tmp_path_factory.mktemp("db") / "generated.sqlite"
    esf.train(meshes, path, level=0, samples=5000, threads=2)
    return path


@pytest.fixture(scope="session")
def test_set(tmp_path_factory, meshes):
    """Views of every generated model rendered with another seed, as PCD files, and a CSV
    naming their classes: (csv path, list of (points, class))."""
    folder = tmp_path_factory.mktemp("testset")
    rows, clouds = [], []
    for mesh in sorted(meshes.glob("*/*.ply")):
        views = esf.render(mesh, level=0, distance=0.8, min_elevation=20, seed=11, threads=2)
        for view in views[:2]:
            if len(view.points) < 200:
                continue
            name = f"{mesh.parent.name}_{mesh.stem}_{view.index}.pcd"
            esf.write_cloud(folder / name, view.points)
            rows.append((name, mesh.parent.name))
            clouds.append((view.points, mesh.parent.name))
    path = folder / "testset.csv"
    with open(path, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["file", "class"])
        writer.writerows(rows)
    return path, clouds


@pytest.fixture
def cloud():
    """A 20,000-point float32 cloud: a noisy half cylinder with a lid (no degenerate cases)."""
    rng = np.random.default_rng(5)
    angle = rng.uniform(0, np.pi, 20000)
    height = rng.uniform(0, 0.2, 20000)
    points = np.stack([0.05 * np.cos(angle), 0.05 * np.sin(angle), height], axis=1)
    points[:2000, 2] = 0.2
    points[:2000, :2] *= rng.uniform(0, 1, (2000, 1))
    return np.ascontiguousarray(points, dtype=np.float32)
