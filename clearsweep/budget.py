"""Work and memory a resolved configuration implies, bounded before anything runs.

A config can be valid field by field and still ask for a run that cannot
finish: ``solver.duration: 1e6`` means a 75 GiB output array,
``solver.dt: 1e-300`` more RK4 steps than the age of the universe allows,
``wear.map: [100000, 100000]`` two 80 GB wear maps. :func:`estimate` counts
the output-grid RK4 steps and the bytes of the arrays a case holds (the
kernel's saved rows, the per-row output variables and the wear maps);
:func:`check_budget` refuses, quoting the estimate, above
:data:`MAX_OUTPUT_BYTES` or :data:`MAX_STEPS` unless ``allow_large``
(``--allow-large``). Both ``clearsweep run`` (through
:func:`clearsweep.simulation.preflight`) and sweep expansion call it.
"""

from __future__ import annotations

import functools
import math
import os
import sys
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .config import DEFAULTS, Config, ConfigError

__all__ = ["Estimate", "estimate", "check_budget", "format_bytes", "MAX_OUTPUT_BYTES", "MAX_STEPS",
           "PlanCosts", "WearPace", "plan_costs", "read_plan_costs", "clearance_joints", "step_seconds",
           "case_seconds", "assembly_seconds", "life_seconds", "sweep_seconds",
           "spectrum_seconds", "ensemble_seconds",
           "MAX_READ_BYTES", "largest_variable", "machine_memory",
           "memory_limit"]

#: Largest memory for one case's arrays [bytes] without ``allow_large``.
MAX_OUTPUT_BYTES = 4 * 2 ** 30
#: Most output-grid RK4 steps of one case without ``allow_large`` (sub-steps come on top).
MAX_STEPS = 10 ** 9
#: Largest variable [bytes] that ``report``, ``plot`` and ``sensitivity`` read from a results
#: file, as its metadata declares it before anything is read: they read whole variables, and
#: a file may declare sizes that no clearsweep run writes (two billion time rows, 15 GiB).
MAX_READ_BYTES = MAX_OUTPUT_BYTES
#: float64 per saved row that the kernel keeps besides N_Y + N_D: time, wear_depth_max (2).
_KERNEL_EXTRA_PER_ROW = 3
_FLOAT = 8


def format_bytes(n: float) -> str:
    """``n`` bytes in binary units (``74.5 GiB``)."""
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if abs(n) < 1024 or unit == "PiB":
            return f"{n:.3g} {unit}" if unit != "B" else f"{int(n)} B"
        n /= 1024
    return f"{n:.3g} PiB"      # pragma: no cover


#: The costs the plans charge, measured by benchmarks/calibrate_plan.py on this project's
#: 2-core x86-64 machine (the file records when, where and under what load).
PLAN_COSTS_FILE = Path(__file__).resolve().parent / "data" / "plan_costs.yaml"
#: The joints in the order the costs file names them.
_JOINTS = ("O", "A", "B", "P")


@dataclass(frozen=True)
class WearPace:
    """How fast a socket wears, as a life plan walks it to ``life.cycles``
    (:func:`clearsweep.service_life.forecast_blocks`), fitted to a reference life run by
    benchmarks/calibrate_plan.py.

    The deepest bin of a ball-and-socket joint at depth h [m] deepens by
    r(h) = K / (d + h) per revolution, d = K / r0: the contact cap's area grows with the
    depth under it (docs/physics.md 5.2, A = 2 pi R_j h_c), so a worn-in socket's depth
    goes as the square root of the revolutions. A config's K and r0 are the reference's
    scaled by Archard's k (times ``wear.amplification``) and by the clearance (the cap's
    area goes as 1 / c); its loads, speed and dynamics are taken to be the reference's.

    Attributes
    ----------
    first_rate_m : float
        r0: the reference's deepest bin after its first block, per revolution [m].
    growth_m2 : float
        K [m^2 per revolution], fitted so that the reference's jumps reach the revolutions
        its run reached.
    clearance_m : float
        The reference joint's radial clearance [m].
    wear_coefficient_m2_per_N : float
        Archard's k of the reference joint's worn surface [m^2/N].
    reference : str
        What was run (config, joint, blocks).
    """

    first_rate_m: float
    growth_m2: float
    clearance_m: float
    wear_coefficient_m2_per_N: float
    reference: str

    def scaled(self, clearance: float, wear_coefficient: float) -> tuple[float, float]:
        """(r0, K) of a socket of ``clearance`` [m] whose surface wears with
        ``wear_coefficient`` (Archard's k times ``wear.amplification``) [m^2/N]."""
        factor = (wear_coefficient / self.wear_coefficient_m2_per_N) * (clearance / self.clearance_m)
        return self.first_rate_m * factor, self.growth_m2 * factor


