"""Recognizer, Database, evaluate, render, segment and train against the esf command."""

import json
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

import esf


def test_database_lists_what_the_cli_lists(cli, database):
    info = json.loads(cli("info", database, "--json").stdout)
    db = esf.Database(database)
    assert db.view_count == info["views"] > 0
    assert {c["name"]: c["models"] for c in db.categories} == info["categories"]
    assert {c["name"]: c["views"] for c in db.categories} == info["category_views"]
    assert len(db.categories) == 10
    assert sum(c["views"] for c in db.categories) == db.view_count
    assert len(db.models) == 10 and all(m["status"] == "complete" for m in db.models)
    assert db.settings["descriptor"] == "esf-angles"
    assert db.descriptor_kinds[0][0] == "esf-angles"
    X, classes, models = db.descriptors()
    # One row a signature: each view's own, then its occluded copies (esf train --occlusions).
    assert X.shape[1] == db.descriptor_kinds[0][2] and len(classes) == len(X)
    assert db.view_count < X.shape[0] <= (1 + int(db.settings["occlusions"])) * db.view_count
    first = db.models[0]
    views = db.views(first["category"], first["name"])
    assert len(views) == first["views"] + first["skipped_views"]
    assert views[0]["pose"].shape == (4, 4)
    np.testing.assert_array_equal(views[0]["descriptors"][0], X[0])


def test_classify_equals_the_cli(cli, database, test_set):
    _, clouds = test_set
    recognizer = esf.Recognizer(database)
    assert recognizer.k == 10 and len(recognizer.categories) == 10
    folder = test_set[0].parent
    files = sorted(folder.glob("*.pcd"))[:4]
    out = json.loads(cli("classify", database, *files, "--json").stdout)
    out = out if isinstance(out, list) else [out]
    for path, expected in zip(files, out):
        c = recognizer.classify(esf.read_cloud(path))
        assert c.class_name == expected["class"]
        assert c.model == expected["model"] and c.view == expected["view"]
        assert c.confidence == pytest.approx(expected["confidence"])
        assert c.distance == pytest.approx(expected["distance"], rel=1e-6)
        np.testing.assert_allclose(c.pose.ravel(), expected["pose"], rtol=1e-6, atol=1e-6)
        assert len(c.neighbours) == 10
        assert [n.model for n in c.neighbours] == [n["model"] for n in expected["neighbours"]]


def test_one_view_per_model_and_the_vote_rule(database, test_set):
    points = test_set[1][0][0]
    per_model = esf.Recognizer(database).classify(points)
    assert len({n.model for n in per_model.neighbours}) == len(per_model.neighbours)
    assert per_model.class_name == per_model.neighbours[0].class_name  # the nearest names it
    views = esf.Recognizer(database, every_view=True).classify(points)
    assert views.neighbours[0].distance == per_model.neighbours[0].distance
    # The k nearest views lie no farther than the k nearest models' views.
    assert all(v.distance <= m.distance for v, m in zip(views.neighbours, per_model.neighbours))
    majority = esf.Recognizer(database, every_view=True, vote="majority").classify(points)
    counts = {}
    for n in majority.neighbours:
        counts[n.class_name] = counts.get(n.class_name, 0) + 1
    assert counts[majority.class_name] == max(counts.values())
    assert majority.confidence == pytest.approx(counts[majority.class_name] / 10)
    with pytest.raises(ValueError, match="vote rule 'best'"):
        esf.Recognizer(database, vote="best")


def test_classify_with_another_k(database, test_set):
    points = test_set[1][0][0]
    recognizer = esf.Recognizer(database)
    three = recognizer.classify(points, k=3)
    assert len(three.neighbours) == 3
    assert [n.distance for n in three.neighbours] == \
        [n.distance for n in recognizer.classify(points).neighbours[:3]]
    same = esf.Recognizer(database, k=3).classify(points)
    assert (same.class_name, same.model, same.view) == (three.class_name, three.model, three.view)
    with pytest.raises(ValueError):
        recognizer.classify(points, k=0)


