"""Parameter sweeps: expansion, backends, resume and assembly (DESIGN.md section 9).

Sweep file
----------
::

    name: coating_clearance        # optional; default: the file's stem
    store: full                    # full (time series + summaries) | summary
    base: case.yaml                # a case config: inline mapping, or a path relative to this file
    sweep:
      grid:                        # cartesian product; one dimension per key
        joints.B.coating: [none, MoS2, lead, PTFE]
        joints.B.clearance: [1.0e-4, 2.5e-4, 5.0e-4]
      zip:                         # each group is ONE dimension; its keys vary together
        - name: clearance_joints   # optional dimension name
          labels: [B, AB]          # optional index values of that dimension
          joints.A.clearance: [0.0, 2.5e-4]
      skip:                        # optional; matching points are not run (status "skipped")
        - {B_coating: none, B_clearance: 1.0e-4}

Keys are dotted paths of the case configuration (docs/architecture.md).
Command-line ``--set KEY=VALUE`` overrides apply to the base; a key that the
sweep varies cannot be overridden.

Naming
------
Each grid key becomes a dimension whose index coordinate holds the values as
given (material names stay strings, so ``ds.sel(B_coating="PTFE")`` works).
Its name is the dotted key with the first component dropped when that is
``joints``, ``mechanism``, ``contact``, ``friction``, ``wear`` or ``solver``,
and the rest joined with ``_``: ``joints.B.coating`` -> ``B_coating``,
``joints.B.clearance`` -> ``B_clearance``, ``mechanism.speed_rpm`` ->
``speed_rpm``, ``wear.amplification`` -> ``amplification``. Keys whose short
names collide with each other or with a variable or coordinate of a case
(``friction.enabled`` and ``wear.enabled``) get the full path joined with
``_`` (``friction_enabled``, ``wear_enabled``).

A zip group becomes one dimension named by its ``name:``, else by its first
key's name + ``_zip``; every key of the group is a non-index coordinate along
it, and ``labels:``, when given, is its index coordinate. Values that are not
all numbers, all booleans or all strings (``null``, lists) are stored as their
JSON text. Dimensions come in file order: grid keys, then zip groups.

A ``skip:`` rule maps coordinate names (or dotted keys) to a value or a list
of values; a point matching every entry of a rule is not run and is stored
with ``status = "skipped"`` (the paper sweep skips coatings on ideal joints).

Running
-------
:func:`expand` validates every case with :func:`clearsweep.config.load_config`
before anything runs: an invalid combination raises ``ConfigError`` naming
the sweep key, its value and the case. :func:`run_sweep` then runs the cases
that have no part yet, serially (one worker), on a process pool
(``forkserver`` or ``spawn``: Numba and ``fork`` do not mix) or on a Dask
``distributed`` client given by the caller (the library never starts a
cluster; ``clearsweep sweep --dask-local N`` does, and closes it). Each
finished case is written at once to ``OUT.parts/<hash>.nc``
(:mod:`clearsweep.store`): by the pool worker that ran it, or by the driver
for Dask workers, which may not share its disk. The final file is assembled
from the parts in sweep order, one case at a time, so results do not depend
on the backend, the number of workers or the completion order.

A case whose simulation does not end with status ``ok``, or raises, is
stored with its status, a ``message`` and fill values (NaN), and the sweep
goes on.
"""

from __future__ import annotations

import concurrent.futures as cf
import copy
import itertools
import json
import multiprocessing
import os
import shlex
import shutil
import signal
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import click
import numpy as np
import xarray as xr

from . import variables
from .config import ConfigError, close_match, dump_config, get_path, load_config, read_yaml, set_path
from .simulation import preflight
from .dataset import versions
from .store import (MESSAGE_ATTRS, NOT_FAILED, STATUS_ATTRS, PartStore, StoreError, SweepSlot,
                    canonical_json, case_hash, history_line, open_results, parts_dir_for,
                    write_part, write_sweep_netcdf)

__all__ = ["Axis", "SweepPlan", "SweepInterrupted", "SweepFailed", "StoreError", "expand",
           "run_sweep", "sweep", "open_results", "drop_timing", "dimension_name", "process_pool",
           "sweep_command",
           "STORE_MODES", "TIMING_VARIABLES"]