@dataclass(frozen=True)
class PlanCosts:
    """What a plan charges, in seconds of one worker's wall time (clearsweep/data/plan_costs.yaml).

    Attributes
    ----------
    step_s : float
        One output-grid RK4 step of the ideal mechanism, as a sweep's worker runs it.
    joint_step_s : dict
        What each joint with clearance adds to every step: ``"A"`` and ``"B"`` a ball in its
        socket, ``"O"`` the crank's journal, ``"P"`` the block on the guide's faces.
    row_s : float
        Each saved row of a case that keeps its time series (``run``, ``store: full``).
    case_s : float
        Each case beyond its steps: packing, the seated start, the summaries, its part.
    map_bin_s : float
        Each bin of each joint's wear map that a case keeping its time series writes.
    block_s : float
        Each life block beyond its steps: the jump (wear rates, the grown map), its row.
    run_start_s : float
        A ``run``'s or a ``life`` run's fixed cost: the interpreter, the imports, the kernel
        from the cache.
    sweep_start_s : float
        A sweep's fixed cost: the driver's and the workers' start, the kernel from the cache.
    assemble_case_s : float
        What a sweep's driver spends on each case: its checks before the run, its part
        checked and copied into the file and the statistics after it.
    assemble_row_s : float
        What the driver spends on each saved row of a case that keeps its time series.
    compile_s : float
        A cold compile of the RK4 kernel (an empty Numba cache).
    measured : dict
        When, where and under what load the file was measured.
    wear_pace : WearPace or None
        A socket's wear pace, which a life plan walks to ``life.cycles`` with; None in a
        file without one (the plan then walks to the wear limits alone).
    spectrum_s : float
        What a sweep's process pays once, with its first case whose settled window holds a
        spectrum (``motion.MIN_SEGMENT_REVOLUTIONS`` revolutions): the import of the
        spectrum's scipy.signal. 0 in a file without it.
    ensemble_s : float
        What a sweep's driver spends on an ensemble's statistics once its cases have run
        (scipy.stats and the intervals). 0 in a file without it.
    slider_crank_step_s : float or None
        One output-grid RK4 step of the ideal slider-crank (``mechanism.kind:
        slider_crank``), as a worker runs it; None in a file without it (:attr:`step_s`).
    joint_revolution_s : dict
        What each joint with clearance of the slider-crank (``"O"``, ``"A"``, ``"B"``) adds
        per crank revolution beyond its step's share: its impacts, whose sub-steps the
        kernel takes at the contact's own time scale, about a fixed number a revolution
        whatever the speed and step. Empty in a file without it.
    """

    step_s: float
    joint_step_s: dict
    row_s: float
    case_s: float
    map_bin_s: float
    block_s: float
    run_start_s: float
    sweep_start_s: float
    assemble_case_s: float
    assemble_row_s: float
    compile_s: float
    measured: dict
    wear_pace: WearPace | None = None
    spectrum_s: float = 0.0
    ensemble_s: float = 0.0
    slider_crank_step_s: float | None = None
    joint_revolution_s: dict = field(default_factory=dict)

    def step_seconds(self, joints: Iterable[str], kind: str = "rssp",
                     steps_per_revolution: float = math.inf) -> float:
        """One step's cost [s] with clearance at ``joints`` (``"OABP"``, ``("B",)``, ...) of
        mechanism ``kind``; the slider-crank's joints' cost per revolution shared by the
        ``steps_per_revolution`` of the case."""
        joints = set(joints)
        base = self.step_s
        if kind == "slider_crank":
            base = self.step_s if self.slider_crank_step_s is None else self.slider_crank_step_s
            base += sum(self.joint_revolution_s.get(j, 0.0) for j in joints) / steps_per_revolution
        return base + sum(self.joint_step_s[j] for j in joints)


