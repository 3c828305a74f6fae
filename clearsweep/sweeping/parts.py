"""One finished case per part file; the resume ledger and its lock.

A sweep writing ``OUT.nc`` keeps its finished cases in the folder
``OUT.nc.parts/`` (:func:`parts_dir_for`):

- ``<key>.nc``: one finished case, named by its case key (:func:`case_key`: the
  hash of everything that decides its results, :func:`clearsweep.params.run_identity`:
  the resolved config, the materials values it reads and the clearsweep version),
  written (with netCDF4 alone, the file ``xarray.Dataset.to_netcdf`` would write:
  :func:`write_part`) to a temporary file in the same folder and renamed into place
  (:func:`clearsweep.dataset.replaced_on_success`), so a part that is visible is
  complete. Each part carries its own key and identity as global attributes
  (:data:`KEY_ATTR`, :data:`IDENTITY_ATTR`): the mark that clearsweep wrote it, and
  the proof that it belongs to the case it is filed under. A killed sweep leaves at
  most a temporary ``.<key>.nc.PID.XXXX.tmp`` file, which the next run removes.
- ``sweep.log``: the folder's ledger, one JSON line per event (``run``, ``done``,
  ``interrupted``, ``assembled``), appended by the driver; ``done`` lines carry the
  case key, the part's content hash (SHA-256), its status and the run id, so a log tells
  which run computed which case.
- ``.lock``: holding ``dataset.LOCK_MARK``, an exclusive ``flock`` held while a sweep uses
  the folder, so
  two sweeps cannot write the same parts; the kernel drops it when the
  process ends, however it ends.

clearsweep deletes only these files, and only its own: a part is its own when it
carries the mark or a ledger line names it with its content hash; a temporary when it
begins as a netCDF4 file; a lock when it holds the lock's mark. A folder that holds anything else (a file the
user put there, a part of another tool) is refused in one line, whatever the options,
and after a sweep is written the folder is removed only if nothing else is in it.
"""

from __future__ import annotations

import datetime as _dt
import functools
import hashlib
import json
import os
import re
import uuid
import warnings
from collections.abc import Callable, Collection, Mapping
from pathlib import Path
from typing import Any, TextIO

import xarray as xr
from xarray.backends.locks import NETCDFC_LOCK

from ..config import Config
from ..dataset import (
    ForeignLock,
    holds_lock_mark,
    lock_exclusively,
    open_results,
    replaced_on_success,
    write_errors_as_oserror,
    write_netcdf_atomic,
)
from ..params import identity_changes, identity_differences, run_identity
from ..schema import ClearsweepWarning

PART_SUFFIX = ".nc"
LOG_NAME = "sweep.log"
LOCK_NAME = ".lock"
#: Hex digits of the SHA-256 kept in a part's name.
HASH_LENGTH = 16
#: Global attribute of every part: the case key it was written for (the mark of a part
#: clearsweep wrote, and what the part's name must be).
KEY_ATTR = "clearsweep_case_key"
#: Global attribute of a part: the canonical JSON of its case's identity
#: (:func:`clearsweep.params.run_identity`), to say what changed when it is refused.
IDENTITY_ATTR = "clearsweep_case_identity"
#: The temporary file of a part being written (``replaced_on_success``'s naming,
#: ``.KEY.nc.PID.XXXX.tmp``, KEY a case key); it is clearsweep's only when it also begins as
#: the netCDF4 (HDF5) file it writes does (:data:`_HDF5_SIGNATURE`, :func:`_is_temporary`).
_TEMPORARY = re.compile(r"\.[0-9a-f]{%d}\.nc\.[0-9]+\.[A-Za-z0-9_]+\.tmp" % HASH_LENGTH)
#: The first bytes netCDF4 writes in a new file (HDF5's superblock signature).
_HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"

#: Held while this process writes a part with netCDF4 (:func:`_write_plain`): xarray's own
#: lock of the netCDF-C library, which its reads and writes in this process take too.
_NETCDF_LOCK = NETCDFC_LOCK


