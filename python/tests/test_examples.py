"""The Python examples (examples/python) run and say what they should."""

import os
import pathlib
import subprocess
import sys

import pytest

import esf

EXAMPLES = pathlib.Path(__file__).resolve().parents[2] / "examples" / "python"


def run(*args):
    return subprocess.run([sys.executable, *map(str, args)], capture_output=True, text=True,
                          check=True, env=dict(os.environ)).stdout


def test_classify_cloud(database, test_set):
    csv_path, clouds = test_set
    cloud = sorted(csv_path.parent.glob("*.pcd"))[0]
    out = run(EXAMPLES / "classify_cloud.py", database, cloud)
    expected = esf.Recognizer(database).classify(esf.read_cloud(cloud))
    assert f"class {expected.class_name} " in out and f"model {expected.model}," in out


def test_train_and_evaluate(tmp_path, cli):
    cli_path = cli("--version", check=False).args[0]
    out = run(EXAMPLES / "train_and_evaluate.py", tmp_path, "--esf", cli_path, "--per-class", 1)
    assert "10 models trained" in out and "test views: 1-NN" in out
    assert (tmp_path / "generated.sqlite").is_file()


def test_sklearn_descriptors(meshes):
    pytest.importorskip("sklearn")
    out = run(EXAMPLES / "sklearn_descriptors.py", meshes)
    assert "random forest" in out and "accuracy on held-out models" in out