#: First components of a dotted key that the dimension name leaves out.
DROPPED_SECTIONS = ("joints", "mechanism", "contact", "friction", "wear", "solver")
#: What a sweep stores per case.
STORE_MODES = ("full", "summary")
#: Variables (and dataset attributes) that change from run to run of the same sweep.
TIMING_VARIABLES = ("wall_time",)
TIMING_ATTRS = ("history",)
#: Top-level keys of a sweep file.
SWEEP_FILE_KEYS = ("name", "store", "base", "sweep")
SWEEP_KEYS = ("grid", "zip", "skip")
#: Keys of a zip group that are not config keys.
ZIP_META_KEYS = ("name", "labels")
#: Futures kept in flight per worker, so that no worker waits for the driver.
IN_FLIGHT_PER_WORKER = 2
#: How often a pool worker checks that the driver process still exists [s].
WATCHDOG_PERIOD_S = 1.0


class SweepInterrupted(KeyboardInterrupt):
    """The sweep was stopped (Ctrl-C) before it finished; its finished cases are kept.

    Attributes
    ----------
    finished, total : int
        Cases with a part, and cases to run, in the sweep.
    parts_dir : pathlib.Path
        Where the finished cases are.
    """

    def __init__(self, finished: int, total: int, parts_dir: Path):
        super().__init__(f"sweep interrupted: {finished} of {total} cases finished (kept in {parts_dir})")
        self.finished, self.total, self.parts_dir = finished, total, parts_dir


class SweepFailed(RuntimeError):
    """The backend failed (a worker died, the scheduler went away); finished cases are kept."""


# ---------------------------------------------------------------------------- naming

def _reserved_names() -> set[str]:
    return {*variables.CASE_VARIABLES, *variables.COORDINATES, *variables.SUMMARY_VARIABLES,
            "status", "message"}


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
        ``"grid"`` or ``"zip"``.
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
            out[self.dim] = (self.dim, _coord_values(self.labels),
                             {"long_name": f"sweep zip group {self.dim}",
                              "config_keys": " ".join(self.keys)})
        for key, name, vals in zip(self.keys, self.names, self.values):
            attrs = {"long_name": f"swept config value {key}", "config_key": key}
            array = _coord_values(vals)
            if array.dtype == object and not all(isinstance(v, str) for v in vals):
                attrs["comment"] = "values stored as JSON text"
            out[name] = (self.dim, array, attrs)
        return out


@dataclass(frozen=True)
class Case:
    """One sweep point: its position, and its resolved config (``None`` when skipped)."""

    index: tuple[int, ...]
    hash: str | None
    config_json: str | None
    skip_message: str = ""

    @property
    def config(self) -> dict | None:
        """The resolved case configuration."""
        return None if self.config_json is None else json.loads(self.config_json)


@dataclass
class SweepPlan:
    """A validated, expanded sweep: its axes and one :class:`Case` per point, in C order.

    Holds the resolved configuration (as JSON text) of every case, never results.
    """

    name: str
    store: str
    source: str
    text: str
    base: dict
    axes: tuple[Axis, ...]
    cases: list[Case]

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

    def runnable(self) -> dict[str, str]:
        """Hash -> resolved config JSON of each distinct case to run, in sweep order."""
        return {c.hash: c.config_json for c in self.cases if c.hash is not None}

    def slots(self) -> list[SweepSlot]:
        """The sweep points for :func:`clearsweep.store.write_sweep_netcdf`."""
        return [SweepSlot(c.hash, c.skip_message) for c in self.cases]

    def to_dataset(self) -> xr.Dataset:
        """The sweep coordinates alone (no data), e.g. to look at a plan before running it."""
        return xr.Dataset(coords={n: (d, v, a) for n, (d, v, a) in self.coords.items()})


# ---------------------------------------------------------------------------- expansion

def _read_sweep(config_or_path) -> tuple[dict, str, Path, str]:
    """(document, source name, folder for relative paths, default name)."""
    if isinstance(config_or_path, Mapping):
        return copy.deepcopy(dict(config_or_path)), "<sweep>", Path.cwd(), "sweep"
    path = Path(config_or_path)
    doc = read_yaml(path, str(config_or_path))
    if not isinstance(doc, dict):
        raise ConfigError(None, doc, f"a sweep mapping with keys {', '.join(SWEEP_FILE_KEYS)}",
                          str(config_or_path))
    return doc, str(config_or_path), path.resolve().parent, path.stem


def _check_keys(mapping: Mapping, allowed: Sequence[str], where: str | None, source: str) -> None:
    for key in mapping:
        if key not in allowed:
            full = f"{where}.{key}" if where else str(key)
            suggestion = close_match(key, allowed)
            raise ConfigError(full, mapping[key], f"one of the keys {', '.join(allowed)}", source,
                              f"{where}.{suggestion}" if where and suggestion else suggestion,
                              got="an unknown key")