def _is_temporary(path: Path) -> bool:
    """Whether ``path`` is a part's temporary file that clearsweep wrote: named as
    :data:`_TEMPORARY`, a plain file that begins with :data:`_HDF5_SIGNATURE`. A user's file
    named alike (``.thesis.nc.v2.tmp``) was deleted before (issue 40, item 3)."""
    if not _TEMPORARY.fullmatch(path.name) or path.is_symlink() or not path.is_file():
        return False
    try:
        with open(path, "rb") as f:
            return f.read(len(_HDF5_SIGNATURE)) == _HDF5_SIGNATURE
    except OSError:
        return False


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


class DamagedPart(StoreError):
    """A finished case's part that cannot be read (truncated, or overwritten by hand): the
    message names it and what to do; before, it read as a failed write with a full-disk
    remedy, and --resume failed the same way every time."""

    def __init__(self, path: str | os.PathLike, reason: str):
        self.path = Path(path)
        super().__init__(f"the finished part {self.path} cannot be read ({reason}): delete it "
                         "and run the same command again with --resume (its case runs again, "
                         "the other finished cases are kept)")


def canonical_json(cfg: Mapping) -> str:
    """Canonical JSON text of a resolved configuration (sorted keys, no spaces)."""
    return json.dumps(cfg, sort_keys=True, separators=(",", ":"), ensure_ascii=True)


def case_hash(cfg: Mapping) -> str:
    """Name of a case's part: the first 16 hex digits of the SHA-256 of :func:`canonical_json`."""
    return hashlib.sha256(canonical_json(cfg).encode("ascii")).hexdigest()[:HASH_LENGTH]


def part_identity(cfg: Config, store: str) -> dict[str, Any]:
    """The identity of a sweep case's part: :func:`clearsweep.params.run_identity` of its
    config and the sweep's ``store`` (what the part holds: a part of one store is never
    resumed or assembled as another's, issue 40)."""
    return {**run_identity(cfg), "store": store}


def case_key(cfg: Config, store: str) -> str:
    """The key of a case's part: :func:`case_hash` of its identity and the sweep's store
    (:func:`clearsweep.params.run_identity`: resolved config without the materials file's
    path, the materials values it reads, the clearsweep version). Editing the materials
    file, or another version, gives other keys: earlier parts are then not this run's."""
    return case_hash(part_identity(cfg, store))


def parts_dir_for(out: str | os.PathLike) -> Path:
    """The parts folder of the sweep output ``out``: ``OUT.parts`` beside it."""
    out = Path(out)
    return out.with_name(out.name + ".parts")


def _now() -> str:
    return _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")


#: Arrays of a part smaller than this [bytes] are stored contiguous and uncompressed: a
#: chunked, compressed HDF5 dataset costs more to write and to copy than its few values
#: (benchmarks/README.md, "Part files"); assembly compresses them into the sweep file.
SMALL_ARRAY_BYTES = 16 * 1024


def _encoding(ds: xr.Dataset) -> dict[str, dict]:
    """Every numeric array of a part of at least :data:`SMALL_ARRAY_BYTES` compressed as one
    chunk, exactly as a case of the sweep file (assembly copies it as compressed bytes).

    Strings, scalars and small arrays are stored as they are.
    """
    return {str(name): {**COMPRESSION, "chunksizes": var.shape} for name, var in ds.variables.items()
            if var.ndim and var.dtype.kind in "biuf" and all(var.shape)
            and var.nbytes >= SMALL_ARRAY_BYTES}


def with_identity(part: xr.Dataset, identity: Mapping[str, Any]) -> xr.Dataset:
    """``part`` carrying its case's ``identity`` (:func:`clearsweep.params.run_identity`) as
    the attribute :data:`IDENTITY_ATTR`, which :func:`write_part` keeps."""
    return part.assign_attrs({IDENTITY_ATTR: canonical_json(identity)})