@functools.lru_cache(maxsize=4)
def read_plan_costs(path: str | None = None) -> PlanCosts:
    """The plan costs of ``path`` (default :data:`PLAN_COSTS_FILE`), read once per process."""
    from .schema import read_yaml

    source = str(path if path is not None else PLAN_COSTS_FILE)
    doc = read_yaml(Path(source), source)
    names = ("step_s", "row_s", "case_s", "map_bin_s", "block_s", "run_start_s",
             "sweep_start_s", "assemble_case_s", "assemble_row_s", "compile_s")
    try:
        shares = {j: float(doc["joint_step_s"][j]) for j in _JOINTS}
        values: dict[str, Any] = {name: float(doc[name]) for name in names}
    except (KeyError, TypeError, ValueError) as exc:
        raise ConfigError(None, None, "a plan-costs file as benchmarks/calibrate_plan.py writes "
                          f"it: numbers {', '.join(names)} and joint_step_s of "
                          f"{', '.join(_JOINTS)} ({type(exc).__name__}: {exc})", source) from None
    if not all(math.isfinite(v) and v >= 0.0 for v in [*values.values(), *shares.values()]):
        raise ConfigError(None, None, "a plan-costs file of finite costs >= 0", source)
    return PlanCosts(joint_step_s=shares, measured=dict(doc.get("measured") or {}),
                     wear_pace=_wear_pace(doc.get("wear_pace"), source),
                     **_later_costs(doc, source), **values)


def _later_costs(doc: Any, source: str) -> dict:
    """The costs a plan-costs file may lack (a file written before them charges 0 for each,
    and the RSSP's step for the slider-crank's): ``spectrum_s``, ``ensemble_s`` and the
    ``slider_crank`` section (its ``step_s`` and ``joint_revolution_s`` of O, A and B)."""
    out: dict[str, Any] = {}
    try:
        for name in ("spectrum_s", "ensemble_s"):
            if doc.get(name) is not None:
                out[name] = float(doc[name])
        section = doc.get("slider_crank")
        if section is not None:
            out["slider_crank_step_s"] = float(section["step_s"])
            out["joint_revolution_s"] = {j: float(section["joint_revolution_s"][j])
                                         for j in "OAB"}
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise ConfigError(None, None, "a plan-costs file whose spectrum_s and ensemble_s are "
                          "numbers and whose slider_crank section has numbers step_s and "
                          f"joint_revolution_s of O, A, B ({type(exc).__name__}: {exc})",
                          source) from None
    numbers = [v for v in out.values() if isinstance(v, float)]
    numbers += list(out.get("joint_revolution_s", {}).values())
    if not all(math.isfinite(v) and v >= 0.0 for v in numbers):
        raise ConfigError(None, None, "a plan-costs file of finite costs >= 0", source)
    return out


def _wear_pace(entry: Any, source: str) -> WearPace | None:
    """The ``wear_pace`` of a plan-costs file (None where it has none)."""
    if entry is None:
        return None
    names = ("first_rate_m", "growth_m2", "clearance_m", "wear_coefficient_m2_per_N")
    try:
        values = {name: float(entry[name]) for name in names}
    except (KeyError, TypeError, ValueError) as exc:
        raise ConfigError(None, None, "a plan-costs file whose wear_pace has numbers "
                          f"{', '.join(names)} ({type(exc).__name__}: {exc})", source) from None
    if not all(math.isfinite(v) and v > 0.0 for v in values.values()):
        raise ConfigError(None, None, "a plan-costs file whose wear_pace numbers are finite "
                          "and > 0", source)
    return WearPace(reference=str(entry.get("reference", "")), **values)


def plan_costs() -> PlanCosts:
    """The costs every plan charges: :func:`read_plan_costs` of the shipped file, or of the
    file ``CLEARSWEEP_PLAN_COSTS`` names (a re-calibration tried before it is written over
    the shipped one)."""
    return read_plan_costs(os.environ.get("CLEARSWEEP_PLAN_COSTS") or None)


