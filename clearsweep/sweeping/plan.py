"""Sweep files -> a plan of cases (grid, zip and skip axes), every case validated before any runs.

The sweep file format and the naming of dimensions are described in
:mod:`clearsweep.sweeping` (package docstring).
"""

from __future__ import annotations

import copy
import itertools
import json
import math
import os
import warnings
from collections.abc import Callable, Collection, Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr

from .. import variables
from ..budget import (
    assembly_seconds,
    case_seconds,
    duration_text,
    ensemble_seconds,
    estimate,
    format_bytes,
    life_seconds,
    spectrum_seconds,
    sweep_seconds,
    sweep_time_text,
)
from ..choices import MAX_CASES, MAX_CASES_ANY, MAX_SAMPLE_POINTS
from ..config import (
    ALTERNATIVES,
    SWEEP_FILE_KEYS,
    Config,
    ConfigError,
    alternative_of,
    close_match,
    dump_config,
    field_info,
    file_kind,
    get_path,
    load_config,
    read_yaml,
    set_setting,
    short_repr,
)
from ..outputs import MEMBER_DIM, SAMPLE_DIM  # noqa: F401  (also read as plan.MEMBER_DIM, plan.SAMPLE_DIM)
from ..schema import OVERSIZED, ClearsweepWarning, oversized_number, oversized_text
from ..service_life import DEPTH_LIMITS, block_steps, forecast_blocks, limit_keys
from .assemble import SweepSlot
from .parts import canonical_json, case_key
from .stores import STORES

#: First components of a dotted key that the dimension name leaves out.
DROPPED_SECTIONS = ("joints", "mechanism", "contact", "friction", "wear", "solver", "ensemble")
#: Keys that the ensemble section sets for every case and a sweep cannot vary.
ENSEMBLE_KEYS = ("ensemble.member", "ensemble.members", "reliability.member", "reliability.members")
#: What a sweep stores per case: the stores of :data:`clearsweep.sweeping.stores.STORES`.
STORE_MODES = tuple(STORES)
SWEEP_KEYS = ("grid", "zip", "sample", "skip")
#: Keys of a ``sample:`` section, and its methods: Sobol' and Latin hypercube points over the
#: ranges (scipy.stats.qmc), or the Saltelli design that Sobol' indices need (SALib).
SAMPLE_KEYS = ("method", "n", "seed", "ranges", "second_order")
SAMPLE_METHODS = ("sobol", "lhs", "saltelli")
#: What a refusal of too many cases tells the user to type (``expand``'s default: a sweep).
TOO_MANY_HINT = "clearsweep sweep --yes runs them all"
#: Keys of a zip group that are not config keys.
ZIP_META_KEYS = ("name", "labels")
#: A plan of more cases than MAX_CASES that is only looked at (``validate``, ``--dry-run``)
#: is counted from its dimensions, not enumerated: the cases checked are every dimension's
#: first value with the others' first, and up to this many more positions of each
#: dimension (spread evenly, with the smallest and largest value of each key).
COUNTED_POSITIONS = 16


def _reserved_names() -> set[str]:
    return {*variables.CASE_VARIABLES, *variables.COORDINATES, *variables.SUMMARY_VARIABLES,
            "status", "message", MEMBER_DIM}


def dimension_name(key: str) -> str:
    """Short name of a swept dotted key (see the module docstring, "Naming").

    >>> dimension_name("joints.B.coating"), dimension_name("mechanism.speed_rpm")
    ('B_coating', 'speed_rpm')
    """
    parts = key.split(".")
    if len(parts) > 1 and parts[0] in DROPPED_SECTIONS:
        parts = parts[1:]
    return "_".join(parts)


def _full_name(key: str) -> str:
    return key.replace(".", "_")


def _coord_values(values: Sequence) -> np.ndarray:
    """Coordinate array of swept values as given: numbers, booleans, strings, else JSON text."""
    vals = list(values)
    if all(isinstance(v, bool) for v in vals):
        return np.array(vals, dtype=bool)
    if all(isinstance(v, int) and not isinstance(v, bool) for v in vals):
        return np.array(vals, dtype=np.int64)
    if all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in vals):
        return np.array(vals, dtype=np.float64)
    if all(isinstance(v, str) for v in vals):
        return np.array(vals, dtype=object)
    return np.array([json.dumps(v) for v in vals], dtype=object)