def _load_base(base, base_dir: Path, source: str, overrides: Sequence[str]) -> dict:
    if base is None:
        base = {}
    if isinstance(base, str):
        path = base_dir / base
        if not path.is_file():
            raise ConfigError("base", base, "an inline case config or the path of a case YAML file "
                              f"(relative to the sweep file; looked for {path})", source)
        return load_config(path, overrides, source_name=f"{source}: base {base}")
    if not isinstance(base, Mapping):
        raise ConfigError("base", base, "an inline case config (a mapping) or the path of a case "
                          "YAML file", source)
    base = copy.deepcopy(dict(base))
    materials = base.get("materials_file")
    if isinstance(materials, str) and not os.path.isabs(os.path.expanduser(materials)):
        base["materials_file"] = str(base_dir / materials)
    return load_config(base, overrides, source_name=f"{source}: base")


def _check_swept_key(key, base: dict, where: str, source: str) -> str:
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
    return key


def _check_values(values, where: str, source: str, length: int | None = None) -> tuple:
    if not isinstance(values, list) or not values:
        raise ConfigError(where, values, "a non-empty list of values", source)
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


def _parse_axes(spec, base: dict, source: str) -> list[Axis]:
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

    raw = []            # (kind, keys, values, name, labels)
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

    all_keys = [k for _, keys, *_ in raw for k in keys]
    for key in all_keys:
        if all_keys.count(key) > 1:
            raise ConfigError(f"sweep.{key}", None, "each key in one grid entry or zip group only",
                              source, got="a key swept twice")
    short = {k: dimension_name(k) for k in all_keys}
    reserved = _reserved_names()
    names = {k: (_full_name(k) if list(short.values()).count(s) > 1 or s in reserved else s)
             for k, s in short.items()}

    axes, taken = [], set(names.values())
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


def _parse_skips(rules, axes: Sequence[Axis], source: str) -> list[list[tuple[str, list]]]:
    """Skip rules as lists of (coordinate name, allowed values)."""
    if rules is None:
        return []
    if not isinstance(rules, list):
        raise ConfigError("sweep.skip", rules, "a list of rules (mappings of coordinate names to "
                          "a value or a list of values)", source)
    coord_values = {}
    by_key = {}
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
        for name, wanted in rule.items():
            name = by_key.get(name, name)
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
    if key is None:     # a relation between two keys (clearance < socket_radius)
        key = next((k for k in assignment if k in (exc.expected or "")), next(iter(assignment)))
    case = ", ".join(f"{n}={v!r}" for n, v in label.items())
    expected = exc.expected if exc.key == key else (
        f"a value with which {exc.key} = {exc.value!r} is {exc.expected}")
    return ConfigError(key, assignment[key], f"{expected} (in the sweep case {case})", source,
                       exc.suggestion)


def _check_overrides(overrides: Iterable[str], axes: Sequence[Axis], source: str) -> None:
    swept = [k for a in axes for k in a.keys]
    for text in overrides:
        key = str(text).partition("=")[0].strip()
        for k in swept:
            if key == k or k.startswith(key + ".") or key.startswith(k + "."):
                raise ConfigError(key, text, "a key that the sweep does not vary; change the "
                                  f"values of {k} in the sweep file", "--set")


