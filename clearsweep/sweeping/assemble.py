"""Parts -> one labelled sweep netCDF, case by case, in bounded memory.

:func:`write_sweep_netcdf` assembles the parts into the final file one case
at a time: it creates the netCDF4 file with every variable chunked one case
per chunk, copies each part into its slice, and renames the file into place.
A part stores each whole-case array as one chunk with the sweep file's
filters, so those chunks are copied as compressed bytes: the workers do the
compression, in parallel, and the driver only moves bytes. Memory holds one
case, the coordinates and, within a budget, the small values, never the sweep's arrays.
"""

from __future__ import annotations

import contextlib
import json
import os
import sys
from collections.abc import Callable, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import netCDF4
import numpy as np

from ..dataset import replaced_on_success, write_errors_as_oserror
from .parts import (
    COMPRESSION,
    IDENTITY_ATTR,
    KEY_ATTR,
    MESSAGE_ATTRS,
    NOT_FAILED,
    STATUS_ATTRS,
    DamagedPart,
    PartStore,
    StoreError,
)


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


#: Bytes of part values the scan keeps for the copy pass, in all: parts beyond it are
#: opened a second time, so that memory stays bounded whatever the sweep's size.
SCAN_CACHE_BYTES = 64 << 20


class _VariableCopy:
    """What the copy pass reads of a part's variable (:func:`_copy_case`), taken by the scan
    while the part is open: its layout and, unless its chunk is copied as bytes, its values."""

    def __init__(self, var, values: np.ndarray | None):
        self.dimensions, self.shape, self.dtype = var.dimensions, var.shape, var.dtype
        self._endian, self._chunking, self._filters = var.endian(), var.chunking(), var.filters()
        self._values = values

    def endian(self) -> str:
        return self._endian

    def chunking(self):
        return self._chunking

    def filters(self):
        return self._filters

    def __getitem__(self, key) -> np.ndarray:
        if self._values is None:
            raise _NeedsFile
        return self._values


class _NeedsFile(Exception):
    """A variable's values were not kept by the scan: the copy pass opens the part."""


class _PartCopy:
    """A part as :func:`_copy_case` reads it, from the scan (the part is not opened again)."""

    def __init__(self, nc):
        # the values of everything but whole-case chunks, and of the case coordinates
        self.dimensions = dict.fromkeys(nc.dimensions)
        self.variables = {name: _VariableCopy(var, _values(var) if name in nc.dimensions
                                              or not _whole_chunk(var) else None)
                          for name, var in nc.variables.items()}

    def __getitem__(self, name: str) -> _VariableCopy:
        return self.variables[name]

    @property
    def nbytes(self) -> int:
        return sum(v._values.nbytes for v in self.variables.values() if v._values is not None)


def _whole_chunk(var) -> bool:
    """Whether a part's variable is one compressed chunk (copied as bytes if the sweep file's
    layout matches, :func:`_chunk_copyable`)."""
    return bool(var.shape) and var.dtype is not str and var.chunking() == list(var.shape)


@dataclass
class _Template:
    """What the parts hold: variables in first-seen order and each case dimension's coordinate."""

    variables: dict[str, _VarInfo] = field(default_factory=dict)
    dim_values: dict[str, np.ndarray] = field(default_factory=dict)
    dim_attrs: dict[str, dict] = field(default_factory=dict)
    dim_sizes: dict[str, int] = field(default_factory=dict)
    statuses: dict[str, str] = field(default_factory=dict)
    #: Part key -> its per-joint global attributes (``joint_*``, :data:`JOINT_ATTR_PREFIX`).
    joint_attrs: dict[str, dict] = field(default_factory=dict)
    #: Part key -> what the copy pass needs of it, read by the scan (:class:`_PartCopy`);
    #: a part missing here is opened again.
    copies: dict[str, _PartCopy] = field(default_factory=dict)