def clearance_joints(cfg: Config) -> str:
    """The joints of ``cfg`` with clearance, in the order O, A, B, P (``"AB"``; ``""``: ideal)."""
    return "".join(j for j in _JOINTS if getattr(cfg.joints, j).clearance > 0.0)


def step_seconds(cfg: Config) -> float:
    """What one output-grid RK4 step of ``cfg`` costs a worker [s]: the ideal step and each
    clearance joint's share (:class:`PlanCosts`); in the slider-crank, also each clearance
    joint's impacts per revolution over the case's steps a revolution."""
    period_steps = cfg.mechanism.speed_rpm * cfg.solver.dt / 60.0
    per_revolution = 1.0 / period_steps if period_steps > 0.0 else math.inf
    return plan_costs().step_seconds(clearance_joints(cfg), cfg.mechanism.kind, per_revolution)


def spectrum_seconds(cfgs: Iterable[Config]) -> float:
    """What a sweep of ``cfgs`` pays once for its summaries' spectrum [s]
    (:attr:`PlanCosts.spectrum_s`): where a case's settled window holds
    ``motion.MIN_SEGMENT_REVOLUTIONS`` crank revolutions or more, else 0. Each worker
    pays it once, side by side: once in the wall time."""
    from .motion import MIN_SEGMENT_REVOLUTIONS

    for cfg in cfgs:
        settled = (cfg.solver.duration - cfg.metrics.settle_time) * cfg.mechanism.speed_rpm / 60.0
        if settled >= MIN_SEGMENT_REVOLUTIONS - 1e-9:
            return plan_costs().spectrum_s
    return 0.0


def ensemble_seconds(cfgs: Iterable[Config]) -> float:
    """What a sweep's driver spends on the ensemble statistics of ``cfgs`` [s]
    (:attr:`PlanCosts.ensemble_s`): 0 unless they are an ensemble's members."""
    return plan_costs().ensemble_s if any(c.ensemble.members > 1 for c in cfgs) else 0.0


def case_seconds(cfg: Config, keeps_series: bool = True, est: Estimate | None = None) -> float:
    """The estimated wall time [s] of one case of ``cfg`` on one worker: its steps priced by
    its joints with clearance (:func:`step_seconds`), its saved rows where the case keeps its
    time series (``run``, ``store: full``), and the cost per case."""
    costs = plan_costs()
    est = estimate(cfg) if est is None else est
    kept = 0.0
    if keeps_series:
        polar, azimuth = cfg.wear.map
        kept = est.rows * costs.row_s + len(_JOINTS) * polar * azimuth * costs.map_bin_s
    return costs.case_s + est.steps * step_seconds(cfg) + kept


def assembly_seconds(cfg: Config, keeps_series: bool, est: Estimate | None = None) -> float:
    """What a sweep's driver spends on a case of ``cfg`` once the cases have run [s]: its part
    checked and copied into the file (its saved rows, where it keeps its time series)."""
    costs = plan_costs()
    rows = (estimate(cfg) if est is None else est).rows if keeps_series else 0
    return costs.assemble_case_s + rows * costs.assemble_row_s


def life_seconds(cfg: Config, blocks: float, steps_per_block: int) -> float:
    """The estimated wall time [s] of a life run of ``cfg`` that takes ``blocks`` blocks of
    ``steps_per_block`` steps: each block's steps priced by the joints with clearance, and
    its jump (:attr:`PlanCosts.block_s`). The slider-crank's impacts
    (:attr:`PlanCosts.joint_revolution_s`, measured on a fresh bearing) are charged to the
    first block alone: the later blocks run in the worn bearing, and cost less than their
    steps without them (benchmarks/README.md, "Plans against measured times")."""
    costs = plan_costs()
    fresh = step_seconds(cfg)
    worn = costs.step_seconds(clearance_joints(cfg), cfg.mechanism.kind)
    return (costs.case_s + blocks * (steps_per_block * worn + costs.block_s)
            + min(blocks, 1.0) * steps_per_block * (fresh - worn))


