import os
from dataclasses import dataclass
from typing import Any, Iterator, Literal, Mapping, Optional, Sequence, Union, overload

import numpy as np
import numpy.typing as npt

class SsiResult:
    @property
    def source(self) -> Literal["refined", "ssi"]: ...
    @property
    def frequency_hz(self) -> npt.NDArray[np.float64]: ...
    @property
    def damping_ratio(self) -> npt.NDArray[np.float64]: ...
    @property
    def frequency_se_hz(self) -> npt.NDArray[np.float64]: ...
    @property
    def damping_se(self) -> npt.NDArray[np.float64]: ...
    @property
    def shape(self) -> npt.NDArray[np.complex128]: ...
    @property
    def shape_se(self) -> npt.NDArray[np.float64]: ...
    @property
    def ssi_modes(self) -> npt.NDArray[np.float64]: ...
    @property
    def real_poles(self) -> npt.NDArray[np.float64]: ...
    @property
    def poles(self) -> npt.NDArray[np.float64]: ...
    @property
    def pole_status(self) -> list[str]: ...
    @property
    def misfit(self) -> Optional[float]: ...
    @property
    def not_refined(self) -> Optional[str]: ...
    def to_json(self) -> str: ...
    def to_dict(self) -> dict[str, Any]: ...
    def html(self, title: Optional[str] = ...) -> str: ...
    def write_shapes_uff(
        self,
        path: Union[str, os.PathLike[str]],
        points: Optional[Sequence[tuple[int, int]]] = ...,
        description: Optional[str] = ...,
    ) -> None: ...

class Report:
    def alarm_lines(self) -> list[str]: ...
    def html(self) -> str: ...
    def to_json(self) -> str: ...
    def to_dict(self) -> dict[str, Any]: ...

Model = Union[dict[str, Any], Literal["benchmark"]]
Validation = Union[dict[str, Any], tuple[npt.ArrayLike, npt.ArrayLike]]

def excite(
    fs: float = ...,
    *,
    excitation: Literal["multisine", "white", "sweep"] = ...,
    rms: float = ...,
    samples: int = ...,
    seed: int = ...,
    f_min: float = ...,
    f_max: float = ...,
) -> npt.NDArray[np.float64]: ...
def simulate(
    model: Model,
    u: npt.ArrayLike,
    fs: float,
    *,
    periodic: bool = ...,
    input_interpolation: Literal["band-limited", "linear"] = ...,
    oversample: int = ...,
    integrator: Literal["rk4", "newmark"] = ...,
    decimation: Literal["sample", "fir"] = ...,
    noise: float = ...,
    noise_seed: int = ...,
) -> npt.NDArray[np.float64]: ...
def identify(
    y: npt.ArrayLike,
    fs: float,
    mass: float,
    *,
    damping: Literal["spectrum", "cluster"] = ...,
    c: Optional[float] = ...,
    excitation_band: Optional[tuple[float, float]] = ...,
    period: Optional[int] = ...,
    linearization: Optional[Literal["paper", "harmonic"]] = ...,
    validate: Optional[Sequence[Validation]] = ...,
    profile: bool = ...,
    record: str = ...,
) -> Report: ...
def refine(
    u: npt.ArrayLike,
    y: npt.ArrayLike,
    fs: float,
    *,
    mass: Optional[float] = ...,
    start: Literal["linear", "zener", "bouc-wen"] = ...,
    input_interpolation: Literal["band-limited", "linear"] = ...,
    estimate: Optional[tuple[int, int]] = ...,
    test: Optional[Sequence[tuple[int, int]]] = ...,
    record: str = ...,
) -> Report: ...
def levels(
    records: Union[Sequence[npt.ArrayLike], dict[str, npt.ArrayLike]],
    fs: float,
    mass: Optional[float] = ...,
    *,
    by_simulation: bool = ...,
    data_periodic: bool = ...,
    fit_exponent: bool = ...,
    validate: Optional[Sequence[Validation]] = ...,
    masses: Optional[Sequence[float]] = ...,
    floors: Optional[Sequence[int]] = ...,
    quantity: Literal["acceleration", "velocity", "displacement"] = ...,
    load_floors: Optional[Sequence[int]] = ...,
    predict: Optional[Sequence[float]] = ...,
) -> Report: ...