@dataclass(frozen=True)
class Axis:
    """One sweep dimension: a grid key, or a zip group of keys that vary together.

    Attributes
    ----------
    dim : str
        Dimension name.
    kind : str
        ``"grid"``, ``"zip"`` or ``"sample"`` (a zip group whose values were drawn).
    keys : tuple of str
        Dotted config keys set along this dimension.
    names : tuple of str
        Coordinate name of each key (for a grid axis, ``names[0] == dim``).
    values : tuple of tuple
        Values of each key, as given in the sweep file.
    labels : tuple or None
        Index values of a zip group's dimension (its ``labels:``).
    """

    dim: str
    kind: str
    keys: tuple[str, ...]
    names: tuple[str, ...]
    values: tuple[tuple, ...]
    labels: tuple | None = None

    @property
    def size(self) -> int:
        return len(self.values[0])

    def assignment(self, i: int) -> dict[str, Any]:
        """Config key -> value at position ``i``."""
        return {k: v[i] for k, v in zip(self.keys, self.values)}

    def label(self, i: int) -> dict[str, Any]:
        """Coordinate name -> value at position ``i``."""
        out = {self.dim: self.labels[i]} if self.labels is not None else {}
        out.update({n: v[i] for n, v in zip(self.names, self.values)})
        return out

    def coords(self) -> dict[str, tuple[str, np.ndarray, dict]]:
        """Coordinates of this dimension: ``name -> (dim, values, attrs)``."""
        out = {}
        if self.labels is not None:
            what = "sample point" if self.kind == "sample" else f"sweep zip group {self.dim}"
            out[self.dim] = (self.dim, _coord_values(self.labels),
                             {"long_name": what, "config_keys": " ".join(self.keys)})
        for key, name, vals in zip(self.keys, self.names, self.values):
            info = field_info(key)
            attrs = {"long_name": info[1] if info else f"swept config value {key}",
                     "config_key": key}
            array = _coord_values(vals)
            if array.dtype == object and not all(isinstance(v, str) for v in vals):
                attrs["comment"] = "values stored as JSON text"
            elif info and info[0] is not None and array.dtype.kind in "iuf":
                attrs["units"] = info[0]
            out[name] = (self.dim, array, attrs)
        return out


@dataclass(frozen=True)
class Case:
    """One sweep point: its position, and its resolved config (``None`` when skipped)."""

    index: tuple[int, ...]
    hash: str | None
    config: Config | None
    skip_message: str = ""

    @property
    def config_json(self) -> str | None:
        """The resolved configuration as canonical JSON (:attr:`hash` is the case key,
        :func:`clearsweep.sweeping.parts.case_key`: of this, less the materials file's path,
        with the materials values it reads and the clearsweep version)."""
        return None if self.config is None else canonical_json(self.config.to_dict())


