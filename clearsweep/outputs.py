"""Output paths: an output never replaces an input, nor a file that clearsweep did not write.

Every command that writes a file checks its output path with :func:`check_output` before any
work starts:

- An output that is one of the command's inputs (the config, its ``base:`` file, a
  ``materials_file``, the results file that ``plot`` or ``sensitivity`` reads) is refused, with
  or without ``--overwrite``. "Is" means the same file: the same path once symbolic links are
  resolved (:func:`os.path.realpath`), or, where both exist, the same inode
  (:func:`os.path.samefile`: a hard link).
- An existing file at the output path is replaced only if clearsweep wrote it: a results file
  (:func:`is_results_file`: a netCDF file whose global attribute ``source`` is
  ``clearsweep``, as every run, life run and sweep writes it) or, for a figure, a figure
  clearsweep drew (:func:`is_own_figure`: the creator :func:`figure_metadata` writes into
  every figure). Any other existing file needs ``--overwrite``.
- A results file of another kind than the command writes (:func:`file_kind`: a run, an
  ensemble, a life run, a sweep, a life sweep, a reliability sweep) is not the command's own
  output either: ``clearsweep run life.yaml`` does not replace ``life.nc``, the life run of
  the same config, without ``--overwrite``.
- An output path that is a symbolic link is followed, as a shell's ``>`` follows it: the
  file is written where the link points (a dangling link's target is created) and the link
  stays (:func:`clearsweep.dataset.replaced_on_success`); the checks above apply to that
  target. A link that never reaches a file (a loop) is refused.

The checks raise :class:`OutputError`, which the CLI reports in one line with exit code 2.
"""

from __future__ import annotations

import os
import re
from collections.abc import Callable, Collection, Iterable, Mapping
from pathlib import Path
from typing import Any

from .version import __version__

#: The global attribute ``source`` of every results file clearsweep writes
#: (``dataset.build_dataset``, the sweep and life datasets).
RESULTS_SOURCE = "clearsweep"
#: First bytes of a netCDF file: classic (CDF1, CDF2, CDF5) and netCDF-4 (HDF5).
NETCDF_SIGNATURES = (b"CDF\x01", b"CDF\x02", b"CDF\x05", b"\x89HDF\r\n\x1a\n")
#: Creator written into every figure (:func:`figure_metadata`) and looked for by :func:`is_own_figure`.
FIGURE_CREATOR = f"clearsweep {__version__}"
#: How each figure format holds :data:`FIGURE_CREATOR` (matplotlib's ``metadata`` keys):
#: a PNG tEXt chunk ``Software``, the PDF Info entry ``/Creator``, the SVG Dublin Core creator.
_FIGURE_MARKS = {
    ".png": (b"\x89PNG\r\n\x1a\n", rb"tEXtSoftware\x00clearsweep "),
    ".pdf": (b"%PDF-", rb"/Creator \(clearsweep "),
    ".svg": (b"<?xml", rb"<dc:creator>\s*<cc:Agent>\s*<dc:title>clearsweep "),
}
#: Bytes read from each end of a figure when looking for its creator (PNG and SVG hold it
#: near the start, PDF near the end).
_FIGURE_READ_BYTES = 1 << 20


#: What to do about an existing file that clearsweep did not write.
OVERWRITE_REMEDY = "pass --overwrite to replace it, or choose another output file"
#: The same where --resume is given and --overwrite would delete the parts that it keeps.
RESUME_REMEDY = ("move it away and run again (--overwrite would also delete the finished parts "
                 "that --resume keeps)")


#: Characters an atomic write adds to the name it writes (``dataset.replaced_on_success``'s
#: temporary file ``.NAME.PID.XXXXXXXX.tmp`` beside it, a process id of up to 7 digits).
TEMPORARY_NAME_EXTRA = len("." + ".9999999." + "x" * 8 + ".tmp")
#: File-name length where the file system does not say (Linux, macOS and Windows: 255).
DEFAULT_NAME_MAX = 255
#: The longest path [bytes, with its final NUL] where the system does not say (Linux's PATH_MAX).
DEFAULT_PATH_MAX = 4096


class OutputError(ValueError):
    """An output path that is an input of the command, or an existing file clearsweep did not write."""


