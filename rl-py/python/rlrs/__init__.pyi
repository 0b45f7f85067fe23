"""Type stubs of rlrs (rl-rs from Python). Arrays are float64 numpy arrays; a "batch" is a 2-D
array with one state per row, and the result then has the batch as its first axis."""

import os
from typing import Any, Literal, Mapping, Optional, Sequence, Tuple, Union, overload

import numpy as np
import numpy.typing as npt

__version__: str
CAPACITIES: list[int]

ArrayLike = npt.ArrayLike
Array = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]
PathLike = Union[str, "os.PathLike[str]"]

class Error(Exception):
    """Every error rl-rs itself reports."""

class LoadError(Error):
    """A model, scene or problem file was refused (file, element, line:column, reason)."""

class ModelError(Error):
    """An algorithm refused its input (lengths, quaternions, a singular mass matrix)."""

class IkError(Error):
    """Inverse kinematics found no solution; `.q` is the best configuration, `.residual` its error."""

    q: Array
    residual: float

class TrajectoryError(Error):
    """A trajectory cannot be built (limits, waypoints)."""

class PlanError(Error):
    """Planning refused its problem (an end point outside the limits or in collision)."""

class RunError(Error):
    """A controller run did not start; nothing moved."""

def set_threads(n: int) -> None:
    """Threads a batched call may use (0: one per CPU, the default)."""

def threads() -> int:
    """Threads a batched call may use."""

def load(
    path: PathLike,
    floating_base: bool = False,
    joint_order: Literal["file", "pinocchio"] = "file",
    mimic: Literal["follow", "independent", "reject"] = "follow",
    inertia_check: Literal["definite", "strict", "lenient"] = "definite",
    locked_joints: Optional[Mapping[str, float]] = None,
) -> Model:
    """Load a URDF, rlmdl or rlkin model into the smallest capacity that holds it."""

class Model:
    """A robot model with its kinematics and dynamics; every method takes one state or a batch."""

    @property
    def name(self) -> str: ...
    @property
    def path(self) -> str: ...
    @property
    def format(self) -> Literal["urdf", "rlmdl", "rlkin"]: ...
    @property
    def nq(self) -> int: ...
    @property
    def nv(self) -> int: ...
    @property
    def capacity(self) -> int: ...
    @property
    def joint_names(self) -> list[str]: ...
    @property
    def frames(self) -> list[str]: ...
    @property
    def lower_limits(self) -> Array: ...
    @property
    def upper_limits(self) -> Array: ...
    @property
    def velocity_limits(self) -> Array: ...
    @property
    def effort_limits(self) -> Array: ...
    @property
    def wraparound(self) -> list[bool]: ...
    @property
    def gravity_vector(self) -> Array: ...
    @property
    def warnings(self) -> list[str]: ...
    def neutral(self) -> Array: ...
    @overload
    def random_configuration(self, n: None = None, seed: int = 0) -> Array: ...
    @overload
    def random_configuration(self, n: int, seed: int = 0) -> Array: ...
    def normalize(self, q: ArrayLike) -> Array: ...
    def integrate(self, q: ArrayLike, v: ArrayLike, dt: float = 1.0) -> Array: ...
    def q_from_pinocchio(self, q: ArrayLike) -> Array: ...
    @overload
    def fk(self, q: ArrayLike, frame: None = None) -> dict[str, Array]: ...
    @overload
    def fk(self, q: ArrayLike, frame: str) -> Array: ...
    def jacobian(self, q: ArrayLike, frame: str) -> Array: ...
    def rnea(self, q: ArrayLike, v: ArrayLike, a: ArrayLike) -> Array: ...
    def aba(self, q: ArrayLike, v: ArrayLike, tau: ArrayLike) -> Array: ...
    def crba(self, q: ArrayLike) -> Array: ...
    def gravity(self, q: ArrayLike) -> Array: ...
    def nle(self, q: ArrayLike, v: ArrayLike) -> Array: ...
    def nonlinear_effects(self, q: ArrayLike, v: ArrayLike) -> Array: ...
    def coriolis(self, q: ArrayLike, v: ArrayLike) -> Array: ...
    def rnea_derivatives(
        self, q: ArrayLike, v: ArrayLike, a: ArrayLike
    ) -> Tuple[Array, Array, Array]: ...
    def aba_derivatives(
        self, q: ArrayLike, v: ArrayLike, tau: ArrayLike
    ) -> Tuple[Array, Array, Array]: ...
    def gravity_derivatives(self, q: ArrayLike) -> Array: ...
    def ik(
        self,
        frame: str,
        target: ArrayLike,
        q0: Optional[ArrayLike] = None,
        method: Literal["dls", "svd", "transpose"] = "dls",
        damping: float = 1e-3,
        epsilon: float = 1e-6,
        max_iterations: int = 10_000,
        seed: Optional[int] = None,
    ) -> Array: ...