def write_part(directory: str | os.PathLike, h: str, part: xr.Dataset) -> Path:
    """Write the part of case ``h`` into ``directory`` atomically (temporary file, then rename),
    marked with its key ``h`` (:data:`KEY_ATTR`).

    Used by :meth:`PartStore.write` and by pool workers, which write their
    cases themselves. Threads of one process (a caller's ``ThreadPoolExecutor``, a Dask
    worker of several threads) write one part at a time: the netCDF and HDF5 libraries
    are not thread-safe, and two writes at once crashed the process (SIGSEGV).
    """
    path = Path(directory) / f"{h}{PART_SUFFIX}"
    if _plain(part):
        with write_errors_as_oserror(path), replaced_on_success(path) as tmp, _NETCDF_LOCK:
            _write_plain(part, tmp, {**part.attrs, KEY_ATTR: h})
        return path
    part = part.assign_attrs({KEY_ATTR: h})
    return write_netcdf_atomic(part, path, encoding=_encoding(part))


def _plain(part: xr.Dataset) -> bool:
    """Whether :func:`_write_plain` writes ``part`` as xarray would: numbers and strings, no
    encoding of their own (a variable read from a file), every coordinate an index."""
    import numpy as np

    def plain(value) -> bool:
        return type(value) in (str, int, float) or isinstance(value, np.floating | np.integer)

    def plain_attrs(attrs: Mapping) -> bool:
        return all(plain(v) or type(v) is list and v and all(type(x) in (int, float) for x in v)
                   for v in attrs.values())

    return (all(name in part.dims for name in part.coords) and plain_attrs(part.attrs)
            and all(not var.encoding and plain_attrs(var.attrs)
                    and (var.dtype.kind in "iufU" or var.dtype.kind == "O"
                         and all(isinstance(x, str) for x in var.values.flat))
                    for var in part.variables.values()))


def _write_plain(part: xr.Dataset, path: str, attrs: Mapping[str, Any]) -> None:
    """Write ``part`` (:func:`_plain`) to the new file ``path`` with netCDF4 alone, as
    ``xarray.Dataset.to_netcdf`` writes it (the same dimensions, variables, attributes, fill
    values and filters, in the same order: tests/test_store.py) at a fraction of its cost:
    xarray's encoding and per-variable bookkeeping were a third of a summary part's write,
    and its writes between definitions half of the rest.

    Floats get ``_FillValue`` NaN, but not the uncompressed coordinates (as
    ``write_netcdf_atomic`` with :func:`_encoding`);
    strings are variable-length; arrays of :data:`SMALL_ARRAY_BYTES` and more are compressed
    as one chunk (:func:`_encoding`), the chunk deflated here (:func:`deflated_chunk`) and
    written as bytes through h5py once netCDF4 has closed the file: the same filters and
    values, at a tenth of HDF5's own deflate on a full case's time series.
    """
    import netCDF4
    import numpy as np

    encoding = _encoding(part)
    chunks = []
    with netCDF4.Dataset(path, "w", format="NETCDF4") as nc:
        nc.setncatts(dict(attrs))
        for var in part.variables.values():
            for dim, size in zip(var.dims, var.shape):
                if dim not in nc.dimensions:
                    nc.createDimension(str(dim), size)
        writes = []
        for key, var in part.variables.items():
            name, dims = str(key), tuple(str(d) for d in var.dims)
            values: Any = var.values
            chunked = None
            if values.dtype.kind in "OU":
                out: Any = nc.createVariable(name, str, dims)
                values = str(values[()]) if values.ndim == 0 else values.astype(object)
            else:
                chunked = encoding.get(name)
                # netCDF4 stores native byte order: a byte-swapped array is converted here
                values = values.astype(values.dtype.newbyteorder("="), copy=False)
                # (write_netcdf_atomic's coordinates: no _FillValue, unless compressed)
                fill = np.nan if values.dtype.kind == "f" and (chunked or key not in part.coords) \
                    else None
                out = nc.createVariable(name, values.dtype, dims, fill_value=fill,
                                        **(chunked or {}))
            if var.attrs:
                out.setncatts(dict(var.attrs))
            if chunked:
                chunks.append((name, values))
            else:
                writes.append((out, values))
        # the values once every variable is defined: a write between two definitions ends
        # and reopens netCDF's define mode, which was half of a part's write
        for out, values in writes:
            out[...] = values
    if chunks:
        import h5py

        with h5py.File(path, "r+") as h5:
            for name, values in chunks:
                h5[name].id.write_direct_chunk((0,) * values.ndim, deflated_chunk(values), 0)