# Parts are read through netCDF4 without xarray: the writer needs the raw arrays (and the
# chunk layout), and xarray's decoding per part costs more than the copy. The decoding that
# write_part's output needs is small: strings, booleans (int8 + dtype="bool"), coordinates.
_HIDDEN_ATTRS = ("_FillValue", "coordinates", "dtype")


@contextmanager
def _open_part(path: Path):
    try:
        nc = netCDF4.Dataset(path)
    except (OSError, RuntimeError) as exc:      # truncated or not netCDF: name the part
        raise DamagedPart(path, getattr(exc, "strerror", None) or str(exc)) from None
    with nc:
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


def _made_for(nc) -> str:
    """The ``store`` the part ``nc`` records it was made for (``"none recorded"`` for a part
    of an older clearsweep)."""
    try:
        made = json.loads(getattr(nc, IDENTITY_ATTR, "null") or "null")
    except (TypeError, json.JSONDecodeError):
        made = None
    store = made.get("store") if isinstance(made, dict) else None
    return store if isinstance(store, str) else "none recorded"


def _scan(slots: Sequence[SweepSlot], store: PartStore, holds: str | None = None) -> _Template:
    """First pass: variables, dtypes, attributes and case coordinates of every part, and
    what the copy pass needs of each (:class:`_PartCopy`: all but the whole-case chunks),
    within :data:`SCAN_CACHE_BYTES`."""
    tpl = _Template()
    budget = SCAN_CACHE_BYTES
    for h in dict.fromkeys(s.hash for s in slots if s.hash is not None):
        if not store.path(h).exists():
            raise StoreError(f"case {h} has no part in {store.directory}; run the sweep with "
                             "--resume to compute it")
        with _open_part(store.path(h)) as nc:
            key = getattr(nc, KEY_ATTR, None)
            if key != h:
                raise StoreError(f"{store.path(h)} holds " + (f"the case {key}" if key else
                                 "no case key") + f", not the case {h} it is filed under "
                                 "(renamed or swapped); run the sweep again with --resume, "
                                 "which computes that case again")
            if holds is not None and (made := _made_for(nc)) != holds:
                raise StoreError(f"{store.path(h)} was made for store: {made}, not for this "
                                 f"sweep's store: {holds}; resume that sweep with its own store, "
                                 "or run this one with --overwrite")
            tpl.statuses[h] = str(_values(nc["status"]).ravel()[0])
            tpl.joint_attrs[h] = {k: nc.getncattr(k) for k in nc.ncattrs()
                                  if k.startswith(JOINT_ATTR_PREFIX)}
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
            if budget > 0:
                copy = _PartCopy(nc)
                budget -= copy.nbytes
                if budget >= 0:
                    tpl.copies[h] = copy
    for dim, values in tpl.dim_values.items():
        tpl.dim_sizes[dim] = len(values)
    return tpl


#: The prefix of a case's per-joint global attributes (``clearsweep.params.joint_attributes``).
JOINT_ATTR_PREFIX = "joint_"

#: Units of a per-joint attribute, by the suffix of its name.
_JOINT_UNITS = {"_Pa": "Pa", "_m": "m", "_m2_per_N": "m2 N-1"}


def _same(a, b) -> bool:
    """Whether two attribute values are equal (NaN equals NaN)."""
    if isinstance(a, str) or isinstance(b, str):
        return isinstance(a, str) and isinstance(b, str) and a == b
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and bool(np.all((a == b) | (np.isnan(a) & np.isnan(b))))


def _joint_attrs(tpl: _Template) -> tuple[dict, dict[str, np.dtype]]:
    """The parts' per-joint attributes split in two: those every part that has them agrees
    on (global attributes of the sweep file) and those that vary from case to case (each a
    variable over the sweep dims: its dtype)."""
    constant: dict = {}
    varying: dict[str, np.dtype] = {}
    for values in tpl.joint_attrs.values():
        for name, value in values.items():
            if name in varying:
                continue
            if name not in constant:
                constant[name] = value
            elif not _same(constant[name], value):
                del constant[name]
                varying[name] = np.dtype(object) if isinstance(value, str) else np.dtype(float)
    return constant, varying


