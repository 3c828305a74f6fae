"""Kernel arrays -> labelled ``xr.Dataset`` with CF attributes and provenance."""

from __future__ import annotations

import datetime as _dt
import errno
import fcntl
import os
import re
import shutil
import sys
import tempfile
import time
from contextlib import contextmanager
from contextvars import ContextVar
from pathlib import Path

import numpy as np
import xarray as xr

from .variables import AXES, CASE_VARIABLES, JOINTS, attrs_for
from .version import __version__
from .xarray_compat import defer_dask_array

# every dataset clearsweep builds or opens passes here: xarray imports dask.array only once
# a dask array can exist (clearsweep.xarray_compat)
defer_dask_array()


def versions() -> dict[str, str]:
    """Versions of the package and of the libraries that shape its numbers."""
    import numba

    return {
        "clearsweep_version": __version__,
        "numba_version": numba.__version__,
        "numpy_version": np.__version__,
        "xarray_version": xr.__version__,
        "python_version": sys.version.split()[0],
    }


def bin_centres_deg(n: int, lo: float, hi: float) -> np.ndarray:
    """Centres of ``n`` equal bins spanning [lo, hi] degrees."""
    edges = np.linspace(lo, hi, n + 1)
    return 0.5 * (edges[:-1] + edges[1:])


def build_dataset(arrays: dict[str, np.ndarray], time_s: np.ndarray, *,
                  config_text: str = "", attrs: dict | None = None) -> xr.Dataset:
    """Label the arrays of one case.

    Parameters
    ----------
    arrays
        Mapping from registered variable names (``variables.CASE_VARIABLES``)
        to arrays shaped as the registry's dims; ``status`` may be a string.
    time_s
        Output times [s].
    config_text
        The resolved configuration as YAML text (provenance).
    attrs
        Further dataset attributes.
    """
    data_vars = {}
    sizes = {"time": len(time_s), "joint": len(JOINTS), "axis": len(AXES)}
    for name, value in arrays.items():
        if name == "status":
            continue
        spec = CASE_VARIABLES[name]
        value = np.asarray(value)
        if value.ndim != len(spec.dims):
            raise ValueError(f"{name}: expected dims {spec.dims}, got shape {value.shape}")
        for d, n in zip(spec.dims, value.shape):
            sizes.setdefault(d, n)
        data_vars[name] = xr.Variable(spec.dims, value, attrs_for(name))
    coords = {
        "time": ("time", np.asarray(time_s, dtype=float), attrs_for("time")),
        "joint": ("joint", list(JOINTS), attrs_for("joint")),
        "axis": ("axis", list(AXES), attrs_for("axis")),
    }
    if "polar" in sizes:
        coords["polar"] = ("polar", bin_centres_deg(sizes["polar"], 0.0, 180.0), attrs_for("polar"))
        coords["azimuth"] = ("azimuth", bin_centres_deg(sizes["azimuth"], -180.0, 180.0),
                             attrs_for("azimuth"))
    if "angle" in sizes:
        coords["angle"] = ("angle", bin_centres_deg(sizes["angle"], -180.0, 180.0), attrs_for("angle"))
    if "revolution" in sizes:
        coords["revolution"] = ("revolution", np.arange(1, sizes["revolution"] + 1, dtype=np.int32),
                                attrs_for("revolution"))
    status = xr.Variable((), str(arrays.get("status", "ok")), {
        "long_name": "simulation status", "description": "ok, or the reason the case stopped"})
    # one construction, in the order of before (data, coordinates, status): the coordinates,
    # named as their dimensions, are indexes; a second merge for status cost a third of it
    ds = xr.Dataset({**data_vars, **{name: xr.IndexVariable(*spec) for name, spec in coords.items()},
                     "status": status})
    ds.attrs.update({
        "title": "clearsweep RSSP mechanism simulation",
        "Conventions": "CF-1.8",
        "source": "clearsweep",
        "history": with_command_line(history_line("created by clearsweep")),
        "config": config_text,
    })
    ds.attrs.update(versions())
    if attrs:
        ds.attrs.update(attrs)
    return ds