@dataclass
class SweepPlan:
    """A validated, expanded sweep: its axes and one :class:`Case` per point, in C order.

    Holds the resolved configuration of every case, never results.
    """

    name: str
    store: str
    source: str
    text: str
    base: Config
    axes: tuple[Axis, ...]
    cases: list[Case]
    #: The clearsweep command that runs it (``sweep``; ``run`` for an ensemble config),
    #: named in the hint that continues it.
    command: str = "sweep"
    #: The case YAML file named by the sweep file's ``base:`` (None: an inline base).
    base_file: str | None = None
    #: A counted plan (:func:`expand` with ``enumerate_cases=False``): ``(points, skipped)``
    #: of the whole sweep, while :attr:`cases` holds only the cases checked; None: every
    #: case is in :attr:`cases`.
    counted: tuple[int, int] | None = None

    @property
    def dims(self) -> dict[str, int]:
        """Sweep dimensions and sizes, in order."""
        return {a.dim: a.size for a in self.axes}

    @property
    def coords(self) -> dict[str, tuple[str, np.ndarray, dict]]:
        """All sweep coordinates: ``name -> (dim, values, attrs)``."""
        out = {}
        for axis in self.axes:
            out.update(axis.coords())
        return out

    def label(self, case: Case) -> dict[str, Any]:
        """Coordinate values of ``case``."""
        out = {}
        for axis, i in zip(self.axes, case.index):
            out.update(axis.label(i))
        return out

    def runnable(self) -> dict[str, Config]:
        """Hash -> resolved config of each distinct case to run, in sweep order."""
        # a case has a hash exactly when it has a config (a skipped point has neither)
        return {c.hash: c.config for c in self.cases if c.hash is not None and c.config is not None}

    def input_files(self) -> list[tuple[str, str]]:
        """``(description, path)`` of every file the sweep reads: the sweep file, its base
        file and the materials files of its cases (for ``clearsweep.outputs.check_output``)."""
        files = [("the sweep file", self.source)] if Path(self.source).is_file() else []
        if self.base_file:
            files.append(("the base config", self.base_file))
        materials = {self.base.materials_file, *(c.materials_file for c in self.runnable().values())}
        files += [("the materials file", m) for m in sorted(m for m in materials if m)]
        return files

    def slots(self) -> list[SweepSlot]:
        """The sweep points for :func:`clearsweep.sweeping.assemble.write_sweep_netcdf`."""
        return [SweepSlot(c.hash, c.skip_message) for c in self.cases]

    def to_dataset(self) -> xr.Dataset:
        """The sweep coordinates alone (no data), e.g. to look at a plan before running it."""
        return xr.Dataset(coords={n: (d, v, a) for n, (d, v, a) in self.coords.items()})

    def describe(self, workers: int | None = None, kept: Collection[str] = ()) -> str:
        """One line: cases, RK4 steps, a rough time and the output size, before the sweep runs.

        Parameters
        ----------
        workers
            Cores the cases share; ``None``: the time is given for one core.
        kept
            Hashes of the cases finished before (``--resume``): not counted as to run.
        """
        every = self.runnable()
        runnable = {h: c for h, c in every.items() if h not in kept}
        done = len(every) - len(runnable)
        resumed = f" ({done:,} finished before, kept)" if done else ""
        estimates = {h: estimate(cfg) for h, cfg in every.items()}
        n_cases, skipped = self.counted or (len(self.cases), sum(c.hash is None for c in self.cases))
        # a counted plan: its other cases as costly as the costliest one checked
        scale = ((n_cases - skipped) / max(len(every), 1)) if self.counted else 1.0
        to_run = round(scale * len(runnable))
        checked = (f" (counted from its dimensions; {len(self.cases):,} cases checked, the "
                   "others when it runs)" if self.counted else "")

        def total(values: list[float]) -> float:
            return max(values, default=0.0) * to_run if self.counted else sum(values)

        def times(values: list[float]) -> list[float]:
            # a counted plan: every case to run as costly as the costliest one checked
            return [max(values, default=0.0)] * to_run if self.counted else values

        if STORES[self.store].runs_life:
            return self._describe_life(runnable, to_run, total, times,
                                       f"sweep {self.name!r}: {n_cases:,} life runs{checked}, "
                                       f"{to_run:,} to run{resumed}", workers)
        steps = total([estimates[h].steps for h in runnable])
        keeps = STORES[self.store].keeps_series
        seconds = times([case_seconds(cfg, keeps, estimates[h]) for h, cfg in runnable.items()])
        assembly = total([assembly_seconds(cfg, keeps, estimates[h])
                          for h, cfg in runnable.items()]) + ensemble_seconds(runnable.values())
        once = spectrum_seconds(runnable.values())
        # the file holds the kept cases too
        keeps_series = STORES[self.store].keeps_series
        sizes = [e.output_bytes if keeps_series else e.map_bytes for e in estimates.values()]
        per_case = max(sizes, default=0) * (n_cases - skipped) if self.counted else sum(sizes)
        counts = f"{n_cases:,} cases" + (f" ({skipped:,} skipped)" if skipped else "")
        return (f"sweep {self.name!r}: {counts}{checked}, {to_run:,} to simulate{resumed}, "
                f"{steps:.3g} RK4 steps: "
                f"{sweep_time_text(seconds, runnable.values(), workers, assembly, once)}; "
                f"results up to "
                f"{format_bytes(per_case)} before compression")

    def _describe_life(self, runnable: dict[str, Config], to_run: int, total, times, head: str,
                       workers: int | None) -> str:
        """:meth:`describe` of a life or reliability sweep: at most life.max_blocks blocks
        a run, and the blocks expected if wear sets the pace
        (:func:`clearsweep.service_life.forecast_blocks`; a reliability member runs until
        every limit it watches is crossed), each in RK4 steps and wall time."""
        every = STORES[self.store].every_limit
        bound, expected, forecasts = [], [], []
        bound_s, expected_s = [], []
        for cfg in runnable.values():
            # a life run simulates up to life.max_blocks blocks of life.block_revolutions,
            # each block's steps priced by its joints with clearance, and each block's jump
            steps = block_steps(cfg)
            forecast = forecast_blocks(cfg, every_limit=every)
            bound.append(cfg.life.max_blocks * steps)
            expected.append(forecast.blocks * steps)
            bound_s.append(life_seconds(cfg, cfg.life.max_blocks, steps))
            expected_s.append(life_seconds(cfg, forecast.blocks, steps))
            forecasts.append(forecast)
        if not forecasts:       # every part is on disk: only the assembly is left
            return f"{head}: nothing to run"
        assembly = total([assembly_seconds(cfg, False) for cfg in runnable.values()])
        most, likely = total(bound), total(expected)
        blocks = sorted({f.blocks for f in forecasts})
        span = (f"{blocks[0]:,}" if len(blocks) == 1 else f"{blocks[0]:,} to {blocks[-1]:,}")
        limits = [name for name in DEPTH_LIMITS if any(name in f.limits for f in forecasts)]
        # the runs that the plan's wear pace takes to life.cycles before any wear limit
        paced = sum(1 for f in forecasts if f.to_cycles is not None and f.to_cycles < f.to_limits)
        pace = ("life.cycles at the wear pace of benchmarks/calibrate_plan.py's reference run, "
                "scaled by Archard's k and the clearance")
        if paced == len(forecasts):
            why = (f"{span} blocks a run to {pace} (not by the loads or speed: a run that "
                   "wears faster ends sooner); fewer where a dynamic limit comes first")
        elif paced:
            why = (f"{span} blocks a run: {paced:,} of {len(forecasts):,} runs to {pace}, the "
                   f"others to their wear limits ({limit_keys(limits)})")
        elif not limits:
            why = f"{span} blocks a run: no wear limit watched to forecast from"
        elif every:
            why = (f"{span} blocks a run to its wear limits ({limit_keys(limits)}), the other "
                   "limits it watches taken to come no later; fewer where life.cycles comes first")
        else:
            why = (f"{span} blocks a run to the first wear limit ({limit_keys(limits)}); fewer "
                   "where life.cycles or another limit comes first")
        return (f"{head}: at most {most:.3g} RK4 steps (life.max_blocks blocks each), at most "
                f"{sweep_time_text(times(bound_s), runnable.values(), workers, assembly)}; "
                f"expected about "
                f"{duration_text(sweep_seconds(times(expected_s), workers, assembly))} "
                f"({likely:.3g} RK4 "
                f"steps and each block's jump: {why})")

    def plan_text(self, workers: int | None = None) -> str:
        """What ``clearsweep validate`` prints for a sweep file: its dimensions, the cases,
        one case's steps and memory, and :meth:`describe`'s total and time estimate."""
        lines = [f"{self.source}: a valid sweep file (store: {self.store}); run it with "
                 f"`clearsweep {self.command} {self.source}`"]
        for axis in self.axes:
            values = (axis.labels if axis.labels is not None and axis.kind != "sample"
                      else axis.values[0])
            shown = ", ".join(short_repr(v) for v in values[:8]) + (", ..." if axis.size > 8 else "")
            if axis.kind == "sample":
                shown = "; ".join(f"{k} in [{min(v):.4g}, {max(v):.4g}]"
                                  for k, v in zip(axis.keys, axis.values))
            elif len(axis.keys) > 1 or axis.keys[0] != axis.dim:
                shown += f" ({', '.join(axis.keys)})"
            lines.append(f"  dimension {axis.dim} ({axis.size}): {shown}")
        estimates = [estimate(cfg) for cfg in self.runnable().values()]
        if estimates:
            steps = [e.steps for e in estimates]
            largest = max(estimates, key=lambda e: e.output_bytes)
            span = (f"{min(steps):,}" if min(steps) == max(steps)
                    else f"{min(steps):,} to {max(steps):,}")
            lines.append(f"  one case: {span} RK4 steps; memory up to {largest.describe()}")
        lines.append("  " + self.describe(workers))
        return "\n".join(lines)