def track(
    records: Sequence[Union[npt.ArrayLike, str, os.PathLike[str]]],
    fs: Optional[float],
    *,
    times: Optional[Sequence[float]] = ...,
    covariates: Optional[Union[npt.ArrayLike, Mapping[str, npt.ArrayLike]]] = ...,
    training: Optional[int] = ...,
    whiten: bool = ...,
    environment_model: bool = ...,
    reference: Optional[Union[str, os.PathLike[str], SsiResult]] = ...,
    block_rows: Optional[int] = ...,
    lag_seconds: Optional[float] = ...,
    lag_periods: Optional[tuple[float, float]] = ...,
    decimate: Optional[int] = ...,
    max_order: Optional[int] = ...,
    order_step: int = ...,
    references: Optional[Sequence[int]] = ...,
    df: Optional[float] = ...,
    dzeta: Optional[float] = ...,
    dmac: Optional[float] = ...,
    dreal: Optional[float] = ...,
    refine: bool = ...,
    joint: bool = ...,
    ssi_errors: Optional[int] = ...,
    max_damping: Optional[float] = ...,
    client: Optional[Any] = ...,
    level_covariate: bool = ...,
    calibrate: bool = ...,
    joint_chart: bool = ...,
) -> Report: ...

class Follow:
    report: Optional[Report]
    taken: list[str]
    @property
    def waiting(self) -> int: ...
    def __iter__(self) -> Iterator[str]: ...
    def __next__(self) -> str: ...

def follow(
    inputs: Union[str, os.PathLike[str], Sequence[Union[str, os.PathLike[str]]]],
    fs: Optional[float] = ...,
    *,
    covariates: Optional[Union[str, os.PathLike[str]]] = ...,
    training: Optional[int] = ...,
    poll: float = ...,
    passes: Optional[int] = ...,
    whiten: bool = ...,
    environment_model: bool = ...,
    reference: Optional[Union[str, os.PathLike[str], SsiResult]] = ...,
    block_rows: Optional[int] = ...,
    lag_seconds: Optional[float] = ...,
    lag_periods: Optional[tuple[float, float]] = ...,
    decimate: Optional[int] = ...,
    max_order: Optional[int] = ...,
    order_step: int = ...,
    references: Optional[Sequence[int]] = ...,
    df: Optional[float] = ...,
    dzeta: Optional[float] = ...,
    dmac: Optional[float] = ...,
    dreal: Optional[float] = ...,
    refine: bool = ...,
    joint: bool = ...,
    ssi_errors: Optional[int] = ...,
    max_damping: Optional[float] = ...,
    level_covariate: bool = ...,
    calibrate: bool = ...,
    joint_chart: bool = ...,
) -> Follow: ...

def track_estimates(
    estimates: Union[str, os.PathLike[str]],
    *,
    covariates: Optional[Union[str, os.PathLike[str]]] = ...,
    training: Optional[int] = ...,
    whiten: bool = ...,
    environment_model: bool = ...,
    calibrate: bool = ...,
    joint_chart: bool = ...,
) -> Report: ...

@dataclass(frozen=True)
class Record:
    data: npt.NDArray[np.float64]
    names: list[str]
    fs: Optional[float]
    points: Optional[list[tuple[int, int]]]
    path: str

def read(
    path: Union[str, os.PathLike[str]],
    *,
    format: Optional[Literal["csv", "npy", "npz", "mat", "uff"]] = ...,
    variable: Optional[str] = ...,
    delimiter: Optional[Literal[",", ";", "\t"]] = ...,
) -> Record: ...