#: The ``clearsweep`` command line being run, as typed (:func:`recorded_command_line`).
_COMMAND_LINE: ContextVar[tuple[str, ...] | None] = ContextVar("clearsweep_command_line",
                                                               default=None)


@contextmanager
def recorded_command_line(words):
    """Within: :func:`command_line` is ``words`` (``["clearsweep", "run", CONFIG, ...]``); the
    command-line interface runs every command inside one."""
    token = _COMMAND_LINE.set(tuple(str(w) for w in words))
    try:
        yield
    finally:
        _COMMAND_LINE.reset(token)


def command_line() -> str | None:
    """The ``clearsweep`` command line being run (``clearsweep run CONFIG --set KEY=VALUE -o
    OUT``), quoted for a shell; None outside a command."""
    import shlex

    words = _COMMAND_LINE.get()
    return shlex.join(words) if words else None


def history_line(text: str) -> str:
    """A CF ``history`` line: UTC time stamp and ``text``."""
    return f"{_dt.datetime.now(_dt.timezone.utc).strftime('%Y-%m-%dT%H:%M:%SZ')}: {text}"


def with_command_line(history: str) -> str:
    """``history`` (a CF history attribute) with a line recording the command line that is
    writing it (:func:`command_line`), when there is one."""
    line = command_line()
    return "\n".join(filter(None, [history, history_line(line)])) if line else history


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


#: Permissions of a new file: what ``open(path, "w")`` would give (0666 less the umask).
_FILE_MODE = 0o666 & ~_umask()


def _temporary_pattern(path: Path) -> re.Pattern:
    """Names of :func:`replaced_on_success`'s temporary files for ``path``: ``.NAME.PID.XXXX.tmp``."""
    return re.compile(rf"\.{re.escape(path.name)}\.(\d+)\.[A-Za-z0-9_]+\.tmp")


