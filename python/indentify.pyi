"""Type stub of `indentify`: identify constitutive-law parameters from instrumented
indentation curves (units N, mm, s, MPa; arrays are float64 numpy arrays)."""

import os
from collections.abc import Callable, Mapping, Sequence
from typing import Any, Literal, Optional, TypedDict, Union

import numpy as np
import numpy.typing as npt

__version__: str

FloatArray = npt.NDArray[np.float64]

ConfigLike = Union[str, "os.PathLike[str]", Mapping[str, Any], None]
"""A RON file's path, RON text (a str containing "(" that is no file's path), a dict with the RON structure, or
None for the embedded R1 example (examples/r1-maxwell.ron)."""

Sets = Union[Mapping[str, Union[float, int, bool, str]], Sequence[str], None]
"""Overrides by dotted path, e.g. {"law.E": 25000, "specimen.nr": 8}, or ["law.E=25000"]."""

DataLike = Union[
    str,
    "os.PathLike[str]",
    "Record",
    Mapping[str, npt.ArrayLike],
    npt.ArrayLike,
    None,
]
"""A curve file (CSV t, F [, h]) or instrument record path, a Record, a dict with arrays t
(s), F (N) and optionally h (mm), or an array of shape (n, 2) [t, F] or (n, 3) [t, h, F]."""

class Error(Exception):
    """Base class of indentify's errors: `str(e)` is the whole message chain, one line each."""

    messages: list[str]
    """The message chain, outermost first."""
    kind: Literal["config", "data", "solver", "io"]

class ConfigError(Error):
    """An invalid configuration or option (syntax, unknown key, out-of-range value, sets)."""

class DataError(Error):
    """Data that cannot be used (missing or malformed file, NaN, wrong shape, too short)."""

class SolverError(Error):
    """The solvers failed (a step that does not converge even after cutting)."""

    partial: dict[str, FloatArray]
    """`simulate` only: the curve up to the failure."""

class IoError(Error):
    """An output cannot be written (unwritable folder, a report folder of another run)."""

class Record:
    """An instrumented-indentation record (s, mm, N)."""

    name: str
    """The test's name (file name, with the test for multi-test files)."""
    @property
    def t(self) -> FloatArray:
        """Time (s)."""
    @property
    def h(self) -> FloatArray:
        """Depth into the surface (mm)."""
    @property
    def F(self) -> FloatArray:
        """Force (N)."""
    @property
    def segment(self) -> Optional[npt.NDArray[np.uint32]]:
        """Segment id of each sample, or None when unknown."""
    @property
    def metadata(self) -> dict[str, Any]:
        """What the file says: format, instrument, tip, protocol, date, vendor results, ..."""
    @property
    def applied(self) -> list[dict[str, Any]]:
        """The preprocessing steps applied: {step, description, values}."""
    def __len__(self) -> int: ...

class GradientResult:
    """J (N^2) and dJ/dc; unpacks as `J, grad = indentify.gradient(...)`."""

    J: float
    gradient: dict[str, float]
    """{name: dJ/dc} in the law's order."""
    params: dict[str, float]
    """{name: value}: the point."""
    units: dict[str, str]
    names: list[str]
    forward_seconds: float
    adjoint_seconds: float
    def __iter__(self) -> Any: ...

class IterationRecord(TypedDict):
    """One iteration, as given to `progress` and listed in `Result.history`."""

    iteration: int
    params: dict[str, float]
    J: float
    grad_norm: float
    forward_solves: int
    adjoint_solves: int
    sensitivity_solves: int
    seconds: float

class Fit(TypedDict):
    """The curves at the schedule times."""

    t: FloatArray
    h: FloatArray
    F_data: FloatArray
    F_fit: FloatArray
    F_start: FloatArray

class Result:
    """The result of `identify`."""

    params: dict[str, float]
    """{name: final value} of every law parameter (free and held)."""
    std: dict[str, Optional[float]]
    """{name: standard deviation}; None for held or undetermined parameters."""
    correlation: FloatArray
    """Correlation matrix of the free parameters (p x p; 0 x 0 without identifiability)."""
    correlation_names: list[str]
    converged: bool
    stop_reason: str
    fit: Fit
    history: list[IterationRecord]
    parameters: list[dict[str, Any]]
    """Per parameter: name, unit, free, start, value, lower, upper, at_lower, at_upper."""
    free: dict[str, bool]
    bounds: dict[str, tuple[float, float]]
    J: float
    J_start: float
    iterations: int
    forward_solves: int
    adjoint_solves: int
    seconds: float
    """The optimizer's wall time (s)."""
    wall_seconds: float
    """The whole pipeline's wall time (s)."""
    law: str
    method: str
    data: str
    quality: Optional[dict[str, float]]
    truth: Optional[dict[str, float]]
    files: Optional[dict[str, Any]]
    tests: list["TestFit"]
    """A joint fit's tests in the configuration's order (empty for one test); `fit` then
    holds their curves end to end."""
    discretization: Optional["Discretization"]
    """The discretization check (None with refine=False or after an interruption)."""
    caveats: list[str]
    """What makes the result less than it looks (empty when nothing)."""
    oliver_pharr: Optional["OliverPharrBeside"]
    """The Oliver-Pharr analysis of the fitted record beside the FE result (result.json's
    `oliver_pharr`); without values and with `skipped` when the record cannot be analysed.
    None for synthesized data and joint fits (each of `tests` has its own)."""
    start: Optional[dict[str, Any]]
    """The closed-form start of start="closed-form" (result.json's start: method, values,
    half_space, rms_rel, seconds, notes); None otherwise."""