def _read_sweep(config_or_path) -> tuple[dict, str, Path, str]:
    """(document, source name, folder for relative paths, default name)."""
    if isinstance(config_or_path, Mapping):
        return copy.deepcopy(dict(config_or_path)), "<sweep>", Path.cwd(), "sweep"
    path = Path(config_or_path)
    doc = read_yaml(path, str(config_or_path))
    if not isinstance(doc, dict):
        raise ConfigError(None, doc, f"a sweep mapping with keys {', '.join(SWEEP_FILE_KEYS)}",
                          str(config_or_path))
    if file_kind(doc) == "case":
        raise ConfigError(None, None, f"a sweep file (top-level keys {', '.join(SWEEP_FILE_KEYS)});"
                          f" run a case config with `clearsweep run {config_or_path}` (check it "
                          f"with `clearsweep validate {config_or_path}`)", str(config_or_path),
                          got=f"a case config (top-level keys {', '.join(map(str, doc))})")
    return doc, str(config_or_path), path.resolve().parent, path.stem


def _check_keys(mapping: Mapping, allowed: Sequence[str], where: str | None, source: str) -> None:
    for key in mapping:
        if key not in allowed:
            full = f"{where}.{key}" if where else str(key)
            suggestion = close_match(key, allowed)
            raise ConfigError(full, mapping[key], f"one of the keys {', '.join(allowed)}", source,
                              f"{where}.{suggestion}" if where and suggestion else suggestion,
                              got="an unknown key")


def _files_from(spec: Any, base_dir: Path) -> Any:
    """``spec`` (a sweep section) with each swept ``materials_file`` that is a relative path
    taken from the sweep file's folder, as the base's own ``materials_file`` is (a relative
    path was read from the current folder: the shipped sweep ran only from the repository's
    root)."""
    if not isinstance(spec, Mapping):
        return spec
    spec = copy.deepcopy(dict(spec))
    groups = [spec.get("grid")] + list(spec.get("zip") or [])
    for group in groups:
        if isinstance(group, dict) and isinstance(group.get("materials_file"), list):
            group["materials_file"] = [
                str(base_dir / v) if isinstance(v, str) and not os.path.isabs(os.path.expanduser(v))
                else v for v in group["materials_file"]]
    return spec


def _load_base(base, base_dir: Path, source: str, overrides: Sequence[str]) -> Config:
    if base is None:
        base = {}
    if isinstance(base, str):
        path = base_dir / base
        if not path.is_file():
            raise ConfigError("base", base, "an inline case config or the path of a case YAML file "
                              f"(relative to the sweep file; looked for {path})", source)
        doc = read_yaml(path, f"{source}: base {base}")
        if file_kind(doc) == "sweep":   # load_config's hint would name `clearsweep sweep` of it
            raise ConfigError("base", base, "the path of a case config (a sweep's base is one "
                              "case; a sweep file cannot be the base of another)", source,
                              got=f"{base!r}, a sweep file")
        return load_config(path, overrides, source_name=f"{source}: base {base}")
    if not isinstance(base, Mapping):
        raise ConfigError("base", base, "an inline case config (a mapping) or the path of a case "
                          "YAML file", source)
    base = copy.deepcopy(dict(base))
    materials = base.get("materials_file")
    if isinstance(materials, str) and not os.path.isabs(os.path.expanduser(materials)):
        base["materials_file"] = str(base_dir / materials)
    return load_config(base, overrides, source_name=f"{source}: base")


def _check_swept_key(key, base: Config, where: str, source: str) -> str:
    if not isinstance(key, str) or not key:
        raise ConfigError(where, key, "a dotted config key such as joints.B.coating", source)
    try:
        value = get_path(base, key)
    except ConfigError as exc:
        raise ConfigError(f"{where}.{key}", None, exc.expected, source, exc.suggestion,
                          got="no such config key") from None
    if isinstance(value, Mapping):
        raise ConfigError(f"{where}.{key}", None, f"a key of a value, not of the section {key} "
                          f"(e.g. {key}.{next(iter(value))})", source, got="a section")
    if key in ENSEMBLE_KEYS:
        raise ConfigError(f"{where}.{key}", None, "a key other than ensemble.member(s) and "
                          "reliability.member(s): set members in the base and every member is "
                          "run along the "
                          f"{MEMBER_DIM!r} dimension", source, got="an ensemble key")
    return key


