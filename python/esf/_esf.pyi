# Type stubs of the compiled module esf._esf (see its docstrings for the full story). Defaults
# are `...`: the module takes them from the C++ option structs, and help(esf.NAME) shows them.
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
def read_cloud(path: PathLike, *, organized: bool = ...) -> FloatArray: ...
def write_cloud(path: PathLike, points: PointsLike, *, encoding: str = ...) -> None: ...
def describe(
    points: PointsLike, *, samples: int = ..., seed: int = ..., sampler: str = ..., grid: int = ...
) -> FloatArray: ...
def describe_batch(
    clouds: Sequence[PointsLike],
    *,
    samples: int = ...,
    seed: int = ...,
    sampler: str = ...,
    grid: int = ...,
    threads: int = ...,
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
    grouping: str = ...,
    plane_distance: float = ...,
    min_height: float = ...,
    max_height: float = ...,
    cluster_tolerance: float = ...,
    min_cluster_points: int = ...,
    viewpoint: Sequence[float] | None = None,
    seed: int = ...,
    threads: int = ...,
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
        k: int = ...,
        descriptor: str = ...,
        use_weights: bool = ...,
        samplings: int = ...,
        vote: str = ...,
        every_view: bool = ...,
        threads: int = ...,
        verify: bool = ...,
        verify_meshes: PathLike | None = None,
        candidates: int = ...,
        verify_within_class: bool = ...,
        merge_parts: bool = ...,
        shape_weight: float = ...,
        fixed_sizes: bool = ...,
        two_way_icp: bool = ...,
    ) -> None: ...
    def classify(self, points: PointsLike, k: int | None = None) -> Classification: ...
    def describe(self, points: PointsLike) -> FloatArray: ...
    def scene(
        self,
        points: PointsLike,
        *,
        grouping: str = ...,
        plane_distance: float = ...,
        min_height: float = ...,
        max_height: float = ...,
        cluster_tolerance: float = ...,
        min_cluster_points: int = ...,
        viewpoint: Sequence[float] | None = None,
        seed: int = ...,
        threads: int = ...,
    ) -> list[SceneObject]: ...
    @property
    def k(self) -> int: ...
    @property
    def categories(self) -> list[str]: ...
    @property
    def verification(self) -> str: ...
    @property
    def descriptor(self) -> str: ...
    @property
    def views(self) -> int: ...

def evaluate(
    database: PathLike,
    test_set: PathLike,
    k: int = ...,
    *,
    descriptor: str = ...,
    use_weights: bool = ...,
    samplings: int = ...,
    threads: int = ...,
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
    descriptor: str = ...,
    level: int = ...,
    samples: int = ...,
    seed: int = ...,
    noise: str = ...,
    distance: float | None = ...,
    max_distance: float | None = ...,
    min_elevation: float = ...,
    max_elevation: float = ...,
    min_points: int = ...,
    occlusions: int = ...,
    catalog: PathLike | None = None,
    use_catalog: bool = ...,
    threads: int = ...,
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
    level: int = ...,
    width: int = ...,
    height: int = ...,
    fx: float | None = None,
    fy: float | None = None,
    cx: float | None = None,
    cy: float | None = None,
    fill: float = ...,
    distance: float | None = None,
    max_distance: float | None = None,
    min_elevation: float = ...,
    max_elevation: float = ...,
    noise: str = ...,
    seed: int = ...,
    scale: float = ...,
    extent: float | None = None,
    threads: int = ...,
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
    def views(self, category: str, model: str, descriptor: str = ...) -> list[dict[str, Any]]: ...
    def descriptors(self, descriptor: str = ...) -> tuple[FloatArray, list[str], list[str]]: ...