def expand(config_or_path: str | os.PathLike | Mapping, overrides: Iterable[str] = ()) -> SweepPlan:
    """Read a sweep, validate every case and return the plan; nothing runs.

    Parameters
    ----------
    config_or_path
        Sweep YAML file, or the same as a mapping (a ``base:`` path is then
        relative to the current folder).
    overrides
        ``"dotted.key=VALUE"`` strings applied to the base (``--set``).

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
    base = _load_base(doc.get("base"), base_dir, source, overrides)
    spec = doc.get("sweep")
    axes = _parse_axes(spec, base, source)
    _check_overrides(overrides, axes, source)
    skips = _parse_skips((spec or {}).get("skip"), axes, source)

    cases = []
    for index in itertools.product(*(range(a.size) for a in axes)):
        assignment, label = {}, {}
        for axis, i in zip(axes, index):
            assignment.update(axis.assignment(i))
            label.update(axis.label(i))
        rule = next((r for r, conds in enumerate(skips)
                     if all(label[n] in wanted for n, wanted in conds)), None)
        if rule is not None:
            cases.append(Case(index, None, None, f"excluded by sweep.skip[{rule}]"))
            continue
        cfg = copy.deepcopy(base)
        for key, value in assignment.items():
            set_path(cfg, key, value)
        try:
            resolved = load_config(cfg, source_name=source)
            preflight(resolved)
        except ConfigError as exc:
            raise _case_error(exc, assignment, label, source) from None
        cases.append(Case(index, case_hash(resolved), canonical_json(resolved)))

    text = dump_config({"name": name, "store": store, "base": base, "sweep": spec or {}})
    return SweepPlan(name, store, source, text, base, tuple(axes), cases)


# ---------------------------------------------------------------------------- one case

def _text(value) -> str:
    value = np.asarray(value)
    return str(value[()] if value.ndim == 0 else value.ravel()[0])


def _failed_part(status: str, message: str, wall_time: float) -> xr.Dataset:
    return xr.Dataset({
        "status": ((), status, STATUS_ATTRS),
        "message": ((), message, MESSAGE_ATTRS),
        "wall_time": ((), float(wall_time), variables.attrs_for("wall_time")),
    })


def _run_case(payload: tuple) -> xr.Dataset:
    """Simulate one case and build its part (runs in a worker).

    Parameters
    ----------
    payload
        ``(config_json, store_mode, simulate, summarize)``; ``None`` for the
        last two means :func:`clearsweep.simulation.simulate` and
        :func:`clearsweep.analysis.case_summary`.

    Returns
    -------
    xr.Dataset
        Summaries, ``status`` and ``message``, and the time series unless
        ``store_mode == "summary"``. A case that raises, or stops with a
        status other than ``ok``, gives only ``status``, ``message`` and
        ``wall_time``.
    """
    config_json, store_mode, simulate, summarize = payload
    if simulate is None:
        from .simulation import simulate
    if summarize is None:
        from .analysis import case_summary as summarize
    start = time.perf_counter()
    try:
        ds = simulate(json.loads(config_json))
        status = _text(ds["status"].values)
        if status == "ok":
            summary = summarize(ds)
            part = summary.copy() if store_mode == "summary" else ds.copy()
            for name, var in summary.data_vars.items():
                part[name] = var
            part["message"] = ((), "", MESSAGE_ATTRS)
            return part
        if "message" in ds:
            message = _text(ds["message"].values)
        else:
            when = ds.attrs.get("status_time_s")
            message = f"the simulation stopped with status {status!r}" + (
                f" at t = {float(when):g} s" if when is not None else "")
        wall = float(ds["wall_time"].values) if "wall_time" in ds else time.perf_counter() - start
        return _failed_part(status, message, wall)
    except Exception as exc:    # a failed case, not a failed sweep
        return _failed_part("error", f"{type(exc).__name__}: {exc}", time.perf_counter() - start)


def _receipt(part: xr.Dataset) -> dict[str, Any]:
    """What the driver logs of a finished case."""
    wall = float(part["wall_time"].values) if "wall_time" in part else None
    return {"status": _text(part["status"].values), "wall_time": wall}


def _run_and_store(payload: tuple, parts_dir: str, h: str) -> dict[str, Any]:
    """Run one case and write its part here, in the worker; return its receipt.

    Writing in the worker keeps the driver (which shares the cores) idle
    while the cases run.
    """
    part = _run_case(payload)
    write_part(parts_dir, h, part)
    return _receipt(part)


# ---------------------------------------------------------------------------- backends

class _InterruptGuard:
    """Ctrl-C that never lands inside a file write.

    While active (main thread only), SIGINT raises ``KeyboardInterrupt``
    only inside :meth:`interruptible` blocks (waiting for workers, running a
    case in this process); anywhere else it is noted and raised by the next
    :meth:`check`. An interrupt inside netCDF/HDF5 or xarray's file locks can
    leave a lock held and hang the cleanup; this keeps it out of them.
    """

    def __init__(self):
        self.requested = False
        self._depth = 0
        self._previous = None

    def __enter__(self) -> _InterruptGuard:
        if threading.current_thread() is threading.main_thread():
            self._previous = signal.signal(signal.SIGINT, self._handler)
        return self

    def __exit__(self, *exc) -> None:
        if self._previous is not None:
            signal.signal(signal.SIGINT, self._previous)
            self._previous = None

    def _handler(self, signum, frame) -> None:
        first = not self.requested
        self.requested = True
        if first and self._depth:
            self._depth = 0
            raise KeyboardInterrupt

    @contextmanager
    def interruptible(self):
        """A block that Ctrl-C may interrupt at once."""
        self.check()
        self._depth += 1
        try:
            yield
        finally:
            self._depth = max(self._depth - 1, 0)

    def check(self) -> None:
        """Raise ``KeyboardInterrupt`` if Ctrl-C was pressed since the guard started."""
        if self.requested:
            raise KeyboardInterrupt


class _Serial:
    """Runs each case in this process when it is submitted."""

    label = "serial"
    window = 1

    def __init__(self, guard: _InterruptGuard):
        self.guard = guard

    def submit(self, h: str, payload) -> cf.Future:
        future = cf.Future()
        with self.guard.interruptible():
            part = _run_case(payload)
        future.set_result(part)
        return future

    def wait(self, futures):
        return futures

    def cancel(self, futures) -> None:
        pass

    def close(self, interrupted: bool = False) -> None:
        pass


def _driver_gone(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    except PermissionError:
        return False
    try:        # killed but not yet reaped by its parent
        with open(f"/proc/{pid}/stat", encoding="ascii") as f:
            return f.read().rpartition(")")[2].split()[0] in ("Z", "X")
    except (OSError, IndexError):
        return False


def _worker_init(driver_pid: int) -> None:
    """Pool worker set-up: leave Ctrl-C to the driver, and end when the driver is gone."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)

    def watch() -> None:
        # A killed driver cannot stop its pool; without this its workers would wait forever.
        while not _driver_gone(driver_pid):
            time.sleep(WATCHDOG_PERIOD_S)
        os._exit(1)

    threading.Thread(target=watch, name="clearsweep-driver-watch", daemon=True).start()