def _check_values(values, where: str, source: str, length: int | None = None) -> tuple:
    if not isinstance(values, list) or not values:
        raise ConfigError(where, values, "a non-empty list of values", source)
    big = oversized_number(values)
    if big is not None:
        raise ConfigError(where, values, OVERSIZED, source, got=oversized_text(big))
    if length is not None and len(values) != length:
        raise ConfigError(where, values, f"a list of {length} values (as long as the group's "
                          "first list: the keys of a zip group vary together)", source,
                          got=f"{len(values)} values")
    return tuple(values)


def _check_unique(values: tuple, where: str, source: str) -> None:
    array = _coord_values(values)
    seen = set()
    for v in array.tolist():
        if v in seen:
            raise ConfigError(where, list(values), "distinct values (they label a dimension)",
                              source, got=f"{v!r} twice")
        seen.add(v)


def _parse_axes(spec, base: Config, source: str, max_cases: int | None = MAX_CASES,
                members: int = 1, too_many_hint: str = TOO_MANY_HINT) -> list[Axis]:
    if spec is None:
        spec = {}
    if not isinstance(spec, Mapping):
        raise ConfigError("sweep", spec, "a mapping with keys grid, zip and skip", source)
    _check_keys(spec, SWEEP_KEYS, "sweep", source)
    grid = spec.get("grid") or {}
    if not isinstance(grid, Mapping):
        raise ConfigError("sweep.grid", grid, "a mapping of dotted config keys to lists of values",
                          source)
    groups = spec.get("zip") or []
    if not isinstance(groups, list):
        raise ConfigError("sweep.zip", groups, "a list of groups (mappings of dotted keys to "
                          "equal-length lists)", source)

    raw: list[tuple] = []   # (kind, keys, values, name, labels)
    for key, values in grid.items():
        where = f"sweep.grid.{key}"
        _check_swept_key(key, base, "sweep.grid", source)
        values = _check_values(values, where, source)
        _check_unique(values, where, source)
        raw.append(("grid", (key,), (values,), None, None))
    for g, group in enumerate(groups):
        where = f"sweep.zip[{g}]"
        if not isinstance(group, Mapping):
            raise ConfigError(where, group, "a mapping of dotted keys to equal-length lists", source)
        keys = [k for k in group if k not in ZIP_META_KEYS]
        if not keys:
            raise ConfigError(where, dict(group), "at least one dotted config key with a list of "
                              "values", source)
        length = len(group[keys[0]]) if isinstance(group[keys[0]], list) else None
        values = []
        for key in keys:
            _check_swept_key(key, base, where, source)
            values.append(_check_values(group[key], f"{where}.{key}", source, length))
        name = group.get("name")
        if name is not None and (not isinstance(name, str) or not name.isidentifier()):
            raise ConfigError(f"{where}.name", name, "a dimension name (letters, digits, _)", source)
        labels = group.get("labels")
        if labels is not None:
            labels = _check_values(labels, f"{where}.labels", source, length)
            _check_unique(labels, f"{where}.labels", source)
        raw.append(("zip", tuple(keys), tuple(values), name, labels))

    sample = spec.get("sample")
    if sample is not None:
        # the cases of every other dimension: a sample is drawn only if the total fits
        others = [(len(values[0]), name or keys[0]) for _, keys, values, name, _ in raw]
        if members > 1:
            others.append((members, MEMBER_DIM))
        sample_keys, drawn = _parse_sample(sample, base, source,
                                           lambda n: _check_case_count([*others, (n, SAMPLE_DIM)],
                                                                       max_cases, too_many_hint, source))
        raw.append(("sample", sample_keys, drawn, SAMPLE_DIM, tuple(range(len(drawn[0])))))

    all_keys = [k for _, keys, *_ in raw for k in keys]
    for key in all_keys:
        if all_keys.count(key) > 1:
            raise ConfigError(f"sweep.{key}", None, "each key in one grid entry or zip group only",
                              source, got="a key swept twice")
    for seconds, revolutions in ALTERNATIVES:
        if seconds in all_keys and revolutions in all_keys:
            raise ConfigError(f"sweep.{revolutions}", None, f"one of {seconds} and {revolutions} "
                              "swept, not both (the same length in two units)", source,
                              got="both swept")
    short = {k: dimension_name(k) for k in all_keys}
    reserved = _reserved_names()
    names = {k: (_full_name(k) if list(short.values()).count(s) > 1 or s in reserved else s)
             for k, s in short.items()}

    axes: list[Axis] = []
    taken = set(names.values())
    if len(taken) != len(all_keys):
        raise ConfigError("sweep", all_keys, "keys with distinct coordinate names", source)
    for kind, keys, values, name, labels in raw:
        if kind == "grid":
            axes.append(Axis(names[keys[0]], kind, keys, (names[keys[0]],), values))
            continue
        dim = name or names[keys[0]] + "_zip"
        if dim in taken or dim in reserved:
            raise ConfigError(f"sweep.zip.{dim}", dim, "a dimension name used by no other sweep "
                              "coordinate or case variable", source, got=f"{dim!r} again")
        taken.add(dim)
        axes.append(Axis(dim, kind, keys, tuple(names[k] for k in keys), values, labels))
    return axes


