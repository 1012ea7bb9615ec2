"""esf.describe / describe_batch / read_cloud / write_cloud against the esf command, array
conversion (zero copy where promised) and the GIL."""

import json
import pathlib
import re
import sys
import threading
import tracemalloc

import numpy as np
import pytest

import esf


def cli_descriptors(cli, path, *args):
    out = cli("describe", path, "--format", "json", *args).stdout
    return np.array(json.loads(out)[0]["descriptor"], dtype=np.float32)


def test_version_is_the_project_version():
    cmake = (pathlib.Path(__file__).resolve().parents[2] / "CMakeLists.txt").read_text()
    assert re.search(r"project\(esf VERSION (\S+)", cmake).group(1) == esf.__version__


@pytest.mark.parametrize("seed,sampler", [(0, "fast"), (7, "fast"), (3, "pcl")])
def test_describe_equals_the_cli(cli, tmp_path, cloud, seed, sampler):
    path = tmp_path / "cloud.pcd"
    esf.write_cloud(path, cloud)
    expected = cli_descriptors(cli, path, "--seed", seed, "--sampler", sampler)
    got = esf.describe(esf.read_cloud(path), seed=seed, sampler=sampler)
    assert got.dtype == np.float32 and got.shape == (640,)
    np.testing.assert_array_equal(got, expected)


def test_describe_equals_the_cli_on_real_clouds(cli, data_dir):
    files = sorted((data_dir / "real" / "objects").glob("*.pcd"))[:3]
    for path in files:
        expected = cli_descriptors(cli, path, "--samples", 8000)
        np.testing.assert_array_equal(esf.describe(esf.read_cloud(path), samples=8000), expected)
        # The organised frame with its NaNs gives the same descriptor: NaNs are dropped.
        organised = esf.read_cloud(path, organized=True)
        np.testing.assert_array_equal(esf.describe(organised, samples=8000), expected)


def test_descriptor_is_normalised_and_seeded(cloud):
    a = esf.describe(cloud, seed=1)
    assert a.sum() == pytest.approx(1.0, abs=1e-4)
    np.testing.assert_array_equal(a, esf.describe(cloud, seed=1))
    assert not np.array_equal(a, esf.describe(cloud, seed=2))


def test_describe_batch_rows_equal_describe(cloud):
    clouds = [cloud, cloud[::2], cloud[:5000] * 3.0]
    batch = esf.describe_batch(clouds, seed=4, threads=2)
    assert batch.shape == (3, 640) and batch.dtype == np.float32
    for row, c in zip(batch, clouds):
        np.testing.assert_array_equal(row, esf.describe(c, seed=4))
    np.testing.assert_array_equal(batch, esf.describe_batch(clouds, seed=4, threads=1))


def test_read_write_round_trip(tmp_path, cloud):
    for encoding in ["binary", "ascii", "binary_compressed"]:
        path = tmp_path / f"{encoding}.pcd"
        esf.write_cloud(path, cloud, encoding=encoding)
        back = esf.read_cloud(str(path))
        assert back.dtype == np.float32 and back.shape == cloud.shape
        if encoding == "ascii":
            np.testing.assert_allclose(back, cloud, rtol=1e-6)
        else:
            np.testing.assert_array_equal(back, cloud)


def test_organised_round_trip_keeps_layout_and_drops_nan_when_flat(tmp_path, cloud):
    frame = cloud[:1200].reshape(30, 40, 3).copy()
    frame[0, :5] = np.nan
    path = tmp_path / "frame.pcd"
    esf.write_cloud(path, frame)
    organised = esf.read_cloud(path, organized=True)
    assert organised.shape == (30, 40, 3)
    np.testing.assert_array_equal(organised, frame)  # NaN compare equal in the same places
    flat = esf.read_cloud(path)
    assert flat.shape == (1195, 3) and np.isfinite(flat).all()


def test_float32_contiguous_is_not_copied(cloud):
    assert esf.as_points(cloud) is cloud
    frame = cloud[:1200].reshape(30, 40, 3)
    assert np.shares_memory(esf.as_points(frame), frame)


def test_other_arrays_are_converted_once(cloud):
    for other in [cloud.astype(np.float64), cloud[::2], np.asfortranarray(cloud),
                  cloud.astype(np.int32), cloud.tolist()]:
        converted = esf.as_points(other)
        assert converted.dtype == np.float32 and converted.flags.c_contiguous
        assert not np.shares_memory(converted, cloud)
        np.testing.assert_array_equal(converted, np.asarray(other, dtype=np.float32))
    np.testing.assert_array_equal(esf.describe(cloud.astype(np.float64)), esf.describe(cloud))
    np.testing.assert_array_equal(esf.describe(cloud.tolist()), esf.describe(cloud))


def peak_bytes(f):
    tracemalloc.start()
    try:
        f()
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def test_describe_allocates_no_copy_of_float32_input():
    big = np.random.default_rng(1).normal(size=(400000, 3)).astype(np.float32)  # 4.8 MB
    as_float64 = big.astype(np.float64)
    # numpy reports its buffers to tracemalloc: the float64 input is converted into a new
    # float32 array of the input's size, the float32 input is used where it is.
    assert peak_bytes(lambda: esf.describe(as_float64, samples=100)) >= big.nbytes
    assert peak_bytes(lambda: esf.describe(big, samples=100)) < big.nbytes // 10


def runs_while_gil_free(call):
    """True when another Python thread ran while `call` was inside the module.

    The switch interval is made so long that a thread holding the GIL keeps it until it blocks or
    gives it up. The main thread waits for the GIL while the worker runs `call`; only if the
    module releases the GIL does the main thread get to run its whole counting loop before the
    worker can return, so the worker sees the final count."""
    count = 0
    seen = []
    started = threading.Event()

    def worker():
        started.set()
        call()
        seen.append(count)

    old = sys.getswitchinterval()
    sys.setswitchinterval(30.0)
    try:
        thread = threading.Thread(target=worker)
        thread.start()
        started.wait()
        for _ in range(200000):
            count += 1
        thread.join()
    finally:
        sys.setswitchinterval(old)
    return seen[0] == 200000


def test_gil_is_released_while_describing(cloud):
    assert runs_while_gil_free(lambda: esf.describe(cloud, samples=400000))
    assert runs_while_gil_free(lambda: esf.describe_batch([cloud] * 8, samples=100000))


def test_threads_describe_the_same_as_one(cloud):
    results = [None] * 4

    def work(i):
        results[i] = esf.describe(cloud, seed=i % 2)

    threads = [threading.Thread(target=work, args=(i,)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    np.testing.assert_array_equal(results[0], esf.describe(cloud, seed=0))
    np.testing.assert_array_equal(results[1], esf.describe(cloud, seed=1))
    np.testing.assert_array_equal(results[0], results[2])


def test_open3d_point_cloud_is_accepted(cloud):
    o3d = pytest.importorskip("open3d")
    pc = o3d.geometry.PointCloud()
    pc.points = o3d.utility.Vector3dVector(cloud.astype(np.float64))
    np.testing.assert_array_equal(esf.describe(pc), esf.describe(cloud))
