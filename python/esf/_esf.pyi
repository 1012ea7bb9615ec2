# Type stubs of the compiled module esf._esf (see its docstrings for the full story).
import os
from typing import Any, Callable, Sequence, Union

import numpy as np
import numpy.typing as npt

PathLike = Union[str, os.PathLike[str]]
#: (N, 3) or (H, W, 3) numbers, or an object with a ``points`` attribute (Open3D PointCloud)
PointsLike = Union[npt.ArrayLike, Any]
FloatArray = npt.NDArray[np.float32]

__version__: str
ESF_SIZE: int

def as_points(points: PointsLike) -> FloatArray: ...
def read_cloud(path: PathLike, *, organized: bool = False) -> FloatArray: ...
def write_cloud(path: PathLike, points: PointsLike, *, encoding: str = "binary") -> None: ...
def describe(
    points: PointsLike, *, samples: int = 20000, seed: int = 0, sampler: str = "fast", grid: int = 64
) -> FloatArray: ...
def describe_batch(
    clouds: Sequence[PointsLike],
    *,
    samples: int = 20000,
    seed: int = 0,
    sampler: str = "fast",
    grid: int = 64,
    threads: int = 0,
) -> FloatArray: ...

class Cluster:
    @property
    def points(self) -> FloatArray: ...
    @property
    def indices(self) -> npt.NDArray[np.uint32]: ...
    @property
    def centroid(self) -> FloatArray: ...
    @property
    def size(self) -> FloatArray: ...
    @property
    def truncated(self) -> bool: ...
    @property
    def message(self) -> str: ...

class Segmentation:
    @property
    def plane_found(self) -> bool: ...
    @property
    def plane(self) -> FloatArray: ...
    @property
    def plane_inliers(self) -> int: ...
    @property
    def finite_points(self) -> int: ...
    @property
    def clusters(self) -> list[Cluster]: ...
    @property
    def message(self) -> str: ...

def segment(
    points: PointsLike,
    *,
    grouping: str = "convexity",
    plane_distance: float = 0.01,
    min_height: float = 0.01,
    max_height: float = 0.40,
    cluster_tolerance: float = 0.02,
    min_cluster_points: int = 100,
    viewpoint: Sequence[float] | None = None,
    seed: int = 0,
    threads: int = 0,
) -> Segmentation: ...

class Neighbour:
    @property
    def class_name(self) -> str: ...
    @property
    def model(self) -> str: ...
    @property
    def view(self) -> int: ...
    @property
    def distance(self) -> float: ...
    @property
    def pose(self) -> FloatArray: ...

class Classification:
    @property
    def class_name(self) -> str: ...
    @property
    def confidence(self) -> float: ...
    @property
    def model(self) -> str: ...
    @property
    def view(self) -> int: ...
    @property
    def distance(self) -> float: ...
    @property
    def pose(self) -> FloatArray: ...
    @property
    def fit(self) -> dict[str, float] | None: ...
    @property
    def verified(self) -> bool: ...
    @property
    def neighbours(self) -> list[Neighbour]: ...

class SceneObject:
    @property
    def class_name(self) -> str | None: ...
    @property
    def confidence(self) -> float: ...
    @property
    def classification(self) -> Classification | None: ...
    @property
    def pose(self) -> FloatArray | None: ...
    @property
    def points(self) -> FloatArray: ...
    @property
    def centroid(self) -> FloatArray: ...
    @property
    def size(self) -> FloatArray: ...
    @property
    def truncated(self) -> bool: ...
    @property
    def error(self) -> str: ...

class Recognizer:
    def __init__(
        self,
        database: PathLike,
        *,
        k: int = 10,
        descriptor: str = "",
        use_weights: bool = True,
        samplings: int = 1,
        vote: str = "nearest",
        every_view: bool = False,
        threads: int = 0,
        verify: PathLike | None = None,
    ) -> None: ...
    def classify(self, points: PointsLike, k: int | None = None) -> Classification: ...
    def describe(self, points: PointsLike) -> FloatArray: ...
    def scene(
        self,
        points: PointsLike,
        *,
        grouping: str = "convexity",
        plane_distance: float = 0.01,
        min_height: float = 0.01,
        max_height: float = 0.40,
        cluster_tolerance: float = 0.02,
        min_cluster_points: int = 100,
        viewpoint: Sequence[float] | None = None,
        seed: int = 0,
        threads: int = 0,
    ) -> list[SceneObject]: ...
    @property
    def k(self) -> int: ...
    @property
    def categories(self) -> list[str]: ...
    @property
    def descriptor(self) -> str: ...
    @property
    def views(self) -> int: ...

def evaluate(
    database: PathLike,
    test_set: PathLike,
    k: int = 10,
    *,
    descriptor: str = "",
    use_weights: bool = True,
    samplings: int = 1,
    threads: int = 0,
) -> dict[str, Any]: ...

class TrainingProgress:
    @property
    def models_total(self) -> int: ...
    @property
    def models_done(self) -> int: ...
    @property
    def models_existing(self) -> int: ...
    @property
    def models_failed(self) -> int: ...
    @property
    def views(self) -> int: ...
    @property
    def views_skipped(self) -> int: ...
    @property
    def model(self) -> str: ...

def train(
    root: PathLike,
    database: PathLike,
    *,
    descriptor: str = "esf-angles",
    level: int = 1,
    samples: int = 20000,
    seed: int = 0,
    noise: str = "kinect",
    distance: float | None = 0.6,
    max_distance: float | None = 1.2,
    min_elevation: float = 0.0,
    max_elevation: float = 90.0,
    min_points: int = 50,
    catalog: PathLike | None = None,
    use_catalog: bool = True,
    threads: int = 0,
    progress: Callable[[TrainingProgress], object] | None = None,
) -> dict[str, Any]: ...

class View:
    @property
    def index(self) -> int: ...
    @property
    def points(self) -> FloatArray: ...
    @property
    def pose(self) -> FloatArray: ...

def render(
    mesh: PathLike,
    *,
    level: int = 1,
    width: int = 640,
    height: int = 480,
    fx: float | None = None,
    fy: float | None = None,
    cx: float | None = None,
    cy: float | None = None,
    fill: float = 0.5,
    distance: float | None = None,
    max_distance: float | None = None,
    min_elevation: float = -90.0,
    max_elevation: float = 90.0,
    noise: str = "kinect",
    seed: int = 0,
    scale: float = 1.0,
    extent: float | None = None,
    threads: int = 0,
) -> list[View]: ...

class Database:
    def __init__(self, path: PathLike) -> None: ...
    @property
    def path(self) -> str: ...
    @property
    def settings(self) -> dict[str, int | float | str]: ...
    @property
    def categories(self) -> list[dict[str, Any]]: ...
    @property
    def models(self) -> list[dict[str, Any]]: ...
    @property
    def view_count(self) -> int: ...
    @property
    def descriptor_kinds(self) -> list[tuple[str, int, int]]: ...
    def views(self, category: str, model: str, descriptor: str = "") -> list[dict[str, Any]]: ...
    def descriptors(self, descriptor: str = "") -> tuple[FloatArray, list[str], list[str]]: ...