def sample_points(method: str, n: int, ranges: Mapping[str, Sequence[float]], seed: int,
                  second_order: bool = False) -> np.ndarray:
    """Points of a sampling sweep, one row per case, one column per key of ``ranges``.

    ``sobol``: n scrambled Sobol' points (``scipy.stats.qmc.Sobol``, n a power of 2 keeps
    its balance); ``lhs``: n Latin hypercube points (``scipy.stats.qmc.LatinHypercube``);
    ``saltelli``: SALib's Saltelli design for Sobol' indices with n base points,
    n (D + 2) cases (n (2 D + 2) with ``second_order``). Seeded: the same arguments give
    the same points.
    """
    lo = np.array([float(r[0]) for r in ranges.values()])
    hi = np.array([float(r[1]) for r in ranges.values()])
    if method in ("sobol", "saltelli") and n & (n - 1):
        # scipy and SALib say "The balance properties of Sobol' points require n to be a
        # power of 2" without naming the key: say it once, in clearsweep's words
        below = 1 << (n.bit_length() - 1)
        warnings.warn(f"sweep.sample.n: {n} is not a power of 2; Sobol' points (method "
                      f"{method}) are balanced at n = 2^k only: {below} or {2 * below} keeps "
                      "that balance", ClearsweepWarning, stacklevel=2)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="The balance properties of Sobol' points")
        if method == "saltelli":
            from SALib.sample import sobol as saltelli

            problem = {"num_vars": len(ranges), "names": list(ranges),
                       "bounds": [[a, b] for a, b in zip(lo, hi)]}
            return saltelli.sample(problem, n, calc_second_order=second_order, seed=seed)
        from scipy.stats import qmc

        engine = (qmc.Sobol(len(ranges), scramble=True, seed=seed) if method == "sobol"
                  else qmc.LatinHypercube(len(ranges), seed=seed))
        return qmc.scale(engine.random(n), lo, hi)


def sample_size(method: str, n: int, dims: int, second_order: bool = False) -> int:
    """Points :func:`sample_points` draws: n, or n (D + 2) for saltelli (n (2 D + 2) with
    second-order indices)."""
    if method != "saltelli":
        return n
    return n * (2 * dims + 2 if second_order else dims + 2)


def _parse_sample(spec, base: Config, source: str,
                  check_count: Callable[[int], None] | None = None
                  ) -> tuple[tuple[str, ...], tuple[tuple, ...]]:
    """The keys and per-key values of a ``sample:`` section; ``check_count(points)`` refuses
    too many before any is drawn (at most MAX_SAMPLE_POINTS in any case)."""
    where = "sweep.sample"
    if not isinstance(spec, Mapping):
        raise ConfigError(where, spec, f"a mapping with keys {', '.join(SAMPLE_KEYS)}", source)
    _check_keys(spec, SAMPLE_KEYS, where, source)
    method = spec.get("method", "sobol")
    if method not in SAMPLE_METHODS:
        raise ConfigError(f"{where}.method", method, " or ".join(SAMPLE_METHODS), source,
                          close_match(method, SAMPLE_METHODS))
    for name, value in spec.items():
        inner = value.items() if name == "ranges" and isinstance(value, Mapping) else [(None, value)]
        for key, item in inner:
            big = oversized_number(item)
            if big is not None:
                raise ConfigError(f"{where}.{name}" + (f".{key}" if key else ""), item,
                                  OVERSIZED, source, got=oversized_text(big))
    n = spec.get("n")
    if not isinstance(n, int) or isinstance(n, bool) or n < 1:
        raise ConfigError(f"{where}.n", n, "an integer >= 1 (points, or base points of saltelli)",
                          source)
    seed = spec.get("seed", 0)
    if not isinstance(seed, int) or isinstance(seed, bool) or seed < 0:
        raise ConfigError(f"{where}.seed", seed, "an integer >= 0", source)
    second = spec.get("second_order", False)
    if not isinstance(second, bool):
        raise ConfigError(f"{where}.second_order", second, "true or false", source)
    ranges = spec.get("ranges")
    if not isinstance(ranges, Mapping) or not ranges:
        raise ConfigError(f"{where}.ranges", ranges, "a mapping of dotted config keys to "
                          "[low, high]", source)
    for key, bounds in ranges.items():
        _check_swept_key(key, base, f"{where}.ranges", source)
        if (not isinstance(bounds, list) or len(bounds) != 2
                or not all(isinstance(b, (int, float)) and not isinstance(b, bool) for b in bounds)
                or not bounds[0] < bounds[1]):
            raise ConfigError(f"{where}.ranges.{key}", bounds, "[low, high], two numbers with "
                              "low < high", source)
        _check_range_ends(key, bounds, base, f"{where}.ranges.{key}", source)
    if second and method != "saltelli":
        raise ConfigError(f"{where}.second_order", second, f"false with method {method} (second-"
                          "order indices are drawn by the saltelli design only)", source)
    size = sample_size(method, n, len(ranges), second)
    if size > MAX_SAMPLE_POINTS:
        raise ConfigError(f"{where}.n", n, f"at most {MAX_SAMPLE_POINTS:,} points in all (the "
                          "points are drawn in memory)", source,
                          got=str(n) if size == n else f"{n} ({method}: {size:,} points)")
    if check_count is not None:
        check_count(size)
    points = sample_points(method, n, ranges, seed, second)
    return tuple(ranges), tuple(tuple(float(v) for v in points[:, i]) for i in range(len(ranges)))


def _check_range_ends(key: str, bounds: Sequence[float], base: Config, where: str,
                      source: str) -> None:
    """Refuse a sample range whose ends are not values ``key`` takes with the base: else a
    point outside them fails, or not, by the luck of the draw."""
    for end in bounds:
        cfg = base.to_dict()
        set_setting(cfg, key, float(end))
        try:
            load_config(cfg, source_name=source)
        except ConfigError as exc:
            raise ConfigError(where, list(bounds), f"a range of values {key} takes: at {end!r}, "
                              f"{exc.key} expected {exc.expected}", source) from None