def test_classify_errors(database):
    recognizer = esf.Recognizer(database)
    with pytest.raises(ValueError, match="at least 3 finite points"):
        recognizer.classify(np.zeros((0, 3), np.float32))
    with pytest.raises(TypeError):
        recognizer.classify("cloud.pcd")


def test_evaluate_equals_esf_eval_json(cli, database, test_set):
    csv_path, _ = test_set
    expected = json.loads(cli("eval", database, csv_path, "-k", 5, "--json").stdout)
    got = esf.evaluate(database, csv_path, k=5)

    def without_timings(report):
        return {key: value for key, value in report.items() if key != "timings"}

    assert without_timings(got) == without_timings(expected)
    assert got["k"] == 5 and got["overall"]["samples"] == len(test_set[1])
    assert set(got["timings"]) == set(expected["timings"])


def test_render_and_scene(meshes, database):
    mesh = sorted(meshes.glob("*/*.ply"))[0]
    views = esf.render(mesh, level=0, distance=0.8, seed=2)
    assert len(views) == 20 and views[0].pose.shape == (4, 4)
    assert sum(len(v.points) > 0 for v in views) > 10
    # A view is in the camera frame: its points lie in front of the camera.
    best = max(views, key=lambda v: len(v.points))
    assert (best.points[:, 2] > 0).all()
    # A table scene: the view's points above a plane of points, seen from the camera.
    pts = best.points
    lowest = pts[:, 1].max()
    xs, zs = np.meshgrid(np.linspace(-0.4, 0.4, 120), np.linspace(0.5, 1.2, 120))
    table = np.stack([xs.ravel(), np.full(xs.size, lowest + 0.002), zs.ravel()], axis=1)
    scene = np.concatenate([pts, table]).astype(np.float32)
    seg = esf.segment(scene, viewpoint=[0, 0, 0])
    assert seg.plane_found and len(seg.clusters) >= 1
    assert seg.clusters[0].points.shape[1] == 3
    objects = esf.Recognizer(database).scene(scene)
    assert len(objects) == len(seg.clusters)
    assert objects[0].class_name in esf.Recognizer(database).categories
    assert objects[0].pose.shape == (4, 4) and objects[0].centroid.shape == (3,)
    np.testing.assert_allclose(objects[0].centroid, seg.clusters[0].centroid)
    # A cloud that is no sensor's image has no frame to merge parts against: as segmented.
    apart = esf.Recognizer(database, merge_parts=False).scene(scene)
    assert [len(o.points) for o in apart] == [len(o.points) for o in objects]
    # The shape term only reorders candidates: without it the objects are the same clusters.
    plain = esf.Recognizer(database, shape_weight=0.0).scene(scene)
    assert [len(o.points) for o in plain] == [len(o.points) for o in objects]
    with pytest.raises(ValueError, match="shape weight"):
        esf.Recognizer(database, shape_weight=3.0)
    # Sizes fixed as the catalog gives them: the same clusters, each with a rigid pose
    # (the models are metric: their poses are rotations and translations either way).
    fixed = esf.Recognizer(database, fixed_sizes=True).scene(scene)
    assert [len(o.points) for o in fixed] == [len(o.points) for o in objects]
    for o in fixed + objects:
        if o.classification is not None and o.classification.fit is not None:
            r = o.pose[:3, :3]
            np.testing.assert_allclose(r.T @ r, np.eye(3), atol=1e-4)
    # Two-way ICP: the same clusters, each fitted model still named by its fit.
    two_way = esf.Recognizer(database, two_way_icp=True).scene(scene)
    assert [len(o.points) for o in two_way] == [len(o.points) for o in objects]
    assert any(o.classification is not None and o.classification.fit is not None for o in two_way)


def test_train_progress_interrupt_and_resume(tmp_path, meshes):
    path = tmp_path / "interrupted.sqlite"
    calls = []

    def progress(p):
        calls.append(p.models_done)
        if p.models_done >= 1:
            signal.raise_signal(signal.SIGINT)  # as Ctrl-C would

    with pytest.raises(KeyboardInterrupt):
        esf.train(meshes, path, level=0, samples=2000, threads=1, progress=progress)
    stored = [m for m in esf.Database(path).models if m["status"] == "complete"]
    assert 1 <= len(stored) < 10
    seen = []
    result = esf.train(meshes, path, level=0, samples=2000, threads=1,
                       progress=lambda p: seen.append(p.models_done))
    assert result["models_existing"] == len(stored)
    assert result["models_trained"] == 10 - len(stored)
    assert seen[-1] == 10
    assert len(esf.Database(path).models) == 10


