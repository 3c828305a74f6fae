"""Per-case parts, resume bookkeeping and the bounded-memory sweep writer.

A sweep writing ``OUT.nc`` keeps its finished cases in the folder
``OUT.nc.parts/`` (:func:`parts_dir_for`):

- ``<hash>.nc``: one finished case (:func:`case_hash` of its resolved
  configuration), written to a temporary file in the same folder and renamed
  into place (:func:`clearsweep.dataset.write_netcdf_atomic`), so a part that
  is visible is complete. A killed sweep leaves at most a temporary
  ``.<hash>.nc.*.tmp`` file, which the next run removes.
- ``sweep.log``: one JSON line per event (``run``, ``done``, ``interrupted``,
  ``assembled``), appended by the driver; ``done`` lines carry the case hash,
  its status and the run id, so a log tells which run computed which case.
- ``.lock``: an exclusive ``flock`` held while a sweep uses the folder, so
  two sweeps cannot write the same parts; the kernel drops it when the
  process ends, however it ends.

:func:`write_sweep_netcdf` assembles the parts into the final file one case
at a time: it creates the netCDF4 file with every variable chunked one case
per chunk, copies each part into its slice, and renames the file into place.
A part stores each whole-case array as one chunk with the sweep file's
filters, so those chunks are copied as compressed bytes: the workers do the
compression, in parallel, and the driver only moves bytes. Memory holds one
case and the coordinates, never the sweep.
"""

from __future__ import annotations

import datetime as _dt
import errno
import fcntl
import hashlib
import json
import os
import shutil
import sys
import uuid
from collections.abc import Callable, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import netCDF4
import numpy as np
import xarray as xr

from .dataset import replaced_on_success, write_netcdf_atomic

__all__ = ["StoreError", "PartStore", "SweepSlot", "canonical_json", "case_hash", "parts_dir_for",
           "write_part", "write_sweep_netcdf", "open_results", "history_line", "PART_SUFFIX", "LOG_NAME"]

PART_SUFFIX = ".nc"
LOG_NAME = "sweep.log"
LOCK_NAME = ".lock"
#: Hex digits of the SHA-256 kept in a part's name.
HASH_LENGTH = 16
#: Compression of numeric variables, in parts and in the assembled file.
COMPRESSION = {"zlib": True, "complevel": 1, "shuffle": True}
#: Statuses that do not count as failures.
NOT_FAILED = ("ok", "skipped")

#: Attributes of the two per-case string variables every sweep holds.
STATUS_ATTRS = {"long_name": "simulation status",
                "description": "ok, skipped, or the reason the case stopped"}
MESSAGE_ATTRS = {"long_name": "status message",
                 "description": "empty for a case that ran to the end; otherwise why it did not"}


class StoreError(RuntimeError):
    """A parts folder that cannot be used as asked (earlier parts, another sweep in it)."""


def canonical_json(cfg: Mapping) -> str:
    """Canonical JSON text of a resolved configuration (sorted keys, no spaces)."""
    return json.dumps(cfg, sort_keys=True, separators=(",", ":"), ensure_ascii=True)


def case_hash(cfg: Mapping) -> str:
    """Name of a case's part: the first 16 hex digits of the SHA-256 of :func:`canonical_json`."""
    return hashlib.sha256(canonical_json(cfg).encode("ascii")).hexdigest()[:HASH_LENGTH]


def parts_dir_for(out: str | os.PathLike) -> Path:
    """The parts folder of the sweep output ``out``: ``OUT.parts`` beside it."""
    out = Path(out)
    return out.with_name(out.name + ".parts")


def open_results(path: str | os.PathLike, **kwargs) -> xr.Dataset:
    """Open a sweep (or one-case) results file.

    Seconds stay floats (``decode_timedelta=False``: ``time`` and
    ``wall_time`` carry ``units: s``), and variable-length strings (material
    names, ``status``, ``message``) come back as strings; sweep coordinates
    keep their values, so ``ds.sel(B_coating="PTFE")`` works.

    Parameters
    ----------
    path
        netCDF file written by :func:`clearsweep.sweeps.run_sweep` or ``clearsweep run``.
    **kwargs
        Passed to :func:`xarray.open_dataset` (e.g. ``engine="h5netcdf"``, ``chunks={}``).

    Returns
    -------
    xr.Dataset
        Lazily loaded; close it (or use it as a context manager) when done.
    """
    kwargs.setdefault("decode_timedelta", False)
    return xr.open_dataset(path, **kwargs)