def _mp_context():
    methods = multiprocessing.get_all_start_methods()
    return multiprocessing.get_context("forkserver" if "forkserver" in methods else "spawn")


def process_pool(workers: int | None = None) -> cf.ProcessPoolExecutor:
    """A process pool set up as :func:`run_sweep` sets up its own.

    Pass it as ``client=`` to run several sweeps on the same warm workers
    (each worker loads the Numba kernel once); shut it down when done.

    Parameters
    ----------
    workers
        Worker processes (default: ``os.cpu_count()``).

    Returns
    -------
    concurrent.futures.ProcessPoolExecutor
        ``forkserver`` (or ``spawn``) workers that ignore Ctrl-C (the driver
        handles it) and exit by themselves when the driver process is gone.
    """
    return cf.ProcessPoolExecutor(max_workers=workers or os.cpu_count() or 1,
                                  mp_context=_mp_context(), initializer=_worker_init,
                                  initargs=(os.getpid(),))


class _Futures:
    """A ``concurrent.futures`` executor: our own process pool, or one the caller passes."""

    def __init__(self, executor: cf.Executor, own: bool, guard: _InterruptGuard, parts_dir: Path):
        self.executor, self.own, self.guard = executor, own, guard
        self.parts_dir = str(parts_dir)
        workers = getattr(executor, "_max_workers", None) or os.cpu_count() or 1
        self.window = IN_FLIGHT_PER_WORKER * workers
        self.label = f"{type(executor).__name__}({workers})"

    @classmethod
    def processes(cls, workers: int, guard: _InterruptGuard, parts_dir: Path) -> _Futures:
        return cls(process_pool(workers), own=True, guard=guard, parts_dir=parts_dir)

    def submit(self, h: str, payload) -> cf.Future:
        return self.executor.submit(_run_and_store, payload, self.parts_dir, h)

    def wait(self, futures):
        with self.guard.interruptible():
            return cf.wait(futures, return_when=cf.FIRST_COMPLETED).done

    def cancel(self, futures) -> None:
        for future in futures:
            future.cancel()

    def close(self, interrupted: bool = False) -> None:
        if not self.own:
            return
        if not interrupted:
            self.executor.shutdown(wait=True)
            return
        # Cases still running are lost anyway: stop their processes instead of waiting for them.
        processes = list((getattr(self.executor, "_processes", None) or {}).values())
        self.executor.shutdown(wait=False, cancel_futures=True)
        for process in processes:
            if process.is_alive():
                process.terminate()
        for process in processes:
            process.join(timeout=5)