class OliverPharrBeside(TypedDict, total=False):
    """The O&P values of a fitted record beside the FE result (MPa, N/mm, mm, N)."""

    test: str
    """The analysed test's name."""
    E: float
    """Indentation modulus E_IT (MPa)."""
    H: float
    """Indentation hardness H_IT (MPa)."""
    Er: float
    S: float
    """Contact stiffness (N/mm)."""
    hc: float
    hmax: float
    Fmax: float
    strain_rate: Optional[float]
    srs: Optional[float]
    nu: float
    tip: str
    E_fe: Optional[float]
    """The fitted E (MPa)."""
    E_difference_pct: Optional[float]
    """100 (E_IT - E_fe) / E_fe."""
    why_they_differ: str
    skipped: str
    """Why there are no values (no unloading, a punch without an area function, ...)."""

class Discretization(TypedDict):
    """The fit re-run on a 2x refined mesh with twice the steps (`identify(refine=True)`)."""

    mesh: str
    steps: str
    rms: float
    """RMS of the force change (N)."""
    rms_rel: float
    """RMS of the force change over the largest force."""
    max_abs: float
    """Largest force change (N)."""
    shift: dict[str, Optional[float]]
    """Parameter shift the refinement implies (None: held or undetermined)."""
    relative_shift: dict[str, Optional[float]]
    exceeds_std: list[str]
    """Parameters whose shift exceeds their standard deviation."""
    seconds: float

class TestFit(TypedDict):
    """One test of a joint fit (`tests: [...]`)."""

    name: str
    data: str
    weight: float
    """w_k in J = sum_k w_k J_k."""
    default_weight: bool
    """Whether w_k is the default 1 / (n_k F_max,k^2)."""
    wJ: float
    """Its share w_k J_k of the final cost."""
    quality: Optional[dict[str, float]]
    fit: Fit
    oliver_pharr: Optional[OliverPharrBeside]
    """This test's record analysed beside the shared fitted E (None: synthesized data)."""

NoiseModel = Union[
    Literal["Residual", "RelativeEstimated"],
    Mapping[Literal["Relative", "Absolute"], float],
]
"""What the standard deviations assume about the force noise: "Residual" (one variance,
2J/(n-p)), "RelativeEstimated" (multiplicative, level from the residuals), {"Relative": f}
(standard deviation f |F|) or {"Absolute": s} (N); the last three by the sandwich covariance."""

class DesignCandidate(TypedDict):
    """One candidate protocol of `design`."""

    name: str
    tests: list[str]
    n_data: int
    std: dict[str, float]
    """{name: standard deviation} (parameter units; inf when undetermined)."""
    rel_std: dict[str, float]
    log_det: float
    """ln det of the information matrix of the scaled variables (-inf: singular)."""
    worst: tuple[str, float]
    undetermined: list[tuple[str, str]]
    condition_number: float
    weakest_direction: Optional[str]
    correlation: FloatArray

class Design(TypedDict):
    """The ranked candidates of `design`."""

    config: str
    noise: str
    names: list[str]
    nominal: dict[str, float]
    candidates: list[DesignCandidate]
    rank_d: list[int]
    """Candidate indices by decreasing log det (D-optimal)."""
    rank_worst: list[int]
    """Candidate indices by increasing worst relative deviation."""
    table: str
    threads: int
    seconds: float
    files: list[str]

class MapIndent(TypedDict):
    id: str
    data: str
    x: float
    y: float
    phase: Literal["A", "B"]

class Map(TypedDict):
    manifest: str
    base: str
    indents: list[MapIndent]
    phases: dict[str, dict[str, float]]

def read_record(
    path: Union[str, "os.PathLike[str]"],
    format: Optional[str] = None,
    test: Optional[int] = None,
    preprocessing: Union[Mapping[str, Any], bool, None] = None,
) -> Record:
    """Reads one record (CSV, Anton Paar, Hysitron TXT/.hld) and preprocesses it.

    format: None/"auto", "csv", "anton-paar", "anton-paar-multi", "hysitron-txt", "hld", "micro-materials".
    test: 1-based test of a multi-test file. preprocessing: None for the defaults (zero
    point, segments), False for none, or a dict like {"resample": {"n": 60}}.
    """

def simulate(
    config: ConfigLike = None,
    sets: Sets = None,
    noise: Optional[float] = None,
    seed: int = 1,
    test: Optional[int] = None,
) -> dict[str, FloatArray]:
    """Simulates the test: {"t" (s), "h" (mm), "F" (N), "a" (contact radius, mm)}.

    test: the 1-based test of a joint configuration (required for one)."""

