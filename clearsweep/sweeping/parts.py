"""One finished case per part file; the resume ledger and its lock.

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
"""

from __future__ import annotations

import datetime as _dt
import errno
import fcntl
import hashlib
import json
import os
import shutil
import uuid
from collections.abc import Collection, Mapping
from pathlib import Path
from typing import Any, TextIO

import xarray as xr

from ..dataset import (
    open_results,
    write_netcdf_atomic,
)

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


def parts_dir_for(out: str | os.PathLike) -> Path:
    """The parts folder of the sweep output ``out``: ``OUT.parts`` beside it."""
    out = Path(out)
    return out.with_name(out.name + ".parts")


def _now() -> str:
    return _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")


def _encoding(ds: xr.Dataset) -> dict[str, dict]:
    """Every numeric array of a part compressed as one chunk, exactly as a case of the sweep file.

    Strings and scalars are stored as they are.
    """
    return {str(name): {**COMPRESSION, "chunksizes": var.shape} for name, var in ds.variables.items()
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
        self._log: TextIO | None = None

    # ------------------------------------------------------------------ life cycle
    def open(self, *, resume: bool = False, overwrite: bool = False,
             expected: Collection[str] | None = None, discard_foreign: bool = False,
             sweep: Mapping[str, Any] | None = None) -> set[str]:
        """Take the folder for this sweep.

        Parameters
        ----------
        resume
            Keep the parts of an earlier run of this sweep (they are not run again).
        overwrite
            Delete the parts and log of an earlier run.
        expected
            Hashes of this sweep's cases. Parts with other hashes belong to
            another sweep (another sweep file, other ``--set`` values): they
            are never deleted unless ``overwrite`` or ``discard_foreign``.
        discard_foreign
            Delete the parts that are not in ``expected``, keep the others.
        sweep
            This sweep (``name``, ``source``, ``cases``), named in the messages.

        Returns
        -------
        set of str
            Hashes of the parts kept (empty unless ``resume``).

        Raises
        ------
        StoreError
            Another sweep holds the folder; it holds parts of another sweep
            (neither ``overwrite`` nor ``discard_foreign``); or it holds parts
            of this sweep and neither ``resume`` nor ``overwrite`` was given.
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
        discarded: list[str] = []
        try:
            self._remove_temporaries()
            finished = self.finished()
            foreign = finished - set(expected) if expected is not None else set()
            if foreign and not overwrite:
                if not discard_foreign:
                    raise StoreError(self._foreign_message(foreign, finished, sweep))
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
        except BaseException:
            self.close()
            raise
        self._log = open(self.directory / LOG_NAME, "a", encoding="utf-8")
        if discarded:
            self.log("discarded", hashes=discarded, reason="parts of another sweep (--discard-parts)")
        return finished

    def owner(self) -> dict[str, Any] | None:
        """The sweep that last used the folder, from its latest ``run`` event (None if unknown)."""
        runs = self.events("run")
        return runs[-1] if runs else None

    def _foreign_message(self, foreign: set[str], finished: set[str],
                         sweep: Mapping[str, Any] | None) -> str:
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
        return (f"{self.directory} holds {len(foreign)} finished case(s) of {whose}, which are "
                f"not cases of this sweep{this}{again}; write to another output file, or pass "
                "--discard-parts to delete those parts (--overwrite deletes every part)")

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