def _process_gone(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    except PermissionError:     # another user's live process
        return False
    try:        # killed but not yet reaped
        with open(f"/proc/{pid}/stat", encoding="ascii") as f:
            return f.read().rpartition(")")[2].split()[0] in ("Z", "X")
    except (OSError, IndexError):
        return False


def remove_stale_temporaries(path: str | os.PathLike) -> list[Path]:
    """Delete the temporary files that killed writers of ``path`` left beside it.

    Only files named as :func:`replaced_on_success` names them for this
    ``path`` (``.NAME.PID.XXXX.tmp``) whose writer process no longer exists
    are removed; a write in progress, or any other file, is left alone.

    Returns
    -------
    list of pathlib.Path
        The files removed.
    """
    path = Path(path)
    pattern = _temporary_pattern(path)
    removed: list[Path] = []
    try:
        candidates = list(path.parent.iterdir())
    except OSError:
        return removed
    for tmp in candidates:
        match = pattern.fullmatch(tmp.name)
        if match and int(match.group(1)) != os.getpid() and _process_gone(int(match.group(1))):
            tmp.unlink(missing_ok=True)
            removed.append(tmp)
    return removed


@contextmanager
def replaced_on_success(path: str | os.PathLike):
    """Yield a temporary path beside ``path``; rename it to ``path`` if the block succeeds.

    On any failure (``KeyboardInterrupt`` included) the temporary file is removed
    and ``path`` is left as it was. The file gets the permissions of an ordinary
    new file (``tempfile.mkstemp`` creates it readable by its owner only). Its
    name, ``.NAME.PID.XXXX.tmp``, carries the writer's process id, so that the
    temporary file of a killed writer is recognised and removed by the next
    write of ``path`` (:func:`remove_stale_temporaries`). A ``path`` that is a symbolic
    link is followed: the file it points to is written (created, where the link dangles)
    and the link stays.
    """
    path = Path(path)
    if path.is_symlink():   # write where the link points, as a shell's `>` does: the link stays
        path = Path(os.path.realpath(path))
    path.parent.mkdir(parents=True, exist_ok=True)
    remove_stale_temporaries(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.{os.getpid()}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        yield tmp
        os.chmod(tmp, _FILE_MODE)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    os.replace(tmp, path)


#: What a lock file that clearsweep makes holds: a file at a lock's path is taken (and
#: removed after) only when it holds exactly this (issue 40, item 3: a user's file named
#: like a lock was deleted).
LOCK_MARK = b"clearsweep lock\n"


class ForeignLock(OSError):
    """A file at a lock's path that clearsweep did not write (:data:`LOCK_MARK`)."""

    def __init__(self, path: Path):
        super().__init__(f"{path} is not a lock file clearsweep wrote; clearsweep deletes only "
                         "its own files: move it away, or write to another output file")
        self.path = path


def holds_lock_mark(path: str | os.PathLike, fd: int | None = None) -> bool:
    """Whether the file at ``path`` (or open as ``fd``) holds :data:`LOCK_MARK` only. A lock
    file is created and its mark written at once; an empty one is read again for up to 0.5 s
    before it is taken for another file."""
    for _ in range(50):
        try:
            if fd is not None:
                data = os.pread(fd, len(LOCK_MARK) + 1, 0)
            else:
                with open(path, "rb") as f:
                    data = f.read(len(LOCK_MARK) + 1)
        except OSError:
            return False
        if data:
            return data == LOCK_MARK
        time.sleep(0.01)
    return False


def lock_exclusively(path: str | os.PathLike) -> int | None:
    """Open ``path`` (created, with its folder, where missing, holding :data:`LOCK_MARK`) and
    take an exclusive ``flock`` on it without waiting; the descriptor, or None where another
    process holds it. A file already at ``path`` that does not hold the mark is not
    clearsweep's: :class:`ForeignLock`, the file untouched.

    The lock counts only once the file locked is still the one at ``path``: a process that
    opened the file just before its holder removed it (holders remove their lock file while
    still holding it) and locked it after, holds a file no longer there, which a third could
    re-create and lock as well; it opens the path again instead. So at most one process
    holds the lock, whatever the interleaving (tests/test_planning_bounds.py)."""
    path = Path(path)
    while True:
        try:
            fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_EXCL, 0o644)
            os.write(fd, LOCK_MARK)
        except FileExistsError:
            try:
                fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW)
            except FileNotFoundError:   # removed by its holder in between: make it again
                continue
            except OSError:             # a link, or a file not ours to open
                raise ForeignLock(path) from None
            if not holds_lock_mark(path, fd):
                os.close(fd)
                raise ForeignLock(path) from None
        except FileNotFoundError:       # the folder was removed by the holder: make it again
            path.parent.mkdir(parents=True, exist_ok=True)
            continue
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as exc:
            os.close(fd)
            if exc.errno in (errno.EAGAIN, errno.EACCES, errno.EWOULDBLOCK):
                return None
            raise
        try:
            now, mine = os.stat(path), os.fstat(fd)
            if (now.st_dev, now.st_ino) == (mine.st_dev, mine.st_ino):
                return fd
        except FileNotFoundError:
            pass
        os.close(fd)        # removed by the process that held it: lock the path's file anew


def file_size_limit() -> int | None:
    """This process's file-size limit (``RLIMIT_FSIZE``, ``ulimit -f``) [bytes]; ``None``:
    none. A write beyond it fails with ``EFBIG`` (netCDF-C: "NetCDF: HDF error")."""
    try:
        import resource
    except ImportError:     # not a POSIX system
        return None
    soft = resource.getrlimit(resource.RLIMIT_FSIZE)[0]
    return None if soft == resource.RLIM_INFINITY else int(soft)


def file_size_limit_text(limit: int | None = None) -> str:
    """The file-size limit in words, for a write it stopped."""
    limit = file_size_limit() if limit is None else limit
    return ("a file would pass this process's file-size limit"
            + (f" of {limit:,} bytes" if limit is not None else "") + " (ulimit -f)")


#: Free space below which a failed write is reported as a full disk [bytes].
NEARLY_FULL_BYTES = 16 * 2 ** 20