def _check_case_count(sizes: Sequence[tuple[int, str]], max_cases: int | None, hint: str,
                      source: str) -> None:
    """Refuse more than ``max_cases`` cases, from the dimensions' sizes alone (nothing of
    the cases is made before)."""
    n_points = math.prod(size for size, _ in sizes)
    shape = " x ".join(f"{size:,} {dim}" for size, dim in sizes)
    if n_points > MAX_CASES_ANY:
        raise ConfigError("sweep", None, f"at most {MAX_CASES_ANY:,} cases, --yes or not (the "
                          "plan holds every case in memory)", source, got=f"{n_points:,} cases ({shape})")
    if max_cases is not None and n_points > max_cases:
        raise ConfigError("sweep", None, f"at most {max_cases:,} cases ({hint})", source,
                          got=f"{n_points:,} cases ({shape})")


def member_axes(base: Config, store: str = "full") -> list[Axis]:
    """The ``member`` dimension that ``base`` adds to a sweep of ``store``
    (:attr:`~clearsweep.sweeping.stores.Store.members`: an ensemble's, ``ensemble.members >
    1``, or a reliability sweep's ``reliability.members`` life runs), else none."""
    members = STORES[store].members(base)
    if members is None:
        return []
    return [Axis(MEMBER_DIM, "grid", (members.key,), (MEMBER_DIM,), (tuple(range(members.count)),))]


def _parse_skips(rules, axes: Sequence[Axis], source: str) -> list[list[tuple[str, list]]]:
    """Skip rules as lists of (coordinate name, allowed values)."""
    if rules is None:
        return []
    if not isinstance(rules, list):
        raise ConfigError("sweep.skip", rules, "a list of rules (mappings of coordinate names to "
                          "a value or a list of values)", source)
    coord_values: dict[str, list] = {}
    by_key: dict[str, str] = {}
    for axis in axes:
        if axis.labels is not None:
            coord_values[axis.dim] = list(axis.labels)
        for key, name, vals in zip(axis.keys, axis.names, axis.values):
            coord_values[name] = list(vals)
            by_key[key] = name
    parsed = []
    for r, rule in enumerate(rules):
        where = f"sweep.skip[{r}]"
        if not isinstance(rule, Mapping) or not rule:
            raise ConfigError(where, rule, "a mapping of coordinate names to a value or a list of "
                              "values", source)
        conditions = []
        for given, wanted in rule.items():
            name = by_key.get(given) or given
            if name not in coord_values:
                raise ConfigError(f"{where}.{name}", wanted, "a sweep coordinate "
                                  f"({', '.join(coord_values)})", source,
                                  close_match(name, coord_values), got="an unknown coordinate")
            wanted = wanted if isinstance(wanted, list) else [wanted]
            for value in wanted:
                if value not in coord_values[name]:
                    raise ConfigError(f"{where}.{name}", value, "one of the swept values "
                                      f"{coord_values[name]!r}", source)
            conditions.append((name, wanted))
        parsed.append(conditions)
    return parsed


def _case_error(exc: ConfigError, assignment: Mapping[str, Any], label: Mapping[str, Any],
                source: str) -> ConfigError:
    """Re-raise a case's ConfigError naming the sweep key and value that caused it."""
    if not assignment:  # a sweep without axes: its one case is the base
        return ConfigError(exc.key, exc.value, exc.expected, source, exc.suggestion, exc.got)
    key = next((k for k in assignment if exc.key and (exc.key == k or exc.key.startswith(k + "."))),
               None)
    case = ", ".join(f"{n}={v!r}" for n, v in label.items())
    if key is None:     # a relation between two keys (clearance < socket_radius)
        key = next((k for k in assignment if k in (exc.expected or "")), None)
    if key is None:     # a value of the base (or a --set) that this case cannot take: name it
        return ConfigError(exc.key, exc.value, f"{exc.expected} (in the sweep case {case})",
                           source, exc.suggestion, exc.got)
    expected = exc.expected if exc.key == key else (
        f"a value with which {exc.key} = {exc.value!r} is {exc.expected}")
    return ConfigError(key, assignment[key], f"{expected} (in the sweep case {case})", source,
                       exc.suggestion)


def _check_overrides(overrides: Iterable[str], axes: Sequence[Axis], source: str) -> None:
    swept = [k for a in axes for k in a.keys]
    for text in overrides:
        key = str(text).partition("=")[0].strip()
        for k in swept:
            if key == alternative_of(k):    # every case would replace it by the swept length
                raise ConfigError(key, text, f"a key other than {key}: the sweep gives this "
                                  f"length in {k}; change the values of {k} in the sweep file",
                                  "--set")
            if key == k or k.startswith(key + ".") or key.startswith(k + "."):
                raise ConfigError(key, text, "a key that the sweep does not vary; change the "
                                  f"values of {k} in the sweep file", "--set")