def deflated_chunk(values) -> bytes:
    """``values`` as the one chunk of a variable with :data:`COMPRESSION`'s filters, as
    bytes HDF5 reads back: its shuffle filter (byte k of every element together, k = 0, 1,
    ...), then a zlib stream. The stream comes from ISA-L (``isal``), which deflates a full
    case's float time series 10-40x faster than zlib at about the same size (benchmarks/
    README.md, "Part files"); any zlib inflates it. Without ``isal``, zlib writes it. The
    bytes are those of ``values`` in native byte order, the variable's."""
    import numpy as np

    # in native byte order, as netCDF4 creates the variable (a byte-swapped array's own
    # bytes would read back as other values)
    a = np.ascontiguousarray(values, dtype=np.asarray(values).dtype.newbyteorder("="))
    shuffled = np.ascontiguousarray(a.reshape(-1).view(np.uint8).reshape(-1, a.itemsize).T)
    return _compress(shuffled, COMPRESSION["complevel"])


def _zlib_compress() -> Callable[[Any, int], bytes]:
    try:
        from isal import isal_zlib
    except ImportError:     # pragma: no cover - isal is a dependency; zlib writes the same format
        import zlib

        return zlib.compress
    return isal_zlib.compress


#: The deflate of a part's chunks: ISA-L's, or zlib's without isal (the same stream format).
_compress = _zlib_compress()


def read_mark(path: str | os.PathLike) -> tuple[str | None, dict[str, Any] | None]:
    """``(key, identity)`` recorded in the part at ``path`` (:func:`write_part`); ``(None, None)``
    for a file that is not a readable part (truncated, another file, a part of an older
    version without the mark). A resume reads each kept part's mark twice (the plan's count,
    then the folder's opening): the header is read once per file version (its inode, size
    and modification time; parts are replaced by rename, never rewritten in place)."""
    try:
        st = os.stat(path)
    except OSError:
        return None, None
    key, text = _mark_attributes(os.fspath(path), st.st_ino, st.st_size, st.st_mtime_ns)
    try:
        identity = json.loads(text) if isinstance(text, str) else None
    except json.JSONDecodeError:
        identity = None
    return (key if isinstance(key, str) else None), identity


@functools.lru_cache(maxsize=1 << 16)
def _mark_attributes(path: str, inode: int, size: int, mtime_ns: int) -> tuple[Any, Any]:
    """The raw key and identity attributes of one version of the part at ``path``."""
    import netCDF4

    try:
        with netCDF4.Dataset(path) as nc:
            return getattr(nc, KEY_ATTR, None), getattr(nc, IDENTITY_ATTR, None)
    except (OSError, RuntimeError, ValueError):
        return None, None


def file_sha256(path: str | os.PathLike) -> str | None:
    """Hex SHA-256 of the file at ``path`` (None where it cannot be read): what a ledger's
    ``done`` line records of the part it names."""
    digest = hashlib.sha256()
    try:
        with open(path, "rb") as f:
            for block in iter(lambda: f.read(1 << 20), b""):
                digest.update(block)
    except OSError:
        return None
    return digest.hexdigest()