class JerkLimited:
    """Time-optimal jerk-limited rest-to-rest motion, axes synchronised (rl-core's JerkLimited)."""

    def __init__(
        self,
        start: ArrayLike,
        goal: ArrayLike,
        max_velocity: Union[float, ArrayLike],
        max_acceleration: Union[float, ArrayLike],
        max_jerk: Union[float, ArrayLike],
    ) -> None: ...
    @property
    def duration(self) -> float: ...
    @property
    def axes(self) -> int: ...
    @property
    def axis_durations(self) -> Array: ...
    def phase_ends(self, axis: int) -> Array: ...
    def sample(self, t: Union[float, ArrayLike]) -> Tuple[Array, Array, Array, Array]: ...
    def __call__(self, t: Union[float, ArrayLike]) -> Array: ...

Limit = Union[float, ArrayLike]
Sync = Literal["time", "time_if_necessary", "phase", "none"]

def otg(
    current_position: ArrayLike,
    target_position: Limit,
    max_velocity: Limit,
    max_acceleration: Limit,
    max_jerk: Limit,
    *,
    current_velocity: Optional[Limit] = None,
    current_acceleration: Optional[Limit] = None,
    target_velocity: Optional[Limit] = None,
    target_acceleration: Optional[Limit] = None,
    min_velocity: Optional[Limit] = None,
    min_acceleration: Optional[Limit] = None,
    min_position: Optional[Limit] = None,
    max_position: Optional[Limit] = None,
    interface: Literal["position", "velocity"] = "position",
    synchronization: Sync = "time",
    minimum_duration: Optional[float] = None,
    waypoints: Optional[ArrayLike] = None,
) -> OtgTrajectory:
    """The time-optimal jerk-limited trajectory from the current to the target state
    (rl-core's online trajectory generator; Ruckig's durations)."""

class OtgTrajectory:
    """A trajectory of `otg`: duration, each axis' own shortest duration, samples."""

    @property
    def duration(self) -> float: ...
    @property
    def axes(self) -> int: ...
    @property
    def min_durations(self) -> Optional[Array]: ...
    @property
    def sections(self) -> Array: ...
    def sample(self, t: Union[float, ArrayLike]) -> Tuple[Array, Array, Array, Array]: ...
    def __call__(self, t: Union[float, ArrayLike]) -> Array: ...

class Otg:
    """The online trajectory generator of a control loop: one call per cycle."""

    def __init__(
        self,
        cycle: float,
        position: ArrayLike,
        velocity: Optional[Limit] = None,
        acceleration: Optional[Limit] = None,
    ) -> None: ...
    def update(
        self,
        target_position: Limit,
        max_velocity: Limit,
        max_acceleration: Limit,
        max_jerk: Limit,
        *,
        target_velocity: Optional[Limit] = None,
        target_acceleration: Optional[Limit] = None,
        min_velocity: Optional[Limit] = None,
        min_acceleration: Optional[Limit] = None,
        min_position: Optional[Limit] = None,
        max_position: Optional[Limit] = None,
        interface: Literal["position", "velocity"] = "position",
        synchronization: Sync = "time",
        minimum_duration: Optional[float] = None,
        waypoints: Optional[ArrayLike] = None,
    ) -> Tuple[Array, Array, Array, bool]: ...
    def step(self) -> Tuple[Array, Array, Array, bool]: ...
    def brake(
        self,
        max_velocity: Limit,
        max_acceleration: Limit,
        max_jerk: Limit,
        *,
        min_velocity: Optional[Limit] = None,
        min_acceleration: Optional[Limit] = None,
        synchronization: Sync = "phase",
    ) -> None: ...
    @property
    def state(self) -> Tuple[Array, Array, Array]: ...
    @property
    def time(self) -> float: ...
    @property
    def duration(self) -> float: ...
    @property
    def axes(self) -> int: ...