class _Dask:
    """A ``distributed.Client`` (given, or connected here to a scheduler address).

    Workers may run on other machines: they send each finished case back and
    the driver writes its part.
    """

    def __init__(self, client, own: bool, guard: _InterruptGuard):
        self.client, self.own, self.guard = client, own, guard
        threads = sum(client.nthreads().values()) or 1
        self.window = IN_FLIGHT_PER_WORKER * threads
        self.label = f"dask({client.scheduler.address}, {threads} threads)"

    def submit(self, h: str, payload):
        return self.client.submit(_run_case, payload, pure=False)

    def wait(self, futures):
        from distributed import wait

        with self.guard.interruptible():
            return wait(futures, return_when="FIRST_COMPLETED").done

    def cancel(self, futures) -> None:
        if futures:
            self.client.cancel(list(futures))

    def close(self, interrupted: bool = False) -> None:
        if self.own:
            self.client.close()


def _backend(workers: int | None, client, n_cases: int, guard: _InterruptGuard, parts_dir: Path):
    if client is not None:
        if isinstance(client, cf.Executor):
            return _Futures(client, own=False, guard=guard, parts_dir=parts_dir)
        if isinstance(client, str):
            from distributed import Client

            return _Dask(Client(client), own=True, guard=guard)
        return _Dask(client, own=False, guard=guard)
    workers = (os.cpu_count() or 1) if workers is None else int(workers)
    if workers < 1:
        raise ValueError(f"workers must be >= 1, got {workers}")
    workers = min(workers, n_cases)
    return _Serial(guard) if workers <= 1 else _Futures.processes(workers, guard, parts_dir)


def _drive(backend, tasks: Iterable[tuple[str, tuple]], on_result: Callable[[str, Any], None],
           guard: _InterruptGuard) -> None:
    """Keep ``backend.window`` cases in flight; hand each result to ``on_result``.

    A result is the case's part (a dataset) or, where the worker wrote the
    part itself, its receipt. Only the result being handled is held, so
    memory does not grow with the sweep.
    """
    tasks = iter(tasks)
    pending: dict[Any, str] = {}

    def refill() -> None:
        for h, payload in itertools.islice(tasks, backend.window - len(pending)):
            pending[backend.submit(h, payload)] = h

    try:
        refill()
        while pending:
            for future in backend.wait(list(pending)):
                h = pending.pop(future)
                on_result(h, future.result())
            guard.check()
            refill()
    except BaseException:
        backend.cancel(list(pending))
        raise


# ---------------------------------------------------------------------------- the sweep

def drop_timing(ds: xr.Dataset) -> xr.Dataset:
    """``ds`` without what changes from run to run (``wall_time``, ``history``).

    Two runs of one sweep, on any backend and any number of workers, are
    identical after this (``xr.testing.assert_identical``).
    """
    out = ds.drop_vars([v for v in TIMING_VARIABLES if v in ds.variables])
    out.attrs = {k: v for k, v in ds.attrs.items() if k not in TIMING_ATTRS}
    return out


def _attrs(plan: SweepPlan) -> dict[str, Any]:
    return {
        "title": "clearsweep RSSP mechanism parameter sweep",
        "Conventions": "CF-1.8",
        "source": "clearsweep",
        "history": history_line(f"clearsweep sweep {plan.name!r} from {plan.source}"),
        "sweep_name": plan.name,
        "sweep_store": plan.store,
        "sweep_dims": " ".join(plan.dims),
        "sweep_config": plan.text,
        **versions(),
    }