def test_train_progress_exception_stops_training(tmp_path, meshes):
    class Stop(Exception):
        pass

    def progress(p):
        if p.models_done >= 2:
            raise Stop("enough")

    path = tmp_path / "stopped.sqlite"
    with pytest.raises(Stop, match="enough"):
        esf.train(meshes, path, level=0, samples=2000, threads=1, progress=progress)
    assert 2 <= len(esf.Database(path).models) < 10
    with pytest.raises(ValueError, match="descriptor"):
        esf.train(meshes, path, descriptor="nonsense")


CHILD = """
import sys, esf
try:
    esf.train(sys.argv[1], sys.argv[2], level=2, threads=1)
except KeyboardInterrupt:
    sys.exit(3)
"""


def stored_models(path):
    try:
        return len(esf.Database(path).models)
    except OSError:  # not created yet
        return 0


def test_ctrl_c_stops_training_between_models(tmp_path, meshes):
    """A real SIGINT while the C++ training runs (the GIL released, no progress callable) stops
    it after the models in hand; what was committed stays and the next run resumes."""
    path = tmp_path / "ctrl_c.sqlite"
    child = subprocess.Popen([sys.executable, "-c", CHILD, str(meshes), str(path)])
    while stored_models(path) == 0 and child.poll() is None:
        time.sleep(0.02)
    child.send_signal(signal.SIGINT)
    assert child.wait(timeout=120) == 3  # 0 would mean it trained on to the end
    stored = stored_models(path)
    assert 1 <= stored < 10
    result = esf.train(meshes, path, level=2, threads=1)
    assert result["models_existing"] == stored and result["models_trained"] == 10 - stored


def test_verification_fits_the_model_and_matches_the_cli(cli, database, meshes, test_set):
    folder = test_set[0].parent
    path = sorted(folder.glob("*.pcd"))[0]
    plain = esf.Recognizer(database, verify=False).classify(esf.read_cloud(path))
    assert plain.fit is None and not plain.verified
    recognizer = esf.Recognizer(database)  # verifies with the surfaces the database stores
    assert recognizer.verification == "stored surfaces"
    c = recognizer.classify(esf.read_cloud(path))
    assert set(c.fit) == {"inliers", "support", "violations", "rms_mm"}
    assert 0.0 <= c.fit["inliers"] <= 1.0 and 0.0 <= c.fit["violations"] <= 1.0
    # The view is of a generated model held in the database: the fit explains most of it.
    assert c.fit["inliers"] > 0.5
    # The meshes it was trained from give the same surfaces (same seed), hence the same fit.
    again = esf.Recognizer(database, verify_meshes=meshes)
    assert again.verification == f"meshes of {meshes}"
    r = again.classify(esf.read_cloud(path))
    assert (r.class_name, r.model, r.fit) == (c.class_name, c.model, c.fit)
    # Within the class the neighbours named, verification picks the model, not the class.
    within = esf.Recognizer(database, verify_within_class=True).classify(esf.read_cloud(path))
    assert within.class_name == plain.class_name and within.fit is not None
    out = json.loads(cli("classify", database, path, "--json").stdout)
    out = out[0] if isinstance(out, list) else out
    assert out["model"] == c.model and out["verified"] == c.verified
    assert set(out["fit"]) == set(c.fit)
    assert out["fit"]["inliers"] == pytest.approx(c.fit["inliers"])
    assert out["fit"]["support"] == pytest.approx(c.fit["support"])
    np.testing.assert_allclose(c.pose.ravel(), out["pose"], rtol=1e-5, atol=1e-5)
    out = json.loads(cli("classify", database, path, "--no-verify", "--json").stdout)
    out = out[0] if isinstance(out, list) else out
    assert "fit" not in out and out["model"] == plain.model