class Scene:
    """A robot among obstacles: collision and distance queries (rl-sg)."""

    def __init__(
        self,
        model: PathLike,
        env: Optional[PathLike] = None,
        srdf: Optional[PathLike] = None,
        kinematics: Optional[PathLike] = None,
        floating_base: bool = False,
        mimic_independent: bool = False,
        package_dirs: Sequence[PathLike] = (),
        convex_hulls: bool = False,
    ) -> None: ...
    @property
    def nq(self) -> int: ...
    @property
    def models(self) -> list[str]: ...
    def check(self, q: ArrayLike) -> dict[str, Any]: ...
    def is_colliding(self, q: ArrayLike, environment: bool = True) -> Union[bool, BoolArray]: ...
    def distance(self, q: ArrayLike, environment: bool = True) -> Union[float, Array]: ...

class PlanOutcome:
    """What Planner.plan found."""

    solved: bool
    path: Optional[Array]
    raw_path: Optional[Array]
    planner: str
    planning_time: float
    optimization_time: float
    iterations: int
    collision_checks: int
    length: float
    raw_length: float
    certificate: Optional[dict[str, Any]]
    joint_names: list[str]

class Planner:
    """A URDF robot for planning (rl-plan): kinematics, collision meshes, spheres."""

    def __init__(
        self,
        urdf: PathLike,
        srdf: Optional[PathLike] = None,
        spheres: Optional[PathLike] = None,
        raw_spheres: bool = False,
        limits: Optional[Mapping[str, Tuple[float, float]]] = None,
    ) -> None: ...
    @property
    def joint_names(self) -> list[str]: ...
    @property
    def nq(self) -> int: ...
    def request(self, request: PathLike) -> Tuple[Array, Array]: ...
    def plan(
        self,
        scene: PathLike,
        request: Optional[PathLike] = None,
        start: Optional[ArrayLike] = None,
        goal: Optional[ArrayLike] = None,
        planner: str = "rrt-connect",
        seed: int = 0,
        time: float = 1.0,
        checker: Literal["hybrid", "spheres", "exact"] = "hybrid",
        sampler: Literal["halton", "uniform", "gaussian", "bridge"] = "halton",
        optimizer: Literal["simple", "advanced", "none"] = "simple",
        resolution: float = 1.0 / 32.0,
        range: Optional[float] = None,
        dynamic_domain: bool = True,
        certify: bool = True,
        certify_margin: float = 1e-4,
    ) -> PlanOutcome: ...
    def certify(self, path: ArrayLike, scene: PathLike, margin: float = 1e-4) -> dict[str, Any]: ...
    def is_valid(self, q: ArrayLike, scene: PathLike) -> Union[bool, BoolArray]: ...

def plan(
    urdf: PathLike,
    scene: PathLike,
    request: Optional[PathLike] = None,
    srdf: Optional[PathLike] = None,
    spheres: Optional[PathLike] = None,
    **options: Any,
) -> PlanOutcome:
    """Planner(urdf, srdf, spheres).plan(scene, request, **options)."""

class ControlRun:
    """A supervised controller run (rl run) against a fake or a real device."""

    def __init__(
        self,
        device: str = "fake-h7",
        model: Union[None, Model, PathLike] = None,
        duration: Optional[float] = None,
        speed: float = 0.25,
        waypoints: Optional[ArrayLike] = None,
        rate: Optional[float] = None,
        priority: int = 80,
        cpus: Sequence[int] = (),
        lock_memory: bool = False,
        supervision: bool = True,
        tracking_bound: Union[None, float, ArrayLike] = None,
        telemetry: bool = True,
        follow: bool = False,
        input_timeout: Optional[float] = None,
    ) -> None: ...
    @property
    def follows(self) -> bool: ...
    def send_position(
        self, position: ArrayLike, velocity: Optional[ArrayLike] = None
    ) -> None: ...
    def send_velocity(self, velocity: ArrayLike) -> None: ...
    @property
    def joints(self) -> list[str]: ...
    @property
    def plan_duration(self) -> float: ...
    @property
    def scheduling(self) -> str: ...
    @property
    def warnings(self) -> list[str]: ...
    def poll(self, timeout: float = 0.1) -> Optional[dict[str, Any]]: ...
    def stop(self, now: bool = False) -> None: ...
    def wait(self) -> dict[str, Any]: ...
    def join(self) -> dict[str, Any]: ...
    def telemetry(self) -> dict[str, npt.NDArray[Any]]: ...