def run_sweep(config_or_path: str | os.PathLike | Mapping, out: str | os.PathLike | None = None,
              workers: int | None = None, client=None, resume: bool = False,
              overrides: Iterable[str] = (), progress: bool = True, *, overwrite: bool = False,
              keep_parts: bool = False, _simulate: Callable | None = None,
              _summarize: Callable | None = None) -> xr.Dataset:
    """Run a parameter sweep and return its results as one labelled dataset.

    Parameters
    ----------
    config_or_path
        Sweep YAML file or mapping (module docstring).
    out
        netCDF file to write. ``None``: work in a temporary folder and
        return the dataset loaded into memory (small sweeps only).
    workers
        Worker processes (default: ``os.cpu_count()``); 1 runs the cases in
        this process. Ignored when ``client`` is given.
    client
        A ``distributed.Client``, a scheduler address (connected to here and
        disconnected after), or a ``concurrent.futures.Executor`` owned by
        the caller (e.g. :func:`process_pool`, to reuse warm workers across
        sweeps). The library never starts a cluster.
    resume
        Keep the finished cases of an interrupted run (``OUT.parts``) and run
        only the others; no case runs twice.
    overrides
        ``"dotted.key=VALUE"`` applied to the base configuration.
    progress
        Show a progress bar (tqdm, on stderr) with the number of failed cases.
    overwrite
        Delete the parts of an earlier run instead of refusing to start.
    keep_parts
        Keep ``OUT.parts`` after the final file is written.

    Returns
    -------
    xr.Dataset
        Sweep dimensions first, then the case dimensions; ``status`` and
        ``message`` per case; attributes ``sweep_config``, ``sweep_dims``,
        ``sweep_failed``, versions and ``history``. Opened lazily from
        ``out`` when given (close it when done).

    Raises
    ------
    ConfigError
        Invalid sweep or case (before anything runs; no file is written).
    StoreError
        ``OUT.parts`` holds earlier parts and neither ``resume`` nor
        ``overwrite`` was given, or another sweep is using it.
    SweepInterrupted
        Ctrl-C: pending cases cancelled, finished ones kept for ``resume``.
    SweepFailed
        The backend failed; finished cases are kept for ``resume``.
    """
    plan = expand(config_or_path, overrides)
    tmpdir = None
    if out is None:
        tmpdir = tempfile.mkdtemp(prefix="clearsweep-")
        out = Path(tmpdir) / f"{plan.name}.nc"
    out = Path(out)
    store = PartStore(parts_dir_for(out))
    try:
        with _InterruptGuard() as guard:
            finished = store.open(resume=resume, overwrite=overwrite)
            try:
                runnable = plan.runnable()
                todo = [(h, (cfg, plan.store, _simulate, _summarize))
                        for h, cfg in runnable.items() if h not in finished]
                _execute(plan, store, todo, len(runnable), workers, client, progress, guard)
                try:
                    counts = write_sweep_netcdf(out, sweep_dims=plan.dims, sweep_coords=plan.coords,
                                                slots=plan.slots(), store=store, attrs=_attrs(plan),
                                                check=guard.check)
                except KeyboardInterrupt:
                    store.log("interrupted", finished=len(runnable), total=len(runnable))
                    raise SweepInterrupted(len(runnable), len(runnable), store.directory) from None
                store.log("assembled", path=str(out), **counts)
            finally:
                store.close()
        if not keep_parts:
            store.remove()
        if tmpdir is None:
            return open_results(out)
        with open_results(out) as ds:
            return ds.load()
    finally:
        if tmpdir is not None:
            shutil.rmtree(tmpdir, ignore_errors=True)


def _execute(plan: SweepPlan, store: PartStore, todo: list, total: int, workers, client,
             progress: bool, guard: _InterruptGuard) -> None:
    """Run ``todo`` on the chosen backend, writing each finished case at once."""
    from tqdm.auto import tqdm

    kept = total - len(todo)
    runnable = plan.runnable()
    failed = sum(1 for r in store.events("done") if r.get("status") not in NOT_FAILED
                 and r.get("hash") in runnable) if kept else 0
    try:
        backend = (_backend(workers, client, len(todo), guard, store.directory) if todo
                   else _Serial(guard))
    except (OSError, TimeoutError) as exc:
        raise SweepFailed(f"cannot start the backend for {client or workers!r}: "
                          f"{type(exc).__name__}: {exc}") from exc
    store.log("run", name=plan.name, cases=len(plan.cases), to_run=len(todo), kept=kept,
              backend=backend.label)
    bar = tqdm(total=total, initial=kept, desc=plan.name, unit="case", disable=not progress,
               file=sys.stderr, dynamic_ncols=True)
    bar.set_postfix(failed=failed)
    done = kept

    def on_result(h: str, result) -> None:
        nonlocal failed, done
        if isinstance(result, xr.Dataset):
            store.write(h, result)
            result = _receipt(result)
        store.log("done", hash=h, **result)
        failed += result["status"] not in NOT_FAILED
        done += 1
        bar.set_postfix(failed=failed, refresh=False)
        bar.update()

    interrupted = False
    try:
        _drive(backend, todo, on_result, guard)
    except KeyboardInterrupt:
        interrupted = True
        store.log("interrupted", finished=done, total=total)
        raise SweepInterrupted(done, total, store.directory) from None
    except Exception as exc:
        interrupted = True
        store.log("failed", error=f"{type(exc).__name__}: {exc}")
        raise SweepFailed(f"the {backend.label} backend failed ({type(exc).__name__}: {exc}); "
                          f"{done} of {total} cases are kept in {store.directory}; run again "
                          "with --resume to finish the sweep") from exc
    finally:
        bar.close()
        backend.close(interrupted=interrupted)