def figure_metadata(fmt: str) -> dict[str, str]:
    """matplotlib ``savefig(metadata=...)`` that marks a figure of format ``fmt`` (``"png"``
    or ``".png"``, ``pdf``, ``svg``) as drawn by clearsweep."""
    key = "Software" if fmt.lower().lstrip(".") == "png" else "Creator"
    return {key: FIGURE_CREATOR}


def same_file(a: str | os.PathLike, b: str | os.PathLike) -> bool:
    """Whether ``a`` and ``b`` name one file: one inode where both exist (symbolic or hard
    links), otherwise one path once symbolic links are resolved."""
    try:
        return os.path.samefile(a, b)
    except OSError:
        return os.path.realpath(a) == os.path.realpath(b)


def _starts_with(path: Path, signatures: Iterable[bytes]) -> bool:
    try:
        with open(path, "rb") as f:
            head = f.read(16)
    except OSError:
        return False
    return any(head.startswith(s) for s in signatures)


def is_results_file(path: str | os.PathLike) -> bool:
    """Whether ``path`` is a netCDF file that clearsweep wrote (global attribute ``source``
    equal to :data:`RESULTS_SOURCE`)."""
    path = Path(path)
    if not _starts_with(path, NETCDF_SIGNATURES):
        return False
    import netCDF4

    try:
        with netCDF4.Dataset(path, "r") as nc:
            return getattr(nc, "source", None) == RESULTS_SOURCE
    except (OSError, RuntimeError, ValueError):
        return False


#: What a results file holds (:func:`kind_of`), and how a message names it.
RESULTS_KINDS = {"run": "a run", "life": "a life run", "reliability": "a reliability sweep",
                 "life-sweep": "a life sweep", "ensemble": "an ensemble",
                 "sample": "a sampling sweep", "sweep": "a sweep"}
#: The kinds whose files a sweep's ``store:`` alone tells (the ``sweep_store`` attribute);
#: a sweep of any other store is a ``"sweep"``, an ``"ensemble"`` or a ``"sample"``.
STORE_KINDS = {"life": "life-sweep", "reliability": "reliability"}

#: Dimensions of one case's arrays; any other dimension is a sweep's.
CASE_DIMS = ("time", "joint", "axis", "polar", "azimuth", "angle", "revolution")
#: The dimension of an ensemble's members (after the sweep's own dimensions) and of a
#: sampling sweep's points (``sweep: sample:``), as results files carry them.
MEMBER_DIM = "member"
SAMPLE_DIM = "sample"

#: Kinds that one command writes, as :func:`check_output` compares them: a sweep file of
#: any design (grid, sampling, ensemble) is one family.
_FAMILY = {"ensemble": "sweep", "sample": "sweep"}


def store_kind(store: str) -> str:
    """The kind of results file (a key of :data:`RESULTS_KINDS`) a sweep of ``store``
    writes, as :func:`check_output` compares it (an ensemble or a sampling sweep of the
    ``full`` or ``summary`` store is a ``"sweep"``)."""
    return STORE_KINDS.get(store, "sweep")


def has_member_statistics(dims: Collection[str], variables: Collection[str]) -> bool:
    """Whether a file holds ensemble members and their statistics (a ``member`` dimension
    and ``members_ok``)."""
    return MEMBER_DIM in dims and "members_ok" in variables


def kind_of(attrs: Mapping[str, Any], dims: Collection[str], variables: Collection[str]) -> str:
    """What a results file holds, from its global attributes, dimensions and variable names:
    the one rule behind :func:`file_kind` (a file on disk) and
    ``analysis.results_kind`` (an open dataset). The first that fits:

    ``"life"``
        a life run (``clearsweep life``): a ``cycle`` dimension and the history of its
        blocks (``stop_reason``, or ``block_status`` in a file without it);
    ``"reliability"``, ``"life-sweep"``
        a sweep with ``store: reliability`` or ``store: life`` (its ``sweep_store``
        attribute);
    ``"ensemble"``
        ensemble members and their statistics (a ``member`` dimension and ``members_ok``),
        a sampling sweep with members included;
    ``"sample"``
        a sampling sweep (``sweep: sample:``; a ``sample`` dimension);
    ``"sweep"``
        any other sweep (``store: full`` or ``summary``; a ``sweep_store`` attribute or a
        dimension that is not a case's, :data:`CASE_DIMS`);
    ``"run"``
        one case (``clearsweep run``).
    """
    if "cycle" in dims and ("stop_reason" in variables or "block_status" in variables):
        return "life"
    store = attrs.get("sweep_store")
    if isinstance(store, str) and store in STORE_KINDS:
        return STORE_KINDS[store]
    if has_member_statistics(dims, variables):
        return "ensemble"
    if SAMPLE_DIM in dims:
        return "sample"
    if store is not None or any(d not in CASE_DIMS for d in dims):
        return "sweep"
    return "run"


