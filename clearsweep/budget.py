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

import math
import os
import sys
from dataclasses import dataclass

from .config import DEFAULTS, Config, ConfigError

__all__ = ["Estimate", "estimate", "check_budget", "format_bytes", "MAX_OUTPUT_BYTES", "MAX_STEPS",
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


#: Wall time of one output-grid RK4 step per worker on this project's 2-core x86-64 machine
#: [s], for the time estimates that ``sweep``, ``validate`` and ``--dry-run`` print, measured
#: on whole sweeps (benchmarks/README.md, "Time estimates": the main job 4.1 us, the shipped
#: ensemble 2.6 us, quiet machine): it counts the contact sub-steps, the wear map, each
#: case's start and the writing of its results, not only the bare step (1.6 us).
SECONDS_PER_STEP = 4e-6


def duration_text(seconds: float) -> str:
    """``seconds`` in the largest unit that keeps it at least 1 (``2.5 min``)."""
    for unit, size in (("d", 86400.0), ("h", 3600.0), ("min", 60.0)):
        if seconds >= size:
            return f"{seconds / size:.3g} {unit}"
    return f"{seconds:.2g} s"


def time_text(steps: float, workers: int | None = None) -> str:
    """The estimated wall time of ``steps`` RK4 steps shared by ``workers`` cores
    (``None``: one core), with the cost per step it assumes."""
    where = f"on {workers} worker{'s' if workers != 1 else ''}" if workers else "on one core"
    return (f"about {duration_text(steps * SECONDS_PER_STEP / (workers or 1))} {where} "
            f"(at {SECONDS_PER_STEP * 1e6:g} us per step)")


#: A sweep's fixed cost [s]: the interpreter's start and the compiled kernel loaded from the
#: cache, in the driver and in each pool worker (benchmarks/README.md, "Time estimates").
SWEEP_START_S = 6.0
#: A sweep's cost per case beyond its steps [s]: its part written and copied into the file.
SECONDS_PER_CASE = 0.05


def sweep_seconds(steps: float, cases: int, workers: int | None = None) -> float:
    """The estimated wall time [s] of a sweep of ``cases`` cases and ``steps`` RK4 steps on
    ``workers`` cores: :func:`time_text`'s steps plus the fixed costs (start, cache load)
    and the cost per case (part writing, assembly)."""
    return SWEEP_START_S + (cases * SECONDS_PER_CASE + steps * SECONDS_PER_STEP) / (workers or 1)


def sweep_time_text(steps: float, cases: int, workers: int | None = None) -> str:
    """:func:`sweep_seconds` in words, with the costs it assumes."""
    share = workers or 1
    seconds = sweep_seconds(steps, cases, workers)
    where = f"on {share} worker{'s' if share != 1 else ''}" if workers else "on one core"
    return (f"about {duration_text(seconds)} {where} (at {SECONDS_PER_STEP * 1e6:g} us per "
            f"step, {SECONDS_PER_CASE:g} s per case and {SWEEP_START_S:g} s to start)")


def case_plan_text(source: str, est: Estimate) -> str:
    """What ``clearsweep run CONFIG --dry-run`` prints for one case."""
    return (f"{source}: one case, {est.steps:,} RK4 steps, memory up to {est.describe()}; "
            f"{time_text(est.steps)}; nothing run (--dry-run)")


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