def duration_text(seconds: float) -> str:
    """``seconds`` in the largest unit that keeps it at least 1 (``2.5 min``)."""
    for unit, size in (("d", 86400.0), ("h", 3600.0), ("min", 60.0)):
        if seconds >= size:
            return f"{seconds / size:.3g} {unit}"
    return f"{seconds:.2g} s"


def _workers_text(workers: int | None) -> str:
    return f"on {workers} worker{'s' if workers != 1 else ''}" if workers else "on one core"


def steps_text(cfgs: Iterable[Config]) -> str:
    """The cost per step a plan charges its cases, ``"at 1.9 us per step (ideal)"`` or
    ``"at 2.1 us per step (B) to 14 us (OABP)"``: by the joints with clearance."""
    priced = sorted({(step_seconds(c), clearance_joints(c) or "ideal") for c in cfgs})
    if not priced:
        return f"at {plan_costs().step_s * 1e6:.2g} us per step"
    lo, hi = priced[0], priced[-1]
    if lo[0] == hi[0]:
        return f"at {lo[0] * 1e6:.2g} us per step ({lo[1]})"
    digits = 2 if f"{lo[0] * 1e6:.2g}" != f"{hi[0] * 1e6:.2g}" else 3
    return (f"at {lo[0] * 1e6:.{digits}g} us per step ({lo[1]}) to {hi[0] * 1e6:.{digits}g} us "
            f"({hi[1]})")


def time_text(cfg: Config, est: Estimate | None = None) -> str:
    """The estimated wall time of one case of ``cfg`` (a ``run``) on one core, with the cost
    per step it charges."""
    seconds = plan_costs().run_start_s + case_seconds(cfg, True, est)
    return (f"about {duration_text(seconds)} on one core ({steps_text([cfg])} and "
            f"{plan_costs().run_start_s:.2g} s to start; benchmarks/calibrate_plan.py)")


def sweep_seconds(case_times: Iterable[float], workers: int | None = None,
                  assembly: float = 0.0, once: float = 0.0) -> float:
    """The estimated wall time [s] of a sweep whose cases cost ``case_times`` [s] on one
    worker each, shared by ``workers`` cores: the fixed start and what each worker pays
    once (``once``: :func:`spectrum_seconds`), then the cases' total over the workers and at
    least the longest case, then the driver's ``assembly`` [s] (:func:`assembly_seconds` of
    each case, and :func:`ensemble_seconds`)."""
    times = list(case_times)
    share = sum(times) / (workers or 1)
    return plan_costs().sweep_start_s + once + max(share, max(times, default=0.0)) + assembly


def sweep_time_text(case_times: Iterable[float], cfgs: Iterable[Config],
                    workers: int | None = None, assembly: float = 0.0,
                    once: float = 0.0) -> str:
    """:func:`sweep_seconds` in words, with the costs it charges."""
    seconds = sweep_seconds(case_times, workers, assembly, once)
    costs = plan_costs()
    return (f"about {duration_text(seconds)} {_workers_text(workers)} ({steps_text(cfgs)}, "
            f"{costs.case_s:.2g} s per case and {costs.sweep_start_s:.2g} s to start; "
            "benchmarks/calibrate_plan.py)")


def case_plan_text(source: str, est: Estimate, cfg: Config) -> str:
    """What ``clearsweep run CONFIG --dry-run`` prints for one case."""
    return (f"{source}: one case, {est.steps:,} RK4 steps, memory up to {est.describe()}; "
            f"{time_text(cfg, est)}; nothing run (--dry-run)")


def _per_row_output_values() -> int:
    """float64 per saved row in the output variables (every variable with a time dimension)."""
    from .variables import AXES, CASE_VARIABLES, JOINTS

    sizes = {"joint": len(JOINTS), "axis": len(AXES)}
    return 1 + sum(math.prod(sizes.get(d, 1) for d in spec.dims if d != "time")
                   for spec in CASE_VARIABLES.values() if "time" in spec.dims)