def file_kind(path: str | os.PathLike) -> str | None:
    """:func:`kind_of` the clearsweep results file at ``path``, read from its header alone;
    None where ``path`` is not a clearsweep results file."""
    if not is_results_file(path):
        return None
    import netCDF4

    try:
        with netCDF4.Dataset(path, "r") as nc:
            return kind_of({k: nc.getncattr(k) for k in nc.ncattrs()}, set(nc.dimensions),
                           set(nc.variables))
    except (OSError, RuntimeError, ValueError):
        return None


def is_own_figure(path: str | os.PathLike) -> bool:
    """Whether ``path`` is a figure clearsweep drew: a PNG, PDF or SVG file (as its suffix
    says) whose creator is :data:`FIGURE_CREATOR` of any version."""
    path = Path(path)
    mark = _FIGURE_MARKS.get(path.suffix.lower())
    if mark is None or not _starts_with(path, [mark[0]]):
        return False
    try:
        with open(path, "rb") as f:
            head = f.read(_FIGURE_READ_BYTES)
            f.seek(max(os.fstat(f.fileno()).st_size - _FIGURE_READ_BYTES, len(head)))
            tail = f.read()
    except OSError:
        return False
    return re.search(mark[1], head + tail) is not None


def _name_max(path: Path, what: str = "PC_NAME_MAX", default: int = DEFAULT_NAME_MAX) -> int:
    """The longest file name [bytes] the file system holding ``path`` (or its nearest
    existing folder) admits (``what="PC_PATH_MAX"``: the longest path)."""
    folder = path.parent
    while True:
        try:
            return int(os.pathconf(folder, what))
        except (OSError, ValueError):
            if folder == folder.parent:
                return default
            folder = folder.parent


def check_name_lengths(path: str | os.PathLike, option: str, derived: Iterable[str] = ()) -> None:
    """Refuse an output whose name, or a name the command derives from it (``derived``: the
    suffixes of ``OUT.parts``, ``OUT.life-checkpoint`` and its lock; each written through
    a temporary file ``.NAME.PID.XXXXXXXX.tmp``), is longer than the file system admits, or
    that lies under a folder name that is, or whose whole path (from ``/``, with the longest
    derived name) is longer than the system's ``PATH_MAX``: the write failed with "File name
    too long" at the end of the work, or a traceback before it.

    Raises
    ------
    OutputError
        Naming the part that is too long, its length and the limit.
    """
    path = Path(path)
    limit = _name_max(path)
    shown = str(path) if len(str(path)) <= 80 else f"{str(path)[:60]}...{str(path)[-12:]}"
    longest = max(("", *derived), key=len)
    for part in path.parent.parts:
        if len(os.fsencode(part)) > limit:
            raise OutputError(f"{option} {shown}: the folder name {part[:24]}... is "
                              f"{len(os.fsencode(part))} bytes long; the file system admits "
                              f"{limit}: choose a shorter one")
    size = len(os.fsencode(path.name))
    if size + len(longest) + TEMPORARY_NAME_EXTRA > limit:
        made = f"OUT{longest} and temporary files" if longest else "temporary files"
        raise OutputError(f"{option} {shown}: the name is {size} bytes long, the names written "
                          f"beside it ({made}) {TEMPORARY_NAME_EXTRA + len(longest)} bytes more, "
                          f"and the file system admits {limit}: choose a name of at most "
                          f"{limit - TEMPORARY_NAME_EXTRA - len(longest)} bytes")
    whole = len(os.fsencode(os.path.abspath(path)))
    path_max = _name_max(path, "PC_PATH_MAX", DEFAULT_PATH_MAX)
    if whole + len(longest) + TEMPORARY_NAME_EXTRA >= path_max:
        raise OutputError(f"{option} {shown}: the path is {whole} bytes long (from /), the "
                          f"names written beside it {TEMPORARY_NAME_EXTRA + len(longest)} bytes "
                          f"more, and the system admits paths of {path_max - 1}: choose a "
                          "shorter path")


