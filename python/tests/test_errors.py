"""Every error path: bad arrays raise ValueError, wrong types TypeError, files OSError /
FileNotFoundError, with the library's (and the esf command's) messages; nothing crashes."""

import numpy as np
import pytest

import esf


@pytest.mark.parametrize("points,message", [
    (np.zeros((0, 3), np.float32), "at least 3 finite points, got 0"),
    (np.full((100, 3), np.nan, np.float32), "at least 3 finite points, got 0"),
    (np.ones((50, 3), np.float32), ""),  # all identical
    (np.zeros((5, 2), np.float32), "expected shape (N, 3) or (H, W, 3), got (5, 2)"),
    (np.zeros(9, np.float32), "got (9,)"),
    (np.zeros((2, 2, 2, 3), np.float32), "got (2, 2, 2, 3)"),
])
def test_bad_arrays_raise_value_error(points, message):
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
        esf.describe(points)


def test_value_error_carries_the_library_message(cli, tmp_path):
    path = tmp_path / "two.pcd"
    esf.write_cloud(path, np.array([[0, 0, 1], [0, 1, 1]], np.float32))
    result = cli("describe", path, check=False)
    assert result.returncode == 2
    with pytest.raises(ValueError) as error:
        esf.describe(esf.read_cloud(path))
    assert str(error.value) in result.stderr


@pytest.mark.parametrize("points", [None, "points.pcd", b"xyz", {"a": 1}, 3.0,
                                    np.array([["a", "b", "c"]]), [[object(), 1, 2]]])
def test_wrong_types_raise_type_error(points):
    with pytest.raises(TypeError):
        esf.describe(points)


def test_bad_options_raise_value_error(cloud):
    with pytest.raises(ValueError, match="sampler"):
        esf.describe(cloud, sampler="slow")
    with pytest.raises(ValueError):
        esf.describe(cloud, samples=0)
    with pytest.raises(ValueError):
        esf.describe(cloud, grid=4)
    with pytest.raises(ValueError):
        esf.describe_batch([cloud], threads=-1)
    with pytest.raises(ValueError, match=r"clouds\[1\]"):
        esf.describe_batch([cloud, cloud[:2]])
    with pytest.raises(ValueError, match="grouping"):
        esf.segment(cloud, grouping="nearest")


def test_missing_files_raise_file_not_found(tmp_path, cli):
    missing = tmp_path / "missing.pcd"
    result = cli("describe", missing, check=False)
    with pytest.raises(FileNotFoundError) as error:
        esf.read_cloud(missing)
    assert str(missing) in str(error.value) and str(error.value) in result.stderr
    for call in [lambda: esf.Recognizer(tmp_path / "missing.sqlite"),
                 lambda: esf.Database(tmp_path / "missing.sqlite"),
                 lambda: esf.render(tmp_path / "missing.ply"),
                 lambda: esf.train(tmp_path / "missing", tmp_path / "db.sqlite"),
                 lambda: esf.evaluate(tmp_path / "missing.sqlite", tmp_path / "t.csv")]:
        with pytest.raises(FileNotFoundError):
            call()
    assert not (tmp_path / "db.sqlite").exists()  # train() failed before creating it


def test_broken_files_raise_os_error(tmp_path):
    broken = tmp_path / "broken.pcd"
    broken.write_text("VERSION .7\nFIELDS x y\n")
    with pytest.raises(OSError, match="broken.pcd") as error:
        esf.read_cloud(broken)
    assert not isinstance(error.value, FileNotFoundError)
    with pytest.raises(OSError, match="unknown.xyzw"):
        esf.read_cloud(tmp_path / "unknown.xyzw")
    not_a_db = tmp_path / "text.sqlite"
    not_a_db.write_text("hello")
    with pytest.raises(OSError, match="text.sqlite"):
        esf.Database(not_a_db)
    with pytest.raises(OSError):
        esf.write_cloud(tmp_path / "no" / "such" / "dir.pcd", np.zeros((3, 3), np.float32))
    with pytest.raises(ValueError, match="PCD"):
        esf.write_cloud(tmp_path / "cloud.ply", np.zeros((3, 3), np.float32))