def _is_ledger(path: Path) -> bool:
    """Whether ``path`` is a ledger clearsweep wrote: empty, or its first line one JSON event."""
    try:
        with open(path, encoding="utf-8") as f:
            first = f.readline()
    except (OSError, UnicodeDecodeError):
        return False
    if not first:
        return True
    try:
        record = json.loads(first)
    except json.JSONDecodeError:
        return False
    return isinstance(record, dict) and "event" in record


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
        self._log: TextIO | None = None

    # ------------------------------------------------------------------ life cycle
    def open(self, *, resume: bool = False, overwrite: bool = False,
             expected: Collection[str] | None = None, discard_foreign: bool = False,
             sweep: Mapping[str, Any] | None = None,
             configs: Mapping[str, Config] | None = None) -> set[str]:
        """Take the folder for this sweep.

        Parameters
        ----------
        resume
            Keep the parts of an earlier run of this sweep (they are not run again); a
            kept part whose recorded key is not its name (renamed, swapped) or that cannot
            be read (truncated) is deleted and its case runs again.
        overwrite
            Delete the parts and log of an earlier run.
        expected
            Keys of this sweep's cases (:func:`case_key`). Parts with other keys belong to
            another sweep, or to this one run with other inputs (an edited materials
            file, another clearsweep version): they are never deleted unless
            ``overwrite`` or ``discard_foreign``.
        discard_foreign
            Delete the parts that are not in ``expected``, keep the others.
        sweep
            This sweep (``name``, ``source``, ``cases``), named in the messages.
        configs
            Key -> resolved config of this sweep's cases, to name what changed when
            parts of other inputs are refused.

        Returns
        -------
        set of str
            Keys of the parts kept (empty unless ``resume``).

        Raises
        ------
        StoreError
            The folder holds a file clearsweep did not write (whatever the options);
            another sweep holds it; it holds parts of another sweep or other inputs
            (neither ``overwrite`` nor ``discard_foreign``); or it holds parts of this
            sweep and neither ``resume`` nor ``overwrite`` was given.
        """
        if resume and overwrite:
            raise StoreError("resume and overwrite exclude each other: resume keeps the finished "
                             "cases, overwrite deletes them")
        self._refuse_strangers()        # before the lock file is made in a folder not ours
        self.directory.mkdir(parents=True, exist_ok=True)
        try:
            fd = lock_exclusively(self.directory / LOCK_NAME)
        except ForeignLock as exc:
            raise StoreError(str(exc)) from None
        if fd is None:
            raise StoreError(f"{self.directory} is in use by another sweep; wait for it to "
                             "finish or write to another output file")
        self._lock_fd = fd
        discarded: list[str] = []
        misfiled: list[str] = []
        try:
            self._refuse_strangers()    # again, now that no other sweep writes here
            self._remove_temporaries()
            finished = self.finished()
            foreign = finished - set(expected) if expected is not None else set()
            if foreign and not overwrite:
                if not discard_foreign:
                    raise StoreError(self._foreign_message(foreign, finished, sweep, configs))
                for h in sorted(foreign):
                    self.path(h).unlink()
                discarded = sorted(foreign)
                finished -= foreign
            if finished and not resume:
                if not overwrite:
                    raise StoreError(
                        f"{self.directory} holds {len(finished)} finished case(s) of an earlier "
                        "run of this sweep; pass --resume to continue that sweep (resume=True), "
                        "or --overwrite to delete them and start again (overwrite=True)")
            if overwrite and self.finished():
                for h in self.finished():
                    self.path(h).unlink()
                (self.directory / LOG_NAME).unlink(missing_ok=True)
                finished = set()
            if resume:
                misfiled = sorted(finished - self.kept_on_resume(finished))
                for h in misfiled:      # its name is not what it holds: run its case again
                    warnings.warn(f"the finished part {self.path(h)} cannot be read or does not "
                                  "hold the case it is filed under (truncated, renamed or "
                                  "swapped): deleted, its case runs again", ClearsweepWarning,
                                  stacklevel=2)
                    self.path(h).unlink()
                finished -= set(misfiled)
        except BaseException:
            self.close()
            raise
        self._log = open(self.directory / LOG_NAME, "a", encoding="utf-8")
        if discarded:
            self.log("discarded", hashes=discarded, reason="parts of another sweep (--discard-parts)")
        if misfiled:
            self.log("discarded", hashes=misfiled, reason="the part does not hold the case it is "
                     "filed under (renamed, swapped or truncated): its case runs again")
        return finished

    def _own(self, name: str, ledger: Mapping[str, str]) -> bool:
        """Whether the entry ``name`` of the folder is a file clearsweep wrote: the log, the
        lock, a part's temporary file, or a part that carries the mark or whose name and
        content hash (:func:`file_sha256`) a ``done`` line of the ledger records."""
        path = self.directory / name
        if path.is_symlink() or not path.is_file():
            return False
        if name == LOG_NAME:
            return _is_ledger(path)
        if name == LOCK_NAME:
            return holds_lock_mark(path)           # it holds the mark clearsweep writes
        if _TEMPORARY.fullmatch(name):
            return _is_temporary(path)
        if not name.endswith(PART_SUFFIX) or name.startswith("."):
            return False
        h = name[: -len(PART_SUFFIX)]
        if read_mark(path)[0] is not None:
            return True
        digest = ledger.get(h)
        return digest is not None and digest == file_sha256(path)

    def _ledger(self) -> dict[str, str]:
        """Key -> content hash (SHA-256) of the parts the ledger (``sweep.log``) says a sweep
        wrote here; a line of an older ledger, without the hash, proves nothing (issue 40,
        item 3: a user's file named like a part, plus a ledger line naming it, was deleted)."""
        return {str(r["hash"]): str(r["sha256"]) for r in self.events("done")
                if r.get("hash") and isinstance(r.get("sha256"), str)}

    def strangers(self) -> list[str]:
        """Names of the entries in the folder that clearsweep did not write (sorted)."""
        try:
            names = sorted(os.listdir(self.directory))
        except (FileNotFoundError, NotADirectoryError):
            return []
        ledger = self._ledger()
        return [n for n in names if not self._own(n, ledger)]

    def _refuse_strangers(self) -> None:
        strangers = self.strangers()
        if strangers:
            shown = ", ".join(strangers[:4]) + (f" and {len(strangers) - 4} more"
                                                if len(strangers) > 4 else "")
            raise StoreError(f"{self.directory} holds {len(strangers)} file(s) that clearsweep did "
                             f"not write ({shown}); it keeps a sweep's finished cases in that "
                             "folder and deletes only its own files there: move them away, or "
                             "write to another output file")

    def owner(self) -> dict[str, Any] | None:
        """The sweep that last used the folder, from its latest ``run`` event (None if unknown)."""
        runs = self.events("run")
        return runs[-1] if runs else None

    def _closest_change(self, foreign: set[str], configs: Mapping[str, Config] | None,
                        store: str | None = None) -> tuple[str, bool] | None:
        """What changed between a foreign part's recorded identity and the nearest case of
        this sweep, in words, and whether only the inputs besides the config changed (the
        materials values, the version); None where no part records its identity."""
        if not configs:
            return None
        theirs = next((identity for h in sorted(foreign)[:16]
                       for identity in [read_mark(self.path(h))[1]] if identity), None)
        if theirs is None:
            return None
        ours = [run_identity(cfg) if store is None else part_identity(cfg, store)
                for cfg in list(configs.values())[:256]]
        same_config = [i for i in ours if i["config"] == theirs.get("config")]
        if same_config:
            return identity_changes(theirs, same_config[0]), True
        best = min(ours, key=lambda i: len(identity_differences(theirs, i)))
        return identity_changes(theirs, best), False

    def _foreign_message(self, foreign: set[str], finished: set[str],
                         sweep: Mapping[str, Any] | None,
                         configs: Mapping[str, Config] | None = None) -> str:
        change = self._closest_change(foreign, configs, (sweep or {}).get("store"))
        if change is not None and change[1]:
            return (f"{self.directory} holds {len(foreign)} finished case(s) of this sweep made "
                    f"with other inputs ({change[0]}); resuming would mix the results of two "
                    "inputs: pass --overwrite to delete every part and start again, or "
                    "--discard-parts to delete those parts")
        owner = self.owner()
        out = self.directory.with_name(self.directory.name[: -len(".parts")])
        def describe(run: Mapping[str, Any]) -> str:
            details = [str(run["source"])] if run.get("source") else []
            if run.get("cases") is not None:
                details.append(f"{run['cases']} cases")
            return f"{run.get('name')!r}" + (f" ({', '.join(details)})" if details else "")

        if owner is None:
            whose, again = "another sweep (sweep.log names none)", ""
        else:
            whose = f"the sweep {describe(owner)}"
            command = owner.get("command", "sweep")
            again = (f"; to finish that sweep run: clearsweep {command} {owner['source']} -o {out} "
                     "--resume (with its --set values)" if owner.get("source") else "")
        this = f" {describe(sweep)}" if sweep else ""
        nearest = f" (nearest case: {change[0]})" if change is not None else ""
        return (f"{self.directory} holds {len(foreign)} finished case(s) of {whose}, which are "
                f"not cases of this sweep{this}{nearest}{again}; write to another output file, "
                "or pass --discard-parts to delete those parts (--overwrite deletes every part)")

    def close(self) -> None:
        """Close the log and release the lock (the parts stay)."""
        if self._log is not None:
            self._log.close()
            self._log = None
        if self._lock_fd is not None:
            os.close(self._lock_fd)
            self._lock_fd = None

    def remove(self) -> None:
        """Delete the files clearsweep wrote in the folder, then the folder if nothing else
        is in it (after a successful assembly): a file put there since is left, with the folder.
        The lock file goes last, while still locked (``dataset.lock_exclusively``)."""
        if self._log is not None:
            self._log.close()
            self._log = None
        ledger = self._ledger()
        for name in sorted(os.listdir(self.directory)) if self.directory.is_dir() else []:
            if name not in (LOG_NAME, LOCK_NAME) and self._own(name, ledger):
                (self.directory / name).unlink(missing_ok=True)
        (self.directory / LOG_NAME).unlink(missing_ok=True)
        if self._lock_fd is not None or self._own(LOCK_NAME, ledger):
            (self.directory / LOCK_NAME).unlink(missing_ok=True)
        self.close()
        try:
            self.directory.rmdir()
        except OSError:
            pass

    def __enter__(self) -> PartStore:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def _remove_temporaries(self) -> None:
        for tmp in self.directory.glob(".*.tmp"):
            if _is_temporary(tmp):
                tmp.unlink(missing_ok=True)

    # ------------------------------------------------------------------ parts
    def path(self, h: str) -> Path:
        """Path of the part of the case with hash ``h``."""
        return self.directory / f"{h}{PART_SUFFIX}"

    def kept_on_resume(self, finished: Collection[str] | None = None) -> set[str]:
        """The finished parts (of ``finished``, default all) that ``--resume`` keeps: those
        that can be read and record the key they are filed under (:func:`read_mark`)."""
        return {h for h in (self.finished() if finished is None else finished)
                if read_mark(self.path(h))[0] == h}

    def finished(self) -> set[str]:
        """Hashes of the parts in the folder."""
        if not self.directory.is_dir():
            return set()
        return {p.name[: -len(PART_SUFFIX)] for p in self.directory.glob(f"*{PART_SUFFIX}")
                if not p.name.startswith(".")}

    def write(self, h: str, part: xr.Dataset) -> Path:
        """Write one finished case atomically (temporary file, then rename), marked with its
        key ``h``."""
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