#: Public name of :func:`run_sweep` (``clearsweep.sweep``).
sweep = run_sweep


# ---------------------------------------------------------------------------- command line

def _fail(message: str, code: int):
    click.echo(f"clearsweep: {message}", err=True)
    sys.exit(code)


@click.command("sweep", context_settings={"help_option_names": ["-h", "--help"]})
@click.argument("config", type=click.Path(dir_okay=False))
@click.option("-o", "--out", type=click.Path(dir_okay=False),
              help="Output netCDF file [default: <config stem>.nc in the current folder]; "
                   "finished cases are kept in OUT.parts/ until it is written.")
@click.option("--workers", type=click.IntRange(min=1), default=None,
              help="Worker processes [default: all cores]; 1 runs the cases in this process.")
@click.option("--resume", is_flag=True,
              help="Continue an interrupted sweep: keep the cases in OUT.parts/, run the others.")
@click.option("--overwrite", is_flag=True, help="Delete the parts of an earlier sweep in OUT.parts/.")
@click.option("--scheduler", metavar="ADDRESS", help="Run on this Dask distributed scheduler.")
@click.option("--dask-local", type=click.IntRange(min=1), metavar="N",
              help="Start a local Dask cluster of N single-thread worker processes for this sweep.")
@click.option("--set", "overrides", multiple=True, metavar="KEY=VALUE",
              help="Override a value of the base config (VALUE in YAML); repeatable.")
@click.option("--keep-parts", is_flag=True, help="Keep OUT.parts/ after writing OUT.")
@click.option("--no-progress", is_flag=True, help="Do not show the progress bar.")
def sweep_command(config: str, out: str | None, workers: int | None, resume: bool, overwrite: bool,
                  scheduler: str | None, dask_local: int | None, overrides: tuple[str, ...],
                  keep_parts: bool, no_progress: bool) -> None:
    """Run the parameter sweep described by CONFIG (YAML) and write one netCDF file.

    Exit status: 0 all cases ok (or skipped), 1 some cases failed (their
    status and message are in the file) or the output cannot be written,
    2 invalid config or options,
    130 interrupted (finished cases kept; rerun with --resume).
    """
    if scheduler and dask_local:
        raise click.UsageError("--scheduler and --dask-local both choose the Dask cluster; give one")
    if resume and overwrite:
        raise click.UsageError("--resume keeps the finished cases and --overwrite deletes them; "
                               "give one")
    out = out or f"{Path(config).stem}.nc"
    cluster = local_client = None
    try:
        client = scheduler
        if dask_local:
            from distributed import Client, LocalCluster

            cluster = LocalCluster(n_workers=dask_local, threads_per_worker=1, processes=True,
                                   host="127.0.0.1", dashboard_address=None)
            client = local_client = Client(cluster)
        ds = run_sweep(config, out, workers=workers, client=client, resume=resume,
                       overrides=overrides, progress=not no_progress, overwrite=overwrite,
                       keep_parts=keep_parts)
        with ds:
            n, failed = ds.attrs["sweep_cases"], ds.attrs["sweep_failed"]
            skipped = ds.attrs["sweep_skipped"]
    except (ConfigError, StoreError) as exc:
        _fail(f"error: {exc}", 2)
    except SweepInterrupted as exc:
        # The same cases only: the overrides are part of every case's hash.
        cmd = shlex.join(["clearsweep", "sweep", config, "-o", out, "--resume",
                          *(a for o in overrides for a in ("--set", o))])
        _fail(f"interrupted: {exc.finished} of {exc.total} cases are finished and kept in "
              f"{exc.parts_dir}; continue with: {cmd}", 130)
    except KeyboardInterrupt:
        _fail("interrupted before any case ran", 130)
    except SweepFailed as exc:
        _fail(f"error: {exc}", 1)
    except OSError as exc:
        _fail(f"error: cannot write {exc.filename or out}: {exc.strerror or exc}", 1)
    finally:
        if local_client is not None:
            local_client.close()
        if cluster is not None:
            cluster.close()
    note = f" ({skipped} skipped)" if skipped else ""
    if failed:
        _fail(f"{failed} of {n} cases failed{note}; see the status and message variables in {out}", 1)
    click.echo(f"clearsweep: wrote {out}: {n} cases{note}", err=True)