def _now() -> str:
    return _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")


def _encoding(ds: xr.Dataset) -> dict[str, dict]:
    """Every numeric array of a part compressed as one chunk, exactly as a case of the sweep file.

    Strings and scalars are stored as they are.
    """
    return {name: {**COMPRESSION, "chunksizes": var.shape} for name, var in ds.variables.items()
            if var.ndim and var.dtype.kind in "biuf" and all(var.shape)}


def write_part(directory: str | os.PathLike, h: str, part: xr.Dataset) -> Path:
    """Write the part of case ``h`` into ``directory`` atomically (temporary file, then rename).

    Used by :meth:`PartStore.write` and by pool workers, which write their
    cases themselves.
    """
    return write_netcdf_atomic(part, Path(directory) / f"{h}{PART_SUFFIX}", encoding=_encoding(part))


class PartStore:
    """The parts folder of one sweep: atomic parts, the event log and the lock.

    Parameters
    ----------
    directory
        The folder (``OUT.parts``); created by :meth:`open`.

    Examples
    --------
    >>> store = PartStore("results.nc.parts")           # doctest: +SKIP
    >>> finished = store.open(resume=True)               # hashes of earlier parts
    >>> store.write(h, part); store.close()
    """

    def __init__(self, directory: str | os.PathLike):
        self.directory = Path(directory)
        self.run_id = uuid.uuid4().hex[:12]
        self._lock_fd: int | None = None
        self._log = None

    # ------------------------------------------------------------------ life cycle
    def open(self, *, resume: bool = False, overwrite: bool = False) -> set[str]:
        """Take the folder for this sweep.

        Parameters
        ----------
        resume
            Keep the parts of an earlier run (they are not run again).
        overwrite
            Delete the parts and log of an earlier run.

        Returns
        -------
        set of str
            Hashes of the parts kept (empty unless ``resume``).

        Raises
        ------
        StoreError
            Another sweep holds the folder, or it holds parts and neither
            ``resume`` nor ``overwrite`` was given.
        """
        if resume and overwrite:
            raise StoreError("resume and overwrite exclude each other: resume keeps the finished "
                             "cases, overwrite deletes them")
        self.directory.mkdir(parents=True, exist_ok=True)
        fd = os.open(self.directory / LOCK_NAME, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as exc:
            os.close(fd)
            if exc.errno in (errno.EAGAIN, errno.EACCES, errno.EWOULDBLOCK):
                raise StoreError(f"{self.directory} is in use by another sweep; wait for it to "
                                 "finish or write to another output file") from None
            raise
        self._lock_fd = fd
        try:
            self._remove_temporaries()
            finished = self.finished()
            if finished and not resume:
                if not overwrite:
                    raise StoreError(
                        f"{self.directory} holds {len(finished)} finished case(s) of an earlier "
                        "sweep; pass --resume to continue that sweep (resume=True), or "
                        "--overwrite to delete them and start again (overwrite=True)")
                for h in finished:
                    self.path(h).unlink()
                (self.directory / LOG_NAME).unlink(missing_ok=True)
                finished = set()
        except BaseException:
            self.close()
            raise
        self._log = open(self.directory / LOG_NAME, "a", encoding="utf-8")
        return finished

    def close(self) -> None:
        """Close the log and release the lock (the parts stay)."""
        if self._log is not None:
            self._log.close()
            self._log = None
        if self._lock_fd is not None:
            os.close(self._lock_fd)
            self._lock_fd = None

    def remove(self) -> None:
        """Delete the folder with everything in it (after a successful assembly)."""
        self.close()
        shutil.rmtree(self.directory, ignore_errors=True)

    def __enter__(self) -> PartStore:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def _remove_temporaries(self) -> None:
        for tmp in self.directory.glob(".*.tmp"):
            tmp.unlink(missing_ok=True)

    # ------------------------------------------------------------------ parts
    def path(self, h: str) -> Path:
        """Path of the part of the case with hash ``h``."""
        return self.directory / f"{h}{PART_SUFFIX}"

    def finished(self) -> set[str]:
        """Hashes of the parts in the folder."""
        if not self.directory.is_dir():
            return set()
        return {p.name[: -len(PART_SUFFIX)] for p in self.directory.glob(f"*{PART_SUFFIX}")
                if not p.name.startswith(".")}

    def write(self, h: str, part: xr.Dataset) -> Path:
        """Write one finished case atomically (temporary file, then rename)."""
        return write_part(self.directory, h, part)

    def read(self, h: str) -> xr.Dataset:
        """The part of case ``h``, loaded into memory."""
        with open_results(self.path(h)) as ds:
            return ds.load()

    # ------------------------------------------------------------------ log
    def log(self, event: str, **fields) -> None:
        """Append one event to ``sweep.log`` (flushed at once)."""
        if self._log is None:
            raise StoreError(f"{self.directory} is not open")
        record = {"event": event, "time": _now(), "run": self.run_id, "pid": os.getpid(), **fields}
        self._log.write(json.dumps(record, sort_keys=True) + "\n")
        self._log.flush()

    def events(self, event: str | None = None) -> list[dict]:
        """The log's records (of one kind of event, if given), oldest first."""
        path = self.directory / LOG_NAME
        if not path.exists():
            return []
        out = []
        for line in path.read_text(encoding="utf-8").splitlines():
            try:
                record = json.loads(line)
            except json.JSONDecodeError:    # a line cut short by a kill
                continue
            if event is None or record.get("event") == event:
                out.append(record)
        return out


# ---------------------------------------------------------------------------- assembly

@dataclass(frozen=True)
class SweepSlot:
    """One point of the sweep grid, in sweep order.

    ``hash`` names its part; a skipped point has no part (``hash`` is
    ``None``) and is stored with ``status = "skipped"`` and ``message``.
    """

    hash: str | None
    message: str = ""


@dataclass
class _VarInfo:
    dims: tuple[str, ...]
    dtype: np.dtype
    attrs: dict
    is_coord: bool


@dataclass
class _Template:
    """What the parts hold: variables in first-seen order and each case dimension's coordinate."""

    variables: dict[str, _VarInfo] = field(default_factory=dict)
    dim_values: dict[str, np.ndarray] = field(default_factory=dict)
    dim_attrs: dict[str, dict] = field(default_factory=dict)
    dim_sizes: dict[str, int] = field(default_factory=dict)
    statuses: dict[str, str] = field(default_factory=dict)


# Parts are read through netCDF4 without xarray: the writer needs the raw arrays (and the
# chunk layout), and xarray's decoding per part costs more than the copy. The decoding that
# write_part's output needs is small: strings, booleans (int8 + dtype="bool"), coordinates.
_HIDDEN_ATTRS = ("_FillValue", "coordinates", "dtype")


@contextmanager
def _open_part(path: Path):
    with netCDF4.Dataset(path) as nc:
        nc.set_auto_maskandscale(False)
        yield nc


def _is_text(dtype: np.dtype) -> bool:
    return dtype.kind in "OUS"


def _dtype(var) -> np.dtype:
    """The dtype xarray would give a part's variable: object for strings, bool where marked."""
    if var.dtype is str:
        return np.dtype(object)
    if "dtype" in var.ncattrs() and var.getncattr("dtype") == "bool":
        return np.dtype(bool)
    return np.dtype(var.dtype)


def _values(var) -> np.ndarray:
    values = var[...]
    return np.asarray(values, dtype=object) if var.dtype is str else np.asarray(values)


def _attrs(var) -> dict:
    return {k: var.getncattr(k) for k in var.ncattrs() if k not in _HIDDEN_ATTRS}


def _coord_names(nc) -> set[str]:
    names = set(str(getattr(nc, "coordinates", "")).split())
    for var in nc.variables.values():
        if "coordinates" in var.ncattrs():
            names.update(str(var.getncattr("coordinates")).split())
    return names


def _union(old: np.ndarray | None, new: np.ndarray) -> np.ndarray:
    """Outer join of two coordinates: numbers sorted, labels in order of first appearance."""
    if old is None or old.shape == new.shape and np.array_equal(old, new):
        return new if old is None else old
    if old.dtype.kind in "iuf" and new.dtype.kind in "iuf":
        return np.union1d(old, new)
    seen = dict.fromkeys(old.tolist())
    seen.update(dict.fromkeys(new.tolist()))
    return np.array(list(seen), dtype=object if _is_text(old.dtype) else None)


def _scan(slots: Sequence[SweepSlot], store: PartStore) -> _Template:
    """First pass: variables, dtypes, attributes and case coordinates of every part (no data)."""
    tpl = _Template()
    for h in dict.fromkeys(s.hash for s in slots if s.hash is not None):
        if not store.path(h).exists():
            raise StoreError(f"case {h} has no part in {store.directory}; run the sweep with "
                             "--resume to compute it")
        with _open_part(store.path(h)) as nc:
            tpl.statuses[h] = str(_values(nc["status"]).ravel()[0])
            for dim, d in nc.dimensions.items():
                if dim in nc.variables:
                    tpl.dim_values[dim] = _union(tpl.dim_values.get(dim), _values(nc[dim]))
                    tpl.dim_attrs.setdefault(dim, _attrs(nc[dim]))
                else:
                    tpl.dim_sizes[dim] = max(tpl.dim_sizes.get(dim, 0), d.size)
            coords = _coord_names(nc)
            for name, var in nc.variables.items():
                if name in nc.dimensions:
                    continue
                info = tpl.variables.get(name)
                if info is None:
                    tpl.variables[name] = _VarInfo(var.dimensions, _dtype(var), _attrs(var),
                                                   name in coords)
                    continue
                if info.dims != var.dimensions:
                    raise StoreError(f"variable {name} has dims {var.dimensions} in part {h} but "
                                     f"{info.dims} in an earlier part")
                if not (_is_text(info.dtype) and _is_text(_dtype(var))):
                    info.dtype = np.result_type(info.dtype, _dtype(var))
    for dim, values in tpl.dim_values.items():
        tpl.dim_sizes[dim] = len(values)
    return tpl


def _nc_type(dtype: np.dtype):
    """netCDF type of a numpy dtype: variable-length strings for text, int8 for booleans."""
    if _is_text(dtype):
        return str
    return np.dtype("i1") if dtype.kind == "b" else dtype


def _fill_value(dtype: np.dtype):
    if dtype.kind == "f":
        return np.nan
    if dtype.kind == "b":
        return -1
    return netCDF4.default_fillvals[f"{dtype.kind}{dtype.itemsize}"]


def _write_values(var, index: tuple, values, text: bool) -> None:
    if text:
        values = np.asarray(values, dtype=object)
        if values.ndim == 0:
            values = str(values[()])
    var[index if var.ndim else ...] = values


def _create_variable(nc, name: str, dims: tuple[str, ...], dtype: np.dtype, attrs: Mapping,
                     chunks: tuple[int, ...] | None):
    """A netCDF variable, compressed and chunked when numeric and not scalar."""
    nctype = _nc_type(dtype)
    kwargs = {}
    if nctype is not str:
        kwargs["fill_value"] = _fill_value(dtype)
        if dims and chunks and all(chunks):
            kwargs.update(COMPRESSION, chunksizes=chunks)
    var = nc.createVariable(name, nctype, dims, **kwargs)
    if kwargs.get("chunksizes"):
        # One chunk of cache: every write fills whole chunks, no need to keep them around.
        nbytes = int(np.prod(chunks)) * np.dtype(nctype).itemsize
        var.set_var_chunk_cache(size=max(nbytes, 1 << 16), nelems=1, preemption=1.0)
    clean = {k: v for k, v in attrs.items() if isinstance(v, (str, int, float, np.generic, list))
             and k not in _HIDDEN_ATTRS}
    if dtype.kind == "b":
        clean.setdefault("flag_values", [0, 1])
        clean.setdefault("flag_meanings", "false true")
    var.setncatts(clean)
    return var


def _positions(part_values: np.ndarray, union: np.ndarray) -> np.ndarray:
    lookup = {v: i for i, v in enumerate(union.tolist())}
    return np.array([lookup[v] for v in part_values.tolist()], dtype=np.intp)


def _case_index(coords: Mapping[str, np.ndarray], dims: tuple[str, ...], sizes: tuple[int, ...],
                tpl: _Template):
    """Per case dimension: where the part's values go in the union, and their reordering."""
    index, order = [], []
    for dim, n in zip(dims, sizes):
        if dim not in tpl.dim_values or np.array_equal(coords[dim], tpl.dim_values[dim]):
            index.append(slice(0, n))
            order.append(None)
            continue
        pos = _positions(coords[dim], tpl.dim_values[dim])
        perm = np.argsort(pos, kind="stable")
        pos = pos[perm]
        if n and pos[-1] - pos[0] + 1 == n:
            index.append(slice(int(pos[0]), int(pos[-1]) + 1))
        else:
            index.append(pos)
        order.append(perm)
    return tuple(index), order


def _define(nc, sweep_dims: Mapping[str, int], sweep_coords: Mapping, tpl: _Template,
            attrs: Mapping) -> dict:
    """Create the dimensions, coordinates and (empty) variables of the sweep file."""
    for dim, size in {**sweep_dims, **tpl.dim_sizes}.items():
        nc.createDimension(dim, size)
    coord_names = []
    for name, (dim, values, cattrs) in sweep_coords.items():
        values, cattrs = np.asarray(values), dict(cattrs)
        if values.dtype.kind == "b":        # as xarray stores booleans
            values, cattrs["dtype"] = values.astype("i1"), "bool"
        var = nc.createVariable(name, _nc_type(values.dtype), (dim,))
        var.setncatts(cattrs)
        _write_values(var, slice(None), values, _is_text(values.dtype))
        if name != dim:
            coord_names.append(name)
    for dim, values in tpl.dim_values.items():
        var = _create_variable(nc, dim, (dim,), values.dtype, tpl.dim_attrs[dim], None)
        _write_values(var, slice(None), values, _is_text(values.dtype))
    sdims = tuple(sweep_dims)
    variables = {name: _create_variable(nc, name, sdims, np.dtype(object), text_attrs, None)
                 for name, text_attrs in (("status", STATUS_ATTRS), ("message", MESSAGE_ATTRS))}
    for name, info in tpl.variables.items():
        if name in variables:
            continue
        chunks = (1,) * len(sdims) + tuple(tpl.dim_sizes[d] for d in info.dims)
        variables[name] = _create_variable(nc, name, sdims + info.dims, info.dtype, info.attrs,
                                           chunks)
        if info.is_coord:
            coord_names.append(name)
    if coord_names:
        attrs = {**attrs, "coordinates": " ".join(coord_names)}
    nc.setncatts(dict(attrs))
    return variables


def _byte_order(var) -> str:
    order = var.endian()
    return sys.byteorder if order == "native" else order


def _chunk_copyable(src, dst, index: tuple, order: list) -> bool:
    """Whether ``src`` (a part's variable) is one chunk encoded exactly as ``dst``'s chunks.

    Then its compressed bytes can be copied as they are (:func:`_copy_chunks`).
    """
    shape = tuple(src.shape)
    return (bool(shape) and src.dtype is not str and src.dtype == dst.dtype
            and _byte_order(src) == _byte_order(dst) and src.chunking() == list(shape)
            and tuple(dst.chunking()[-len(shape):]) == shape
            and all(c == 1 for c in dst.chunking()[:-len(shape)])
            and all(o is None for o in order)
            and all(isinstance(i, slice) and i.start == 0 for i in index)
            and src.filters() == dst.filters())


def _copy_case(nc_part, where: tuple[int, ...], variables: Mapping, tpl: _Template) -> list[str]:
    """Write one part's variables into its slice; return those left for :func:`_copy_chunks`."""
    coords = {d: _values(nc_part[d]) for d in nc_part.dimensions if d in nc_part.variables}
    raw = []
    for name, var in nc_part.variables.items():
        if name in nc_part.dimensions:
            continue
        dst = variables[name]
        index, order = _case_index(coords, var.dimensions, var.shape, tpl)
        if _chunk_copyable(var, dst, index, order):
            raw.append(name)
            continue
        values = _values(var)
        for axis, perm in enumerate(order):
            if perm is not None:
                values = np.take(values, perm, axis=axis)
        _write_values(dst, where + index, values, var.dtype is str)
    return raw


def _filters(dataset) -> list[tuple]:
    plist = dataset.id.get_create_plist()
    return [plist.get_filter(i)[:3:2] for i in range(plist.get_nfilters())]


def _copy_chunks(path: Path, raw: Sequence[tuple[tuple[int, ...], Path, list[str]]],
                 check: Callable[[], None] | None) -> None:
    """Second pass: copy the compressed chunks of whole-case variables without re-encoding.

    Parts and the sweep file use the same chunk layout (one case) and the
    same filters, so each chunk is read and written as bytes: the driver
    neither inflates nor deflates the bulk of the data.
    """
    import h5py

    with h5py.File(path, "r+") as out:
        pipelines: dict[str, list] = {}
        for where, part, names in raw:
            if check is not None:
                check()
            with h5py.File(part, "r") as src:
                for name in names:
                    s, d = src[name], out[name]
                    if _filters(s) != pipelines.setdefault(name, _filters(d)):
                        raise StoreError(f"{part}: {name} is encoded unlike the sweep file")
                    mask, chunk = s.id.read_direct_chunk((0,) * s.ndim)
                    d.id.write_direct_chunk(where + (0,) * s.ndim, chunk, mask)


def write_sweep_netcdf(path: str | os.PathLike, *, sweep_dims: Mapping[str, int],
                       sweep_coords: Mapping[str, tuple[str, np.ndarray, Mapping]],
                       slots: Sequence[SweepSlot], store: PartStore,
                       attrs: Mapping | None = None,
                       check: Callable[[], None] | None = None) -> dict[str, int]:
    """Assemble the parts into one netCDF4 file, one case at a time, and rename it into place.

    Parameters
    ----------
    path
        The final file; it appears only once complete.
    sweep_dims
        Sweep dimensions and their sizes, in order; ``slots`` is their C-order product.
    sweep_coords
        ``name -> (dim, values, attrs)``; a coordinate named like its dim is
        the index (``B_coating``), the others are non-index coordinates
        (the keys of a zip group).
    slots
        One :class:`SweepSlot` per sweep point, in C order over ``sweep_dims``.
    store
        The parts.
    attrs
        Global attributes.
    check
        Called before each case is copied; may raise (``KeyboardInterrupt``)
        to stop, leaving no file.

    Returns
    -------
    dict
        ``{"cases": n, "failed": n, "skipped": n}``, also written as the
        global attributes ``sweep_cases``, ``sweep_failed`` and ``sweep_skipped``.

    Notes
    -----
    Variables keep the parts' dims after the sweep dims, with chunks of one
    case and zlib compression; case coordinates that differ between parts
    (e.g. a swept duration) are outer-joined and the missing values filled
    (NaN for floats). Cases without a variable (failed or skipped ones) read
    as fill values.

    Three passes over the parts, each holding one case at most: the headers
    (variables, dtypes, case coordinates), then netCDF4 writes of everything
    but whole-case arrays stored as one chunk, then an h5py copy of those
    arrays' compressed chunks as bytes (:func:`_copy_chunks`).
    """
    shape = tuple(sweep_dims.values())
    if int(np.prod(shape)) != len(slots):
        raise ValueError(f"{len(slots)} slots for a sweep of shape {shape}")
    tpl = _scan(slots, store)
    counts = {"cases": len(slots),
              "failed": sum(1 for s in slots if s.hash is not None
                            and tpl.statuses[s.hash] not in NOT_FAILED),
              "skipped": sum(1 for s in slots if s.hash is None)}
    attrs = {**(attrs or {}), **{f"sweep_{k}": v for k, v in counts.items()}}
    raw = []
    with replaced_on_success(path) as tmp:
        with netCDF4.Dataset(tmp, "w", format="NETCDF4") as nc:
            variables = _define(nc, sweep_dims, sweep_coords, tpl, attrs)
            for i, slot in enumerate(slots):
                if check is not None:
                    check()
                where = tuple(int(k) for k in np.unravel_index(i, shape)) if shape else ()
                if slot.hash is None:
                    _write_values(variables["status"], where, "skipped", True)
                    _write_values(variables["message"], where, slot.message, True)
                    continue
                with _open_part(store.path(slot.hash)) as part:
                    names = _copy_case(part, where, variables, tpl)
                if names:
                    raw.append((where, store.path(slot.hash), names))
        _copy_chunks(Path(tmp), raw, check)
    return counts


def history_line(text: str) -> str:
    """A CF ``history`` line: UTC time stamp and ``text``."""
    return f"{_now()}: {text}"

