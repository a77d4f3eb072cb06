"""Type stubs of the compiled module ``vesicle._vesicle`` (re-exported by ``vesicle``)."""

import os
from typing import Any, Callable, Iterator, Literal, Mapping, Sequence

import numpy as np
import numpy.typing as npt

__version__: str

Overrides = Mapping[str, Any] | Sequence[str] | None
StopReason = Literal["stationary", "t_end", "max_steps", "wall_time", "stalled", "callback"]
Record = dict[str, float | int]
PathLike = str | os.PathLike[str]

class InvalidInput(ValueError):
    """Invalid input, with the command line's message; ``field`` is the dotted scene key."""

    field: str
    reason: str

class BlowUp(RuntimeError):
    """A step failed; the simulation keeps its last good state."""

    step: int
    t: float
    dt: float
    check: str
    cause: Literal["blew up", "volume", "area", "energy rise"]

class DeviceError(RuntimeError):
    """The device failed during a run; the simulation keeps its last good state."""

    step: int
    t: float

class StepView:
    """What a callback is given: the step's record, read as a mapping (``view["t"]``,
    ``dict(view)``) or as attributes (``view.t``), and ``phi`` while the callback runs."""

    step: int
    t: float
    dt: float
    energy: float
    area: float
    volume: float
    reduced_volume: float
    reduced_energy: float
    sigma: float
    residual: float
    rate: float
    rejected: int
    wall_seconds: float
    def __getitem__(self, key: str) -> float | int: ...
    def __contains__(self, key: object) -> bool: ...
    def __len__(self) -> int: ...
    def __iter__(self) -> Iterator[str]: ...
    def keys(self) -> list[str]: ...
    def values(self) -> list[float | int]: ...
    def items(self) -> list[tuple[str, float | int]]: ...
    def get(self, key: str, default: Any = None) -> Any: ...
    def to_dict(self) -> Record:
        """The record as a dict."""
    @property
    def phi(self) -> npt.NDArray[np.float64]:
        """φ of this state on the full box, read-only, shape n; only inside the callback."""

Callback = Callable[[StepView], bool | None]

class Scene:
    """A validated scene: a dict or a scene-file path, with ``--set``-like overrides."""

    def __init__(self, spec: Mapping[str, Any] | str | os.PathLike[str], overrides: Overrides = None) -> None: ...
    def with_overrides(self, overrides: Mapping[str, Any] | Sequence[str]) -> Scene:
        """This scene with more overrides, validated again."""
    def to_dict(self) -> dict[str, Any]:
        """The scene with every default explicit."""
    def to_json(self) -> str:
        """The scene as the text of a scene file."""
    @property
    def dim(self) -> int: ...
    @property
    def n(self) -> list[int]: ...
    @property
    def h(self) -> float: ...
    @property
    def eps(self) -> float: ...
    @property
    def dt(self) -> float: ...

class Simulation:
    """A scene's simulation, prepared and constrained as ``vesicle run`` does."""

    def __init__(self, scene: Scene | Mapping[str, Any] | str | os.PathLike[str], threads: int | None = None) -> None: ...
    @staticmethod
    def resume(folder: str | os.PathLike[str], overrides: Overrides = None, threads: int | None = None) -> Simulation:
        """Continue the run whose checkpoint.bin is in ``folder``, exactly."""
    def run(
        self,
        until: float | None = None,
        max_steps: int | None = None,
        stop_residual: float | None = None,
        callback: Callback | None = None,
        every: int = 1,
        out: PathLike | None = None,
    ) -> StopReason:
        """Step until a stop rule fires; the reason it stopped. The scene's output schedules
        apply: written into ``out`` as ``vesicle run`` writes them, else snapshots kept in
        memory (take_snapshots())."""
    def step(self, n: int = 1, callback: Callback | None = None, every: int = 1, out: PathLike | None = None) -> StopReason:
        """Take ``n`` steps."""
    def take_snapshots(self) -> list[tuple[int, float, npt.NDArray[np.float64]]]:
        """The snapshots kept by runs without ``out``, handed over: (step, t, phi)."""
    def checkpoint(self, folder: str | os.PathLike[str]) -> None:
        """Write folder/checkpoint.bin (atomically) and folder/timeseries.csv."""
    @property
    def scene(self) -> Scene: ...
    @property
    def t(self) -> float: ...
    @property
    def step_count(self) -> int: ...
    @property
    def dt(self) -> float: ...
    @property
    def record(self) -> Record: ...
    @property
    def energy(self) -> float: ...
    @property
    def area(self) -> float: ...
    @property
    def volume(self) -> float: ...
    @property
    def reduced_volume(self) -> float: ...
    @property
    def reduced_energy(self) -> float: ...
    @property
    def sigma(self) -> float: ...
    @property
    def residual(self) -> float: ...
    @property
    def phi(self) -> npt.NDArray[np.float64]:
        """φ on the full box, read-only, shape n."""
    @phi.setter
    def phi(self, value: npt.ArrayLike) -> None:
        """Set φ (shape n, finite, |φ| ≤ 5, even about the mirror planes): the engine is
        built again on it."""
    @property
    def history(self) -> dict[str, npt.NDArray[Any]]:
        """The time series, one array per timeseries.csv column."""
    @property
    def threads(self) -> int: ...
    def surface(self) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.int64], float, float, float]:
        """(vertices, faces, area, volume, v) of the φ = 0 surface (3D)."""
    def levelset(self, refined: bool = False) -> dict[str, float]:
        """{"area", "volume", "reduced_volume"} of the φ = 0 level set."""
    def write_npy(self, path: str | os.PathLike[str]) -> None: ...
    def write_vti(self, path: str | os.PathLike[str], name: str = "phi") -> None: ...
    def write_ply(self, path: str | os.PathLike[str]) -> None: ...
    def write_png(self, path: str | os.PathLike[str], title: str | None = None) -> None: ...
    def write_charts(self, folder: str | os.PathLike[str]) -> None: ...

def axisym_solve(
    branch_name: str,
    v: float,
    nodes: int = 241,
    c0: float = 0.0,
    ade: tuple[float, float] | None = None,
    bc: float | None = None,
) -> dict[str, Any]: ...
def axisym_follow(branch_name: str, vs: Sequence[float], nodes: int = 241, c0: float = 0.0) -> dict[str, Any]: ...
def axisym_updown(v: float, nodes: int = 241) -> list[dict[str, Any]]: ...
def cli(args: Sequence[str]) -> int: ...
def studies() -> list[tuple[str, str]]:
    """The command line's studies: (name, description)."""
def study(
    name: str,
    file: PathLike,
    out: PathLike,
    quick: bool = False,
    force: bool = False,
    overrides: Overrides = None,
) -> dict[str, dict[str, npt.NDArray[Any]]]:
    """Run ``vesicle study NAME FILE --out OUT``; its tables, typed."""