def expand(config_or_path: str | os.PathLike | Mapping, overrides: Iterable[str] = (), *,
           allow_large: bool = False, max_cases: int | None = MAX_CASES,
           too_many_hint: str = TOO_MANY_HINT, enumerate_cases: bool = True) -> SweepPlan:
    """Read a sweep, validate every case and return the plan; nothing runs.

    Parameters
    ----------
    config_or_path
        Sweep YAML file, or the same as a mapping (a ``base:`` path is then
        relative to the current folder).
    overrides
        ``"dotted.key=VALUE"`` strings applied to the base (``--set``).
    allow_large
        Admit cases beyond the work and memory bounds of
        :func:`clearsweep.budget.check_budget`.
    max_cases
        Refuse a sweep of more points than this (computed from the axes' sizes and the
        member count before any case, member or sample point is made); ``None``: no limit
        (``--yes``).
    too_many_hint
        What the refusal tells the user to type instead (the command in use).
    enumerate_cases
        False (``validate``, ``--dry-run``): a sweep of more than MAX_CASES points is
        counted from its dimensions, not enumerated: only the cases of
        :func:`counted_positions` are made and checked, and :attr:`SweepPlan.counted`
        holds the whole sweep's points and skipped points.

    Returns
    -------
    SweepPlan

    Raises
    ------
    ConfigError
        Malformed sweep file, unknown key, or a case that the config does not
        admit (the error names the sweep key, its value and the case).
    """
    overrides = [overrides] if isinstance(overrides, str) else list(overrides)
    doc, source, base_dir, stem = _read_sweep(config_or_path)
    _check_keys(doc, SWEEP_FILE_KEYS, None, source)
    name = doc.get("name", stem)
    if not isinstance(name, str) or not name:
        raise ConfigError("name", name, "a non-empty string", source)
    store = doc.get("store", "full")
    if store not in STORE_MODES:
        raise ConfigError("store", store, " or ".join(STORE_MODES), source, close_match(store, STORE_MODES))
    kind = STORES[store]
    base = _load_base(doc.get("base"), base_dir, source, overrides)
    spec = _files_from(doc.get("sweep"), base_dir)
    kind.check_base(base, source)
    member_axis = member_axes(base, store)
    members = member_axis[0].size if member_axis else 1
    axes = _parse_axes(spec, base, source, max_cases, members, too_many_hint)
    _check_case_count([(a.size, a.dim) for a in axes] + ([(members, MEMBER_DIM)] if members > 1 else []),
                      max_cases, too_many_hint, source)
    axes += member_axis
    _check_overrides(overrides, axes, source)
    skips = _parse_skips((spec or {}).get("skip"), axes, source)

    n_points = math.prod(a.size for a in axes)
    counted = None
    indices: Iterable[tuple[int, ...]] = itertools.product(*(range(a.size) for a in axes))
    if not enumerate_cases and n_points > MAX_CASES:
        indices = counted_positions(axes)
        counted = (n_points, _count_skipped(axes, skips))
    cases = []
    for index in indices:
        assignment, label = {}, {}
        for axis, i in zip(axes, index):
            assignment.update(axis.assignment(i))
            label.update(axis.label(i))
        rule = next((r for r, conds in enumerate(skips)
                     if all(label[n] in wanted for n, wanted in conds)), None)
        if rule is not None:
            cases.append(Case(index, None, None, f"excluded by sweep.skip[{rule}]"))
            continue
        cfg = base.to_dict()
        for key, value in assignment.items():
            set_setting(cfg, key, value)
        try:
            resolved = load_config(cfg, source_name=source)
            kind.check_case(resolved, source, allow_large, label)
        except ConfigError as exc:
            raise _case_error(exc, assignment, label, source) from None
        cases.append(Case(index, case_key(resolved, store), resolved))

    if cases and all(c.hash is None for c in cases):
        raise ConfigError("sweep.skip", (spec or {}).get("skip"), "rules that leave at least one "
                          "case to run", source, got=f"rules that skip all {len(cases)} cases")
    text = dump_config({"name": name, "store": store, "base": base.to_dict(), "sweep": spec or {}})
    base_file = doc.get("base")
    return SweepPlan(name, store, source, text, base, tuple(axes), cases,
                     base_file=str(base_dir / base_file) if isinstance(base_file, str) else None,
                     counted=counted)


def counted_positions(axes: Sequence[Axis], most: int = COUNTED_POSITIONS) -> list[tuple[int, ...]]:
    """The cases a counted plan checks, in sweep order: every dimension at its first value,
    and each dimension in turn at up to ``most`` evenly spread positions and at the smallest
    and largest value of each of its numeric keys, the others at their first."""
    found = {(0,) * len(axes)}
    for d, axis in enumerate(axes):
        spots = set(np.linspace(0, axis.size - 1, min(most, axis.size)).round().astype(int).tolist())
        for values in axis.values:
            if all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values):
                spots.update((int(np.argmin(values)), int(np.argmax(values))))
        for i in spots:
            found.add(tuple(i if k == d else 0 for k in range(len(axes))))
    return sorted(found)


def _count_skipped(axes: Sequence[Axis], skips: Sequence[Sequence[tuple[str, list]]]) -> int:
    """Points excluded by the skip rules, counted over the dimensions they name only."""
    if not skips:
        return 0
    names = {n for rule in skips for n, _ in rule}
    named = [d for d, a in enumerate(axes) if names & {a.dim, *a.names}]
    others = math.prod(a.size for d, a in enumerate(axes) if d not in named)
    hits = 0
    for index in itertools.product(*(range(axes[d].size) for d in named)):
        label: dict[str, Any] = {}
        for d, i in zip(named, index):
            label.update(axes[d].label(i))
        hits += any(all(label[n] in wanted for n, wanted in rule) for rule in skips)
    return hits * others