def _joint_attr_variable_attrs(name: str) -> dict:
    out = {"long_name": f"{name} of each case (a per-joint attribute that varies across the sweep)"}
    unit = next((u for suffix, u in _JOINT_UNITS.items() if name.endswith(suffix)), None)
    if unit is not None:
        out["units"] = unit
    return out


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


def _write_values(var, index: tuple | slice, values, text: bool) -> None:
    if text:
        values = np.asarray(values, dtype=object)
        if values.ndim == 0:
            values = str(values[()])
    var[index if var.ndim else ...] = values


def _create_variable(nc, name: str, dims: tuple[str, ...], dtype: np.dtype, attrs: Mapping,
                     chunks: tuple[int, ...] | None, coordinate: bool = False):
    """A netCDF variable, compressed and chunked when numeric and not scalar; a
    ``coordinate`` gets no ``_FillValue``."""
    nctype = _nc_type(dtype)
    kwargs: dict[str, Any] = {}
    if nctype is not str and not coordinate:    # a coordinate has no missing values
        kwargs["fill_value"] = _fill_value(dtype)
        if dims and chunks and all(chunks):
            kwargs.update(COMPRESSION, chunksizes=chunks)
    var = nc.createVariable(name, nctype, dims, **kwargs)
    if kwargs.get("chunksizes"):
        # One chunk of cache: every write fills whole chunks, no need to keep them around.
        nbytes = int(np.prod(kwargs["chunksizes"])) * np.dtype(nctype).itemsize
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
    index: list = []
    order: list = []
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
        var = _create_variable(nc, dim, (dim,), values.dtype, tpl.dim_attrs[dim], None, coordinate=True)
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


class _Writes:
    """The sweep file's values written case by case (everything but the whole-case chunks
    copied as bytes), kept in memory and written once per variable by :meth:`flush`: a
    netCDF4 write per variable and case was most of a small case's assembly. Within
    :data:`SCAN_CACHE_BYTES`; past it, or for a case whose coordinates are placed by
    position (outer-joined case coordinates), what is kept is written and the rest is
    written case by case. Entries no case writes hold the variable's fill value (what the
    file reads there either way)."""

    def __init__(self, variables: Mapping, budget: int | None = None):
        self.variables = variables
        self.budget = SCAN_CACHE_BYTES if budget is None else budget
        self.arrays: dict[str, np.ndarray] = {}
        self.kept = True

    def write(self, name: str, index: tuple, values, text: bool) -> None:
        if self.kept and not all(isinstance(i, int | slice) for i in index):
            self.flush()
        array = self.arrays.get(name) if self.kept else None
        if array is None and self.kept:
            array = self._array(name)
        if array is None:
            _write_values(self.variables[name], index, values, text)
            return
        if text:
            values = np.asarray(values, dtype=object)
            if values.ndim == 0:
                values = str(values[()])
        array[index] = values

    def _array(self, name: str) -> np.ndarray | None:
        var = self.variables[name]
        text = var.dtype is str
        dtype = np.dtype(object) if text else np.dtype(var.dtype)
        nbytes = int(np.prod(var.shape)) * (64 if text else dtype.itemsize)
        if nbytes > self.budget:
            self.flush()
            return None
        self.budget -= nbytes
        fill: Any
        if text:
            fill = ""
        elif "_FillValue" in var.ncattrs():
            fill = var.getncattr("_FillValue")
        else:
            fill = netCDF4.default_fillvals[f"{dtype.kind}{dtype.itemsize}"]
        array = np.full(var.shape, fill, dtype=dtype)
        self.arrays[name] = array
        return array

    def flush(self) -> None:
        """Write what is kept; from here on every value is written at once."""
        for name, array in self.arrays.items():
            var = self.variables[name]
            _write_values(var, slice(None), array, var.dtype is str)
        self.arrays.clear()
        self.kept = False


