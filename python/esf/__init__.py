"""ESF (Ensemble of Shape Functions) point-cloud descriptors, training on CAD models and
table-scene recognition, over the esf C++ library; numpy arrays in and out.

    >>> import esf
    >>> points = esf.read_cloud("milk.pcd")           # (N, 3) float32, finite points
    >>> d = esf.describe(points, seed=0)              # (640,) the same as `esf describe`
    >>> esf.Recognizer("meshes.sqlite").classify(points).class_name

Points are any (N, 3) array-like of numbers (or an Open3D PointCloud); a C-contiguous float32
array is used without a copy, anything else is converted once (see ``as_points``). The GIL is
released while computing, so Python threads describe and classify in parallel. Errors:
ValueError for bad clouds and options, TypeError for what is not an array of numbers,
OSError / FileNotFoundError for files, with the messages the ``esf`` command prints.
"""

from ._esf import (
    ESF_SIZE,
    Classification,
    Cluster,
    Database,
    Neighbour,
    Recognizer,
    SceneObject,
    Segmentation,
    TrainingProgress,
    View,
    __version__,
    as_points,
    describe,
    describe_batch,
    evaluate,
    read_cloud,
    render,
    segment,
    train,
    write_cloud,
)

__all__ = [
    "ESF_SIZE",
    "Classification",
    "Cluster",
    "Database",
    "Neighbour",
    "Recognizer",
    "SceneObject",
    "Segmentation",
    "TrainingProgress",
    "View",
    "__version__",
    "as_points",
    "describe",
    "describe_batch",
    "evaluate",
    "read_cloud",
    "render",
    "segment",
    "train",
    "write_cloud",
]