def check_folder(path: str | os.PathLike, option: str) -> None:
    """Refuse an output whose folder cannot be made: a part of it is an existing file (``-o
    one.yaml/out.nc``). Missing folders are made when the output is written; before, this
    case ran the whole simulation and then failed with "File exists"."""
    path = Path(path)
    for folder in (path.parent, *path.parent.parents):
        if folder.exists() or folder.is_symlink():
            if not folder.is_dir():
                raise OutputError(f"{option} {path}: {folder} is a file, not a folder; choose "
                                  "an output in a folder")
            return


def check_output(path: str | os.PathLike, option: str,
                 inputs: Iterable[tuple[str, str | os.PathLike | None]], *, overwrite: bool,
                 replaceable: Callable[[Path], bool] = is_results_file,
                 what: str = "a clearsweep results file", remedy: str = OVERWRITE_REMEDY,
                 kind: str | None = None, derived: Iterable[str] = ()) -> None:
    """Refuse to write ``path`` over an input, or over an existing file that is not ``replaceable``.

    Parameters
    ----------
    path
        The output file.
    option
        How the user gave it, named in the message (``"-o/--out"``).
    inputs
        ``(description, path)`` of every file the command reads (``("the config file",
        "a.yaml")``); ``None`` paths are skipped.
    overwrite
        ``--overwrite``: an existing file that is not ``replaceable`` may be replaced.
    replaceable
        Which existing files are the command's own output, replaced without ``--overwrite``:
        :func:`is_results_file` or :func:`is_own_figure`.
    what
        Those files, in words, for the message.
    remedy
        What the user can do about an existing file that is not ``replaceable``.
    kind
        The kind of results file the command writes (a key of :data:`RESULTS_KINDS`): an
        existing results file of another kind is replaced only with ``overwrite`` (a sweep
        of any design, grid, sampling or ensemble, counts as one kind).
    derived
        Suffixes of the names the command writes beside ``path`` (:func:`check_name_lengths`).

    Raises
    ------
    OutputError
        ``path`` is one of ``inputs``, an existing non-regular file (a device such as
        ``/dev/null``, a pipe) or a symbolic link that loops, whatever ``overwrite``; or,
        without ``overwrite``, an existing file that is not ``replaceable`` or a results
        file of another ``kind``.
    """
    path = Path(path)
    check_name_lengths(path, option, derived)
    check_folder(path, option)
    for description, source in inputs:
        if source is not None and same_file(path, source):
            how = ("is" if os.path.abspath(path) == os.path.abspath(source)
                   else "resolves to" if os.path.realpath(path) == os.path.realpath(source)
                   else "is a hard link to")
            raise OutputError(f"{option} {path} {how} {description} {source}, which this command "
                              "reads; an output never replaces an input: choose another output file")
    if path.is_symlink() and Path(os.path.realpath(path)).is_symlink():
        raise OutputError(f"{option} {path} is a symbolic link that never reaches a file (a "
                          "loop); choose another output file")
    if path.exists() and not path.is_file():
        # the write renames a new file into place: it would replace the device or pipe itself
        raise OutputError(f"{option} {path} is not a regular file (a device, a pipe, a socket); "
                          "an output is written to a file: choose one")
    if path.exists() and not overwrite and not replaceable(path):
        raise OutputError(f"{option} {path} exists and is not {what}; {remedy}")
    if kind is not None and path.exists() and not overwrite:
        there = file_kind(path)
        if there is not None and _FAMILY.get(there, there) != _FAMILY.get(kind, kind):
            raise OutputError(f"{option} {path} is the results file of {RESULTS_KINDS[there]}, "
                              f"and this command writes {RESULTS_KINDS[kind]}; {remedy}")