@contextmanager
def write_errors_as_oserror(path: str | os.PathLike):
    """Turn the netCDF library's errors of a write into ``OSError`` naming ``path``.

    netCDF-C reports a full disk, or a file it cannot write, as
    ``RuntimeError("NetCDF: HDF error")``, and h5py (the chunks copied into a sweep
    file) as a ``RuntimeError`` or ``OSError`` whose text holds HDF5's ``errno = N``;
    callers (the CLI) catch ``OSError`` for every output failure. The message adds the
    free space on the disk; a write stopped by the file-size limit (``ulimit -f``: HDF5's
    errno 27, or netCDF-C's error under a finite limit) is ``EFBIG`` and names the limit.
    """
    try:
        yield
    except (RuntimeError, OSError) as exc:
        text = str(exc)
        said = re.search(r"errno = (\d+)", text)
        if isinstance(exc, OSError) and (exc.errno is not None or said is None):
            raise
        if not (text.startswith("NetCDF:") or said):
            raise
        code = int(said.group(1)) if said else None
        limit = file_size_limit()
        if code == errno.EFBIG or (code is None and limit is not None):
            raise OSError(errno.EFBIG, file_size_limit_text(limit), str(path)) from exc
        try:
            free = shutil.disk_usage(Path(path).parent).free
        except OSError:
            free = None
        full = code == errno.ENOSPC or (free is not None and free < NEARLY_FULL_BYTES)
        reason = text + (f" (the disk is full: {free} bytes free)" if full else "")
        raise OSError(errno.ENOSPC if full else errno.EIO, reason, str(path)) from exc


def write_netcdf_atomic(ds: xr.Dataset, path: str | os.PathLike, *, encoding: dict | None = None,
                        engine: str = "netcdf4") -> Path:
    """Write ``ds`` to ``path`` via a temporary file in the same folder and an atomic rename.

    A failure at any point leaves no file at ``path`` (and no temporary file);
    a failure of the netCDF library (a full disk) is raised as ``OSError``.
    """
    path = Path(path)
    # coordinates hold no missing values: no _FillValue on them (CF 2.5.1)
    encoding = {**{str(name): {"_FillValue": None} for name in ds.coords}, **(encoding or {})}
    with write_errors_as_oserror(path), replaced_on_success(path) as tmp:
        from xarray.backends.common import ArrayWriter

        store = _writable_store(tmp, engine)
        writer = ArrayWriter()   # what is not written at once (dask-chunked arrays) waits here
        try:
            ds.dump_to_store(store, writer=writer, encoding=encoding)
            writer.sync()
        finally:
            store.close()
    return path


def _writable_store(path: str | os.PathLike, engine: str):
    """A new netCDF file's xarray data store, with a lock of its own: xarray's default
    (``Dataset.to_netcdf``) asks dask which scheduler is running, which imports dask.array
    and distributed (half a second) into every ``clearsweep run``; a file written by one
    process needs no scheduler-aware lock."""
    import threading

    from xarray.backends import H5NetCDFStore, NetCDF4DataStore

    if engine == "h5netcdf":
        return H5NetCDFStore.open(str(path), mode="w", lock=threading.Lock())
    return NetCDF4DataStore.open(str(path), mode="w", format="NETCDF4", lock=threading.Lock())


def open_results(path: str | os.PathLike, **kwargs) -> xr.Dataset:
    """Open a sweep (or one-case) results file.

    Seconds stay floats (``decode_timedelta=False``: ``time`` and
    ``wall_time`` carry ``units: s``), and variable-length strings (material
    names, ``status``, ``message``) come back as strings; sweep coordinates
    keep their values, so ``ds.sel(B_coating="PTFE")`` works.

    Parameters
    ----------
    path
        netCDF file written by :func:`clearsweep.sweeping.run.run_sweep` or ``clearsweep run``.
    **kwargs
        Passed to :func:`xarray.open_dataset` (e.g. ``engine="h5netcdf"``, ``chunks={}``).

    Returns
    -------
    xr.Dataset
        Lazily loaded; close it (or use it as a context manager) when done.
    """
    kwargs.setdefault("decode_timedelta", False)
    return xr.open_dataset(path, **kwargs)