@dataclass(frozen=True)
class Estimate:
    """What one case costs, before it runs.

    Attributes
    ----------
    steps_asked : int
        ``ceil(solver.duration / solver.dt)``.
    steps : int
        Output-grid RK4 steps: ``steps_asked`` rounded up to whole output
        samples (sub-steps, where contacts need them, come on top), and the twin runs of
        the largest Lyapunov exponent (:func:`lyapunov_steps`).
    rows : int
        Saved rows: ``steps_asked`` rounded up to whole output samples /
        ``solver.save_every`` + 1.
    values_per_row : int
        float64 per row: the kernel's N_Y + N_D + time and wear maximum,
        plus the output variables.
    map_values : int
        float64 of the wear maps (one per joint: N_JOINTS x polar x azimuth),
        the projections and the output copy's.
    """

    steps_asked: int
    steps: int
    rows: int
    values_per_row: int
    map_values: int

    @property
    def row_bytes(self) -> int:
        return self.rows * self.values_per_row * _FLOAT

    @property
    def map_bytes(self) -> int:
        return self.map_values * _FLOAT

    @property
    def output_bytes(self) -> int:
        """Bytes of one case's arrays in memory (an upper bound of its netCDF output)."""
        return self.row_bytes + self.map_bytes

    def describe(self) -> str:
        return (f"{format_bytes(self.output_bytes)}: {self.rows:,} rows x {self.values_per_row} "
                f"float64 = {format_bytes(self.row_bytes)}, and wear maps "
                f"{format_bytes(self.map_bytes)}")


def _steps_asked(cfg: Config) -> int:
    ratio = cfg.solver.duration / cfg.solver.dt
    if not math.isfinite(ratio):
        return int(sys.float_info.max)      # beyond any limit
    return max(1, int(math.ceil(ratio - 1e-9)))