def gradient(
    config: ConfigLike = None,
    data: DataLike = None,
    sets: Sets = None,
    test: Optional[int] = None,
) -> GradientResult:
    """J = 1/2 sum (F - F_data)^2 (N^2) and dJ/dc by the discrete adjoint.

    test: the 1-based test of a joint configuration (required for one)."""

def identify(
    config: ConfigLike = None,
    data: DataLike = None,
    sets: Sets = None,
    progress: Optional[Callable[[IterationRecord], object]] = None,
    *,
    out: Union[str, "os.PathLike[str]", None] = None,
    force: bool = False,
    method: Optional[Literal["bfgs", "lbfgs", "lbfgsb", "lm"]] = None,
    max_iterations: Optional[int] = None,
    free: Optional[Sequence[str]] = None,
    fixed: Union[Mapping[str, Optional[float]], Sequence[str], None] = None,
    start: Union[Mapping[str, float], Literal["oliver-pharr", "closed-form"], None] = None,
    noise: Optional[float] = None,
    seed: int = 1,
    noise_model: Optional[NoiseModel] = None,
    refine: bool = True,
) -> Result:
    """Identifies the parameters (GIL released; Ctrl-C stops after the iteration).

    refine=False skips the discretization check (the fit re-run on a refined mesh; its
    result is Result.discretization). free: a list of names, or one name as a str.

    A joint configuration (tests: [...]) is fitted as a whole (Result.tests). noise_model
    replaces the configuration's identify.noise. start="oliver-pharr" starts the free
    parameters from the Oliver-Pharr analysis of the record (as first_guess);
    start="closed-form" starts E (Maxwell: E and eta) from the closed-form pre-fit of the
    curve's loading and hold (Result.start says what was set)."""

def design(
    config: ConfigLike = None,
    sets: Sets = None,
    *,
    free: Optional[Sequence[str]] = None,
    fixed: Union[Mapping[str, Optional[float]], Sequence[str], None] = None,
    out: Union[str, "os.PathLike[str]", None] = None,
    jobs: Optional[int] = None,
) -> Design:
    """Ranks the `design` section's candidate protocols by the deviations they would give
    at the nominal (law) values under the section's stated noise (candidates in parallel)."""

def make_map(
    dir: Union[str, "os.PathLike[str]"],
    n: int = 10,
    noise: float = 0.02,
    seed: int = 1,
    coarse: bool = False,
    spacing: float = 0.05,
) -> Map:
    """Writes a synthetic two-phase Maxwell map (records, manifest.csv, base.ron)."""

def load_config(config: ConfigLike = None, sets: Sets = None) -> dict[str, Any]:
    """A validated configuration as a dict with the RON structure."""

def laws() -> list[dict[str, Any]]:
    """Every registered law: name, variant, summary, example, kinds, lists, parameters
    (name, set, unit, description, range, min, min_inclusive, max, max_inclusive,
    only_in) and forms (label, parameters); the data of `indentify laws --json`."""

PathLike = Union[str, "os.PathLike[str]"]

def analyze(
    file: PathLike,
    *,
    test: Optional[int] = None,
    tip: Optional[PathLike] = None,
    nu: float = 0.3,
    epsilon: str = "tip",
    beta: float = 1.0,
    fit_range: Optional[tuple[float, float]] = None,
    zero_point: Optional[bool] = None,
    out: Optional[PathLike] = None,
) -> dict[str, Any]:
    """Oliver-Pharr (ISO 14577) analysis of every test (or `test`, from 1): the dict of
    `indentify analyze --json` (tests[k]["E"], ["H"], ["Er"] in MPa, ["S"] in N/mm, ["hc"],
    ["hmax"] in mm, ["Fmax"] in N; tip["modulus"] the tip's own). tip: "berkovich",
    "cone:70.3", "sphere:10" (radius in um), "flat:50" or a tip file (.ron) of calibrate;
    epsilon: "tip", "m" or a number; out: analysis.json, analysis.csv and figures there."""

def calibrate(
    file: PathLike,
    *,
    modulus: float,
    nu: float,
    out: Optional[PathLike] = None,
    tests: Optional[Sequence[int]] = None,
    compliance: Optional[float] = None,
    terms: int = 3,
    beta: float = 1.0,
    fit_range: Optional[tuple[float, float]] = None,
) -> dict[str, Any]:
    """Frame compliance and ISO area function from a reference of known Young's modulus
    (MPa: fused silica 72000): the dict of `indentify calibrate --json`; out writes the tip
    file that analyze(tip=...) and punch: Calibrated(file: ...) read."""

class FirstGuess(TypedDict):
    starts: dict[str, float]
    op: dict[str, Any]
    notes: list[str]

def first_guess(
    config: ConfigLike = None,
    data: Optional[PathLike] = None,
    sets: Sets = None,
) -> FirstGuess:
    """Start values of the configuration's free parameters from the Oliver-Pharr analysis of
    its record (or of `data`): E = E_IT, sY from H/3, the viscous parameters from the hold."""