def _copy_case(nc_part, where: tuple[int, ...], variables: Mapping, tpl: _Template,
               writes: _Writes | None = None) -> list[str]:
    """Write one part's variables into its slice (through ``writes``, where given); return
    those left for :func:`_copy_chunks`."""
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
        if writes is None:
            _write_values(dst, where + index, values, var.dtype is str)
        else:
            writes.write(name, where + index, values, var.dtype is str)
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
                       check: Callable[[], None] | None = None,
                       finish: Callable[[Path], None] | None = None,
                       holds: str | None = None) -> dict[str, int]:
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
    finish
        Called with the complete temporary file before it is renamed into
        place, to add variables computed from it (the ensemble statistics).
    holds
        The sweep's ``store``: every part must record that it was made for it (its
        identity, :func:`clearsweep.sweeping.parts.part_identity`), or nothing is written.

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

    A case's per-joint global attributes (``joint_*``: type, materials, the contact values
    the kernel ran with) that every part agrees on become global attributes of the sweep
    file; those that differ between cases become variables of the same name over the sweep
    dims (fill values where a case has none: a failed or skipped one).

    Three passes over the parts: the headers (variables, dtypes, case coordinates) and
    every value but the whole-case arrays stored as one chunk (kept up to
    :data:`SCAN_CACHE_BYTES`, so that a part is opened once), then netCDF4 writes of those
    values (one per variable for as many as :data:`SCAN_CACHE_BYTES` hold, :class:`_Writes`),
    then an h5py copy of the whole-case arrays' compressed chunks as bytes
    (:func:`_copy_chunks`). Memory holds one case, the coordinates and at most twice
    :data:`SCAN_CACHE_BYTES` of small values.
    """
    shape = tuple(sweep_dims.values())
    if int(np.prod(shape)) != len(slots):
        raise ValueError(f"{len(slots)} slots for a sweep of shape {shape}")
    tpl = _scan(slots, store, holds)
    counts = {"cases": len(slots),
              "failed": sum(1 for s in slots if s.hash is not None
                            and tpl.statuses[s.hash] not in NOT_FAILED),
              "skipped": sum(1 for s in slots if s.hash is None)}
    constant, varying = _joint_attrs(tpl)
    attrs = {**(attrs or {}), **constant, **{f"sweep_{k}": v for k, v in counts.items()}}
    for name, dtype in varying.items():
        tpl.variables[name] = _VarInfo((), dtype, _joint_attr_variable_attrs(name), False)
    raw = []
    with write_errors_as_oserror(path), replaced_on_success(path) as tmp:
        with netCDF4.Dataset(tmp, "w", format="NETCDF4") as nc:
            variables = _define(nc, sweep_dims, sweep_coords, tpl, attrs)
            writes = _Writes(variables)
            for i, slot in enumerate(slots):
                if check is not None:
                    check()
                where = tuple(int(k) for k in np.unravel_index(i, shape)) if shape else ()
                if slot.hash is None:
                    writes.write("status", where, "skipped", True)
                    writes.write("message", where, slot.message, True)
                    continue
                names = None
                if slot.hash in tpl.copies:
                    with contextlib.suppress(_NeedsFile):
                        names = _copy_case(tpl.copies[slot.hash], where, variables, tpl, writes)
                if names is None:
                    with _open_part(store.path(slot.hash)) as part:
                        names = _copy_case(part, where, variables, tpl, writes)
                if names:
                    raw.append((where, store.path(slot.hash), names))
                for name in varying:
                    value = tpl.joint_attrs[slot.hash].get(name)
                    if value is not None:
                        writes.write(name, where, value, isinstance(value, str))
            writes.flush()
        _copy_chunks(Path(tmp), raw, check)
        if finish is not None:
            finish(Path(tmp))
    return counts