def estimate(cfg: Config) -> Estimate:
    """Steps and bytes of one resolved case (:func:`clearsweep.config.load_config`).

    Mirrors :func:`clearsweep.params.pack` (whole output samples, rounded up)
    and :func:`clearsweep.simulation.run_kernel` (the arrays it allocates).
    """
    from .core import layout as L  # imports Numba: only when a case is checked

    save_every = cfg.solver.save_every
    asked = _steps_asked(cfg)
    steps = max(1, -(-asked // save_every)) * save_every
    rows = steps // save_every + 1
    per_row = L.N_Y + L.N_D + _KERNEL_EXTRA_PER_ROW + _per_row_output_values()
    polar, azimuth = cfg.wear.map
    map_values = L.N_JOINTS * (polar * azimuth + 3 * L.N_ANGLE_BINS)
    return Estimate(asked, steps + lyapunov_steps(cfg, rows), rows, per_row, map_values)


def lyapunov_steps(cfg: Config, rows: int) -> int:
    """Output-grid steps of the twin runs for the largest Lyapunov exponent
    (``metrics.lyapunov_revolutions``, :func:`clearsweep.simulation.lyapunov_exponent`): two
    runs of a block of whole saved rows, about a revolution, per revolution the run's
    ``rows`` hold after its settled window's start."""
    revolutions = cfg.metrics.lyapunov_revolutions
    if revolutions <= 0:
        return 0
    row_dt = cfg.solver.dt * cfg.solver.save_every
    period = 60.0 / cfg.mechanism.speed_rpm
    block = max(1, int(round(period / row_dt)))
    first = int(math.ceil(cfg.metrics.settle_time / row_dt - 1e-9))
    blocks = max(0, min(revolutions, (rows - 1 - first) // block))
    return 2 * blocks * block * cfg.solver.save_every


def check_budget(cfg: Config, *, allow_large: bool = False,
                 source: str = "<config>") -> Estimate:
    """Refuse a case whose estimate is out of bounds; return the estimate.

    Parameters
    ----------
    cfg
        A resolved configuration.
    allow_large
        Accept more than :data:`MAX_OUTPUT_BYTES` or :data:`MAX_STEPS`
        (``--allow-large``). A ``solver.save_every`` larger than the run is
        refused regardless: it would stretch the run to one whole sample.
    source
        Name of the config in the message.

    Raises
    ------
    ConfigError
        Naming the key that drives the cost and quoting the estimate.
    """
    solver = cfg.solver
    est = estimate(cfg)
    if solver.save_every > est.steps_asked:
        raise ConfigError(
            "solver.save_every", solver.save_every,
            f"an integer <= {est.steps_asked} (the steps in solver.duration / solver.dt; a larger "
            f"one stretches the run to one whole output sample, {est.steps} steps)", source)
    hint = "or pass --allow-large (allow_large=True) if the machine can take it"
    limit = memory_limit(allow_large)
    if limit is None or (allow_large and est.output_bytes <= limit):
        return est
    if allow_large:
        hint = "--allow-large lifts the bounds of clearsweep, not those of this machine"
    # of the two that set the rows, name the one that left its usual range
    length_key = "solver.duration" if solver.revolutions is None else "solver.revolutions"
    row_key = length_key if solver.duration > DEFAULTS.solver.duration else "solver.dt"
    if not allow_large and est.steps > MAX_STEPS:
        steps = solver.duration / solver.dt
        key = row_key
        value = cfg.get(key)
        got = (f"{value!r} (solver.duration / solver.dt = {solver.duration!r}"
               f" s / {solver.dt!r} s = {steps:.3g} steps)")
        if solver.revolutions is not None:      # the seconds come from the speed: name it
            got = (f"{value!r} (solver.revolutions * 60 / mechanism.speed_rpm = "
                   f"{solver.revolutions!r} * 60 / {cfg.mechanism.speed_rpm!r} = "
                   f"{solver.duration:.3g} s, / solver.dt ({solver.dt!r} s) = {steps:.3g} steps)")
        raise ConfigError(key, value,
                          f"a run of at most {MAX_STEPS:.3g} RK4 steps; raise solver.dt, shorten "
                          f"{length_key}, {hint}", source, got=got)
    if est.output_bytes > limit:
        if est.map_bytes > est.row_bytes:
            key, value, fix = "wear.map", list(cfg.wear.map), "use fewer wear-map bins"
        else:
            key, value, fix = (row_key, cfg.get(row_key), f"shorten {length_key}, raise "
                               "solver.dt or solver.save_every")
        where = f"this machine's memory ({format_bytes(limit)} free)" if allow_large else \
            format_bytes(MAX_OUTPUT_BYTES)
        raise ConfigError(key, value, f"a case whose arrays fit in {where}; {fix}"
                          f"{'; ' if allow_large else ', '}{hint}",
                          source, got=f"{value!r} (estimated {est.describe()})")
    return est


def memory_limit(allow_large: bool = False) -> int | None:
    """Most bytes a run's arrays may take: :data:`MAX_OUTPUT_BYTES`, or with ``allow_large``
    this machine's memory (:func:`machine_memory`; None: unknown, unbounded)."""
    return machine_memory() if allow_large else MAX_OUTPUT_BYTES


def machine_memory() -> int | None:
    """Memory [bytes] a run can take on this machine now: the kernel's ``MemAvailable``
    (else the physical memory), and at most the address-space limit (``ulimit -v``);
    None when neither is known. What ``--allow-large`` is still bounded by: past it, the
    arrays would end in a MemoryError or the kernel's out-of-memory killer."""
    import resource

    found = []
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    found.append(int(line.split()[1]) * 1024)
    except (OSError, ValueError, IndexError):
        pass
    if not found:
        try:
            found.append(os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
        except (OSError, ValueError, AttributeError):
            pass
    soft, _ = resource.getrlimit(resource.RLIMIT_AS)
    if soft != resource.RLIM_INFINITY:
        found.append(soft)
    return min(found) if found else None


def largest_variable(path: str) -> tuple[str, dict[str, int], int] | None:
    """``(name, dims and sizes, bytes)`` of the largest variable the netCDF file ``path``
    declares, from its metadata alone (nothing of its data is read); None when the netCDF
    library cannot open it (the reader says why). A text variable counts 8 bytes a value."""
    import netCDF4

    try:
        with netCDF4.Dataset(path) as nc:
            groups, found = [nc], []
            while groups:
                group = groups.pop()
                groups += list(group.groups.values())
                for name, var in group.variables.items():
                    size = getattr(var.dtype, "itemsize", 8) * math.prod(var.shape)
                    found.append((size, name, dict(zip(var.dimensions, var.shape))))
    except (OSError, ValueError, RuntimeError):
        return None
    if not found:
        return None
    size, name, dims = max(found, key=lambda f: f[0])
    return name, dims, size