@dataclass(frozen=True)
class ModeShape:
    number: int
    frequency_hz: float
    damping_ratio: float
    nodes: list[int]
    motion: npt.NDArray[np.complex128]

@dataclass(frozen=True)
class Shapes:
    nodes: dict[int, tuple[float, float, float]]
    modes: list[ModeShape]

def read_shapes(path: Union[str, os.PathLike[str]]) -> Shapes: ...

@overload
def ssi(
    y: npt.ArrayLike,
    fs: float,
    *,
    block_rows: Optional[int] = ...,
    lag_seconds: Optional[float] = ...,
    lag_periods: Optional[tuple[float, float]] = ...,
    decimate: Optional[int] = ...,
    max_order: Optional[int] = ...,
    order_step: int = ...,
    references: Optional[Sequence[int]] = ...,
    df: Optional[float] = ...,
    dzeta: Optional[float] = ...,
    dmac: Optional[float] = ...,
    dreal: Optional[float] = ...,
    refine: bool = ...,
    joint: bool = ...,
    ssi_errors: Optional[int] = ...,
    max_damping: Optional[float] = ...,
    channels: Optional[Sequence[str]] = ...,
    record: str = ...,
    fdd: bool = ...,
    setups: None = ...,
    geometry: None = ...,
    lines: None = ...,
    records_anywhere: Literal[False] = ...,
    rigid_floors: Literal[False] = ...,
) -> SsiResult: ...
@overload
def ssi(
    y: None = ...,
    fs: Optional[float] = ...,
    *,
    block_rows: Optional[int] = ...,
    lag_seconds: Optional[float] = ...,
    lag_periods: Optional[tuple[float, float]] = ...,
    decimate: Optional[int] = ...,
    max_order: Optional[int] = ...,
    order_step: int = ...,
    references: None = ...,
    df: Optional[float] = ...,
    dzeta: Optional[float] = ...,
    dmac: Optional[float] = ...,
    dreal: Optional[float] = ...,
    refine: bool = ...,
    joint: bool = ...,
    ssi_errors: Optional[int] = ...,
    max_damping: Optional[float] = ...,
    channels: None = ...,
    record: str = ...,
    fdd: Literal[False] = ...,
    setups: Union[str, os.PathLike[str]],
    geometry: Optional[Union[str, os.PathLike[str]]] = ...,
    lines: Optional[Union[str, os.PathLike[str]]] = ...,
    records_anywhere: bool = ...,
    rigid_floors: bool = ...,
) -> Report: ...

def amplitude(
    y: Union[npt.ArrayLike, Sequence[npt.ArrayLike]],
    fs: float,
    *,
    modes: Optional[Sequence[float]] = ...,
    measured: Literal["displacement", "velocity", "acceleration"] = ...,
    amplitude_of: Optional[Literal["displacement", "velocity", "acceleration"]] = ...,
    levels: int = ...,
    cycles: float = ...,
    groups: int = ...,
    min_triggers: int = ...,
    band: Optional[float] = ...,
    method: Literal["envelope", "extrema"] = ...,
    period: Optional[int] = ...,
    block_rows: Optional[int] = ...,
    lag_seconds: Optional[float] = ...,
    lag_periods: Optional[tuple[float, float]] = ...,
    decimate: Optional[int] = ...,
    max_order: Optional[int] = ...,
    order_step: int = ...,
    references: Optional[Sequence[int]] = ...,
    df: Optional[float] = ...,
    dzeta: Optional[float] = ...,
    dmac: Optional[float] = ...,
    dreal: Optional[float] = ...,
    refine: bool = ...,
    joint: bool = ...,
    ssi_errors: Optional[int] = ...,
    max_damping: Optional[float] = ...,
    floors: Optional[Sequence[int]] = ...,
    record: str = ...,
) -> Report: ...
