"""Command-line interface (``clearsweep``): every click command is defined here.

Each command imports the modules it runs when it runs, so ``clearsweep --help``
or ``clearsweep validate`` does not load Numba, xarray or matplotlib; an import
that fails (a broken matplotlib) is reported by the command that needs it, as
an error, not hidden as an unknown command.

Every error, click's usage errors included, is one line on stderr,
``clearsweep: error: <message>`` (``clearsweep: interrupted: ...`` on Ctrl-C), formatted
in one place (:func:`error_line`), with the exit code: 2 for bad input or options (a
:class:`~clearsweep.config.ConfigError` from any subcommand, an unknown option, a missing
argument), 1 for failed work (a run, a life run or ensemble members that stop with a status
other than ``ok``, failed sweep cases, an output file that cannot be written: nothing left
at its path), 130 on interrupt. stdout carries what a command prints as its result (a
summary, a table, a plan); stderr carries progress, notes and ``clearsweep: wrote PATH``.
An output that is one of the command's inputs, or an existing file that clearsweep did not
write (without ``--overwrite``), is refused before any work with exit 2
(:mod:`clearsweep.outputs`).
Every command takes ``-q``; ``run``, ``sweep`` and ``life`` take ``--dry-run``.
"""

from __future__ import annotations

import errno
import json
import math
import os
import re
import shlex
import sys
import time
import warnings
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn

import click

if TYPE_CHECKING:
    import xarray as xr

from .budget import case_plan_text, check_budget, plan_costs
from .choices import (
    DEFAULT_SWEEP_METRIC,
    DPI_RANGE,
    FIGURE_DPI,
    KINDS,
    MAX_CASES,
    OUTPUT_SUFFIXES,
    REPORT_FORMATS,
    SWEEP_BACKENDS,
    SWEPT_X_KINDS,
    X_AXES,
)
from .config import Config, ConfigError, dump_config, file_kind, load_config, parse_yaml, read_yaml
from .outputs import (
    OVERWRITE_REMEDY,
    RESULTS_SOURCE,
    RESUME_REMEDY,
    OutputError,
    check_output,
    is_own_figure,
    store_kind,
)
from .schema import ClearsweepWarning
from .studies import STUDIES
from .variables import JOINTS, format_length
from .version import __version__


class CommandFailed(click.ClickException):
    """A command that cannot finish: ``message`` becomes one ``clearsweep: error: ...`` line
    (``clearsweep: interrupted: ...`` for exit 130) and the process exits with ``exit_code``:
    2 bad input or options, 1 failed work, 130 interrupted."""

    def __init__(self, message: str, exit_code: int = 1) -> None:
        super().__init__(message)
        self.exit_code = exit_code  # type: ignore[misc]  # click's class default is 1


def error_line(exc: click.ClickException) -> str:
    """The one stderr line of ``exc``, whichever command or click itself raised it: the only
    place that formats an error (a usage error names the help that lists the options)."""
    message = exc.format_message().replace("\n", " ").strip()
    if isinstance(exc, click.UsageError):
        if message[:1].isupper() and message[1:2].islower():   # click's "No such option: ..."
            message = message[0].lower() + message[1:]
        if exc.ctx is not None:
            message = f"{message.removesuffix('.')} (see '{exc.ctx.command_path} --help')"
    kind = "interrupted" if exc.exit_code == 130 else "error"
    return f"clearsweep: {kind}: {message}"


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """Print a warning as one ``clearsweep: warning: ...`` line on stderr: clearsweep's own
    in its words, a library's (SALib, scipy, numpy) with where it came from, instead of
    the library's two raw lines with a source line."""
    text = " ".join(str(message).split())
    if not issubclass(category, ClearsweepWarning):
        parts = Path(filename).parts
        origin = next((parts[i + 1] for i, p in enumerate(parts[:-1])
                       if p in ("site-packages", "dist-packages")), Path(filename).stem)
        text = f"{text} ({category.__name__} from {origin})"
    click.echo(f"clearsweep: warning: {text}", err=True)


class _Command(click.Command):
    """A command that reports every error as one line on stderr with its exit code: click's own usage
    errors (exit 2), a ``ConfigError`` or ``OutputError`` whichever command raises it (exit 2), a
    :class:`CommandFailed` (its code) and Ctrl-C (exit 130), whether it runs under the group
    or on its own (a script or a test may call one): click runs in non-standalone mode."""

    def invoke(self, ctx: click.Context):
        try:
            with warnings.catch_warnings():
                warnings.showwarning = _show_warning
                return super().invoke(ctx)
        except (ConfigError, OutputError) as exc:
            raise CommandFailed(str(exc), 2) from None
        except KeyboardInterrupt:
            raise CommandFailed("stopped by Ctrl-C", 130) from None

    def main(self, args=None, prog_name=None, complete_var=None, standalone_mode=True, **extra):
        if not standalone_mode:
            return super().main(args, prog_name, complete_var, False, **extra)
        try:
            code = super().main(args, prog_name, complete_var, False, **extra)
        except click.exceptions.NoArgsIsHelpError as exc:   # bare `clearsweep`: its help
            click.echo(exc.ctx.get_help() if exc.ctx else "")
            code = 0
        except click.ClickException as exc:
            click.echo(error_line(exc), err=True)
            code = exc.exit_code
        except click.Abort:
            click.echo(error_line(CommandFailed("stopped by Ctrl-C", 130)), err=True)
            code = 130
        sys.exit(code if isinstance(code, int) else 0)


class _Group(_Command, click.Group):
    """The ``clearsweep`` group: its commands are :class:`_Command`, as it is."""

    command_class = _Command

    def main(self, args=None, *rest, **extra):
        from .dataset import recorded_command_line

        # the command line as typed: the history of a results file it writes records it
        words = sys.argv[1:] if args is None else shlex.split(args) if isinstance(args, str) else args
        try:
            with recorded_command_line(["clearsweep", *words]):
                return super().main(args, *rest, **extra)
        finally:
            if args is None and not rest and extra.get("standalone_mode", True):
                _ending()


def _ending() -> None:
    """The ``clearsweep`` process ends with its command (it exits once this returns): move
    what the command made out of the garbage collector's reach, so that the interpreter's
    shutdown does not walk it again. Those collections were 0.14-0.33 s of a short run
    (benchmarks/README.md, the cached start); its files are written and closed by then,
    and the exit handlers still run. Not done where the command runs inside a caller
    (arguments given: a script, ``CliRunner``)."""
    import gc

    gc.freeze()


_allow_large = click.option(
    "--allow-large", is_flag=True,
    help="Run a case beyond the bounds on its work and memory (4 GiB of arrays, 1e9 RK4 steps).")

def announce_compile(quiet: bool = False, cases: Iterable[Config] = ()) -> None:
    """Compile the kernel builds that the ``cases`` run (their solver.method and joint set,
    ``params.kernel_build``) now, saying so, where neither this process nor the cache
    has them."""
    from .core.jointset import label
    from .params import kernel_build
    from .simulation import kernel_needs_compiling, prepare_kernel

    for method, build in dict.fromkeys((cfg.solver.method, kernel_build(cfg)) for cfg in cases):
        if kernel_needs_compiling(method, build):
            if not quiet:
                name = "kernel" if method == "rk4" else f"{method} kernel"
                click.echo(f"compiling the {name} build that allows clearance at {label(build)} (once, "
                           f"about {plan_costs().compile_s:.0f} s on a quiet 2-core machine, "
                           "longer when it is busy) ...",
                           err=True)
            seconds = prepare_kernel(method, build)
            if not quiet:
                click.echo(f"compiled in {seconds:.0f} s; cached for later runs", err=True)


def _cap_workers(workers: int | None, option: str = "--workers") -> int | None:
    """Worker processes on this machine: at most its cores (a process per case beyond them
    only takes memory); says so on stderr when it caps."""
    cores = os.cpu_count() or 1
    if workers is not None and workers > cores:
        click.echo(f"clearsweep: note: {option} {workers} is more than this machine's {cores} "
                   f"cores; using {cores}", err=True)
        return cores
    return workers


def _reason(exc: OSError) -> str:
    """Why a write failed, in words: a full disk is named as such."""
    if exc.errno == errno.ENOSPC:
        return f"the disk is full ({exc.strerror})"
    if exc.errno == errno.EFBIG:
        from .dataset import file_size_limit_text

        return (exc.strerror if exc.strerror and "ulimit -f" in exc.strerror
                else file_size_limit_text()) + "; raise the limit (ulimit -f unlimited)"
    return exc.strerror or str(exc)


def _write_or_exit(ds: Any, out: str | Path) -> Path:
    """Write ``ds`` to ``out`` atomically; an unwritable path is one error line and exit 1."""
    from .dataset import write_netcdf_atomic

    path = Path(out)
    try:
        write_netcdf_atomic(ds, path)
    except OSError as exc:
        _fail(f"cannot write {path}: {_reason(exc)}", 1)
    return path


def _case_inputs(config: str, cfg) -> list[tuple[str, str | None]]:
    """The files a case config's command reads (for ``outputs.check_output``)."""
    return [("the config file", config), ("the materials file", cfg.materials_file)]


def _check_out(out: str | None, default: str | Path, inputs, overwrite: bool,
               parts_resumed: bool = False, *, kind: str,
               derived: Iterable[str] = (".parts",)) -> str:
    """``-o/--out`` (or its default), refused where it is an input, a file that is not a
    clearsweep results file or a results file of another ``kind`` than the command writes
    (without --overwrite; ``outputs.file_kind``), or where it or a name ``derived`` from
    it is too long for the file system; returns the path. ``parts_resumed``: --resume of a
    sweep or ensemble, which --overwrite cannot join."""
    path = out or str(default)
    check_output(path, "-o/--out" if out else "-o/--out (default)", inputs, overwrite=overwrite,
                 remedy=RESUME_REMEDY if parts_resumed else OVERWRITE_REMEDY, kind=kind,
                 derived=derived)
    return path


def _replacing(path: str, attr: str, new_text: str) -> str:
    """What writing ``path`` replaces, for the line that says it was written: ``""`` when
    nothing is there, else the earlier result's time and the values it was made with that
    differ (from the resolved config its attribute ``attr`` records), shown as --set."""
    if not Path(path).is_file():
        return ""
    import netCDF4

    from .params import _flat

    try:
        # the two attributes alone: opening it with xarray decoded every variable
        with netCDF4.Dataset(path, "r") as old:
            attrs = {name: old.getncattr(name) for name in old.ncattrs()}
        old_text, history = attrs.get(attr), str(attrs.get("history", ""))
        if not isinstance(old_text, str):
            return ""
        # the same text: the same values, without reading it twice (most of this, before)
        old_flat, new_flat = ({}, {}) if old_text == new_text else (
            _flat(parse_yaml(old_text, path)), _flat(parse_yaml(new_text, "config")))
    except Exception:       # not a results file we can read: check_output decided it may go
        return ""
    when = history.split(": ", 1)[0] if ": " in history else "earlier"
    changed = [f"{k}={json.dumps(old_flat.get(k))}" for k in sorted(set(old_flat) | set(new_flat))
               if k != "name" and old_flat.get(k) != new_flat.get(k)]
    what = ("made with the same values" if not changed else "made with --set " + " --set ".join(
        changed[:6]) + (f" and {len(changed) - 6} more differences" if len(changed) > 6 else ""))
    return f", replacing the result of {when} {what}"


def _check_figure(path: str, option: str, inputs, overwrite: bool) -> None:
    """A figure's output: never an input; an existing file only if clearsweep drew it (or --overwrite)."""
    check_output(path, option, inputs, overwrite=overwrite, replaceable=is_own_figure,
                 what="a figure clearsweep drew")


def _wrote(path: str | Path, quiet: bool, detail: str = "") -> None:
    """Say on stderr which file a command wrote (stdout carries what it prints as its result:
    a summary, a table, a plan), unless ``quiet``."""
    if not quiet:
        click.echo(f"clearsweep: wrote {path}{detail}", err=True)


class _InFile(click.Path):
    """An input file's path: a name with a NUL byte is refused in one line (click's check
    of the path ended in a ValueError traceback, "embedded null byte")."""

    def convert(self, value, param, ctx):
        text = os.fsdecode(value) if isinstance(value, bytes | os.PathLike) else str(value)
        if "\0" in text:
            self.fail(f"{text!r} holds a NUL byte, which no file name can", param, ctx)
        return super().convert(value, param, ctx)


class _OutFile(click.Path):
    """An output file's path (``-o/--out``): refused at once where it cannot name a file,
    an empty name or a name ending in ``/`` (before, ``-o ''`` wrote the default file and
    ``-o new/`` the file ``new``, exit 0)."""

    def __init__(self) -> None:
        super().__init__(dir_okay=False)

    def convert(self, value, param, ctx):
        text = os.fsdecode(value) if isinstance(value, bytes | os.PathLike) else str(value)
        if text == "":
            self.fail("an empty name; give a file name, such as out.nc", param, ctx)
        if "\0" in text:
            self.fail(f"{text!r} holds a NUL byte, which no file name can; give a file name, "
                      "such as out.nc", param, ctx)
        if text.endswith(("/", os.sep)) or os.path.basename(text) in (".", ".."):
            self.fail(f"{text!r} names a folder; give a file in it, such as "
                      f"{text.rstrip('/' + os.sep) or '.'}/out.nc", param, ctx)
        return super().convert(value, param, ctx)


_OUT_FILE = _OutFile()

_quiet = click.option("-q", "--quiet", is_flag=True,
                      help="Print nothing but errors and warnings.")
_dry_run = click.option("--dry-run", is_flag=True,
                        help="Print the plan (cases, RK4 steps, memory, time estimate) and exit, "
                             "simulating nothing and writing no file.")


_overrides = click.option(
    "--set", "overrides", multiple=True, metavar="KEY=VALUE",
    help="Override a config value, VALUE in YAML (e.g. joints.B.coating=PTFE, "
         "solver.baumgarte=[50,50]); repeatable.")


@click.group("clearsweep", cls=_Group, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="clearsweep")
def main() -> None:
    """Dynamics and wear of the RSSP mechanism and the planar slider-crank
    (mechanism.kind) with clearance and coatings in any of their joints: the crank's
    bearing O, the crank pin A, the rod-slider joint B, the slider's guide P."""


@main.command()
@click.argument("config", type=_InFile(dir_okay=False))
@click.option("-o", "--out", type=_OUT_FILE,
              help="Output netCDF file [default: <config stem>.nc in the current folder].")
@_overrides
@_allow_large
@_quiet
@_dry_run
@click.option("--workers", type=click.IntRange(min=1), default=None,
              help="Worker processes for the members of an ensemble [default: all cores].")
@click.option("--resume", is_flag=True,
              help="Ensemble: continue an interrupted run, keeping the members in OUT.parts/.")
@click.option("--overwrite", is_flag=True,
              help="Replace an existing OUT that is not a clearsweep results file; ensemble: "
                   "also delete the members an earlier run left in OUT.parts/.")
@click.option("--discard-parts", is_flag=True,
              help="Ensemble: delete the parts in OUT.parts/ that belong to another sweep or "
                   "config; without it such parts make the run refuse.")
def run(config: str, out: str | None, overrides: tuple[str, ...], allow_large: bool,
        quiet: bool, dry_run: bool, workers: int | None, resume: bool, overwrite: bool,
        discard_parts: bool) -> None:
    """Simulate one case described by CONFIG (YAML) and write its results; with
    ``ensemble.members > 1``, every member (a ``member`` dimension) and the ensemble
    statistics, run as a sweep: finished members are kept in OUT.parts/ until OUT is
    written, and an interrupted run continues with --resume (exit 130 on interrupt)."""
    cfg = load_config(config, overrides)
    est = check_budget(cfg, allow_large=allow_large, source=config)
    if cfg.ensemble.members <= 1 and (resume or discard_parts):
        raise click.UsageError("--resume and --discard-parts act on the parts of an ensemble "
                               "(ensemble.members > 1); this config runs one case")
    if dry_run:
        out = out or Path(config).stem + ".nc"
    else:
        out = _check_out(out, Path(config).stem + ".nc", _case_inputs(config, cfg), overwrite,
                         resume, kind="ensemble" if cfg.ensemble.members > 1 else "run")
    if cfg.ensemble.members > 1:
        _run_ensemble(config, cfg, out, overrides, allow_large, quiet, _cap_workers(workers),
                      resume=resume, overwrite=overwrite, discard_parts=discard_parts,
                      dry_run=dry_run)
        return
    # bad input is refused before the kernel is compiled (the seated start needs it)
    _preflight(cfg, config, allow_large)
    if dry_run:
        click.echo(case_plan_text(config, est, cfg))
        return
    from .simulation import simulate

    replacing = _replacing(out, "config", dump_config(cfg))
    announce_compile(quiet, [cfg])
    try:
        ds = simulate(cfg, allow_large=allow_large)
    except ConfigError as exc:
        if exc.source != "<config>":
            raise
        # A check on the resolved config (the step bound): name the file it came from.
        raise ConfigError(exc.key, exc.value, exc.expected, config, exc.suggestion,
                          exc.got) from None
    except MemoryError as exc:
        _out_of_memory(exc, est.describe())
    path = _write_or_exit(ds, out)
    if not quiet:
        from .analysis import run_summary_text

        click.echo(run_summary_text(ds))
    _wrote(path, quiet, replacing)
    status = str(ds["status"].values)
    if status != "ok":
        hint = ds.attrs.get("status_hint")
        _fail(f"run stopped: {status} (results so far in {path})" + (f"; {hint}" if hint else ""),
              1)


@main.command("life")
@click.argument("config", type=_InFile(dir_okay=False))
@click.option("-o", "--out", type=_OUT_FILE,
              help="Output netCDF file [default: <config stem>_life.nc in the current folder].")
@_overrides
@_allow_large
@_quiet
@_dry_run
@click.option("--resume", is_flag=True,
              help="Continue an interrupted life run from its checkpoint OUT.life-checkpoint.")
@click.option("--discard-checkpoint", is_flag=True,
              help="Delete a checkpoint OUT.life-checkpoint that this run cannot continue (an "
                   "earlier run without --resume, another config or other --set values); "
                   "without it such a checkpoint makes the run refuse.")
@click.option("--overwrite", is_flag=True,
              help="Replace an existing OUT that is not a clearsweep results file.")
def life_command(config: str, out: str | None, overrides: tuple[str, ...], allow_large: bool,
                 quiet: bool, dry_run: bool, resume: bool, discard_checkpoint: bool,
                 overwrite: bool) -> None:
    """Service life of CONFIG by cycle jumps (its `life:` section; docs/service_life.md):
    clearance growth, coating wear-through and vibration against revolutions.

    The state after every block is kept in OUT.life-checkpoint until OUT is written; an
    interrupted or killed run continues with --resume (exit 130 on interrupt).
    """
    cfg = load_config(config, overrides)
    from .service_life import (
        CHECKPOINT_SUFFIX,
        CheckpointError,
        LifeInterrupted,
        LifeState,
        block_steps,
        checkpoint_path_for,
        life,
        life_block,
        life_plan_text,
        life_stop_hint,
        life_summary_text,
        life_time_left,
        life_time_text,
    )

    if cfg.ensemble.members > 1:    # one life run follows one case: it would run member 0 alone
        raise ConfigError("ensemble.members", cfg.ensemble.members, "1 with `clearsweep life`; a "
                          "life run of every member is a sweep file with store: life", config)
    if dry_run:
        click.echo(life_plan_text(cfg, config, allow_large=allow_large))
        return
    life_block(cfg, allow_large=allow_large, source=config)     # refused before the compile
    out = _check_out(out, Path(config).stem + "_life.nc", _case_inputs(config, cfg), overwrite,
                     kind="life",
                     derived=(CHECKPOINT_SUFFIX, CHECKPOINT_SUFFIX + ".lock"))
    checkpoint = checkpoint_path_for(out)
    replacing = _replacing(out, "config", dump_config(cfg))
    if not quiet:       # the plan's time, as a sweep prints its plan before it runs
        click.echo(f"clearsweep: a life run of at most {cfg.life.max_blocks:,} blocks: "
                   f"{life_time_text(cfg, block_steps(cfg))}", err=True)
    announce_compile(quiet, [cfg])

    started, blocks = time.perf_counter(), [0]
    depths: list[tuple[float, float]] = []      # (revolutions, deepest bin [m]) per block
    before = [(0, 0.0)]                         # a resumed checkpoint's blocks and revolutions

    def deepest(row: dict[str, Any]) -> tuple[float, float]:
        finite = [float(d) for d in row["wear_depth_max"] if math.isfinite(d)]
        return float(row["cycle"]), max(finite, default=0.0)

    def progress(row: dict[str, Any]) -> None:
        blocks[0] += 1
        depths.append(deepest(row))
        if not quiet:
            # the joints with a clearance (an ideal joint's depth is NaN)
            depth = ", ".join(f"{j} {format_length(d, 3)}" for j, d in zip(JOINTS, row["wear_depth_max"])
                              if math.isfinite(d))
            left = life_time_left(cfg, float(row["cycle"]), blocks[0], time.perf_counter() - started,
                                  depths, before[0])
            click.echo(f"  block at {row['cycle']:.4g} revolutions: max depth {depth}, "
                       f"status {row['block_status']}" + (f"; {left}" if left else ""), err=True)

    def resumed(state: LifeState) -> None:
        # the blocks left count from the checkpoint's, the pace from this process's
        before[0] = (len(state.rows), float(state.cycles))
        depths[:] = [deepest(row) for row in state.rows]
        if not quiet:
            click.echo(f"resuming from {checkpoint}: {len(state.rows)} blocks, "
                       f"{state.cycles:.4g} revolutions", err=True)

    try:
        ds = life(cfg, allow_large=allow_large, progress=progress, checkpoint=checkpoint,
                  resume=resume, discard_checkpoint=discard_checkpoint, resumed=resumed)
    except CheckpointError as exc:
        _fail(str(exc), 2)
    except LifeInterrupted as exc:
        _fail(f"{exc.blocks} finished blocks are kept in {checkpoint}; continue "
              f"with: {_resume_command('life', config, out, overrides)}" if exc.blocks
              else "before a block finished", 130)
    except OSError as exc:
        _fail(f"cannot write {exc.filename or checkpoint}: {_reason(exc)}", 1)
    except MemoryError as exc:
        _out_of_memory(exc, "its blocks and snapshots (see --dry-run)",
                       f"; the finished blocks are kept in {checkpoint}" if checkpoint.exists() else "")
    path = _write_or_exit(ds, out)
    checkpoint.unlink(missing_ok=True)
    if not quiet:
        click.echo(life_summary_text(ds))
    _wrote(path, quiet, replacing)
    if str(ds["stop_reason"].values).startswith("block_status:"):
        hint = life_stop_hint(cfg, str(ds["stop_reason"].values))
        _fail(f"life run stopped: {ds['stop_reason'].values} (results so far in {path})"
              + (f"; {hint}" if hint else ""), 1)


def _run_ensemble(config: str, cfg, out: str, overrides: tuple[str, ...],
                  allow_large: bool, quiet: bool, workers: int | None, *, resume: bool,
                  overwrite: bool, discard_parts: bool, dry_run: bool) -> None:
    """``run`` of an ensemble: its members as a sweep of one design (all in one file), under
    the sweep's rules for its parts and failures (:func:`_run_sweep_or_fail`)."""
    from .analysis import format_ensemble_report
    from .sweeping import expand

    if resume and overwrite:
        raise click.UsageError("--resume keeps the finished members and --overwrite deletes "
                               "them; give one")
    path = Path(out)
    try:
        plan = expand({"name": Path(config).stem, "base": cfg.to_dict()}, allow_large=allow_large,
                      too_many_hint="a sweep file with this config as its base runs more: "
                                    "clearsweep sweep FILE --yes")
    except ConfigError as exc:   # the members' count: name the file it came from
        raise ConfigError(exc.key, exc.value, exc.expected, config, exc.suggestion, exc.got) from None
    plan.source, plan.command = config, "run"
    if dry_run:
        click.echo(plan.plan_text(_plan_workers(plan, workers)))
        return
    announce_compile(quiet, [cfg])
    ds = _run_sweep_or_fail(plan, str(path), "run", config, overrides, workers=workers,
                            progress=not quiet, allow_large=allow_large, resume=resume,
                            overwrite=overwrite, discard_parts=discard_parts)
    with ds:
        if not quiet:
            click.echo(format_ensemble_report(ds))
        failed = int(ds.attrs["sweep_failed"])
        n = int(ds.attrs["sweep_cases"])
    _wrote(path, quiet)
    if failed:
        _fail(f"{failed} of {n} members stopped with a status other than ok (see the status and "
              f"message variables in {path})", 1)


def _plan_workers(plan, workers: int | None) -> int:
    """The cores a plan's cases share: ``workers`` (all cores by default), at most one per case."""
    return min(workers or os.cpu_count() or 1, max(len(plan.runnable()), 1))


def _run_sweep_or_fail(plan, out: str, command: str, config: str, overrides: tuple[str, ...],
                       **options: Any) -> xr.Dataset:
    """:func:`clearsweep.sweeping.run_sweep` of ``plan`` for ``sweep`` and an ensemble ``run``,
    its failures each one error line: exit 2 for a bad config or foreign parts, 1 for failed
    work or an unwritable output (naming the finished cases kept), 130 on interrupt (with the
    command that continues)."""
    from .sweeping import PartStore, StoreError, SweepFailed, SweepInterrupted, parts_dir_for, run_sweep

    try:
        return run_sweep(plan, out, report_failures=False, **options)
    except (ConfigError, StoreError) as exc:
        _fail(str(exc), 2)
    except SweepInterrupted as exc:
        _fail(f"{exc.finished} of {exc.total} cases are finished and kept in {exc.parts_dir}; "
              f"continue with: {_resume_command(command, config, out, overrides)}", 130)
    except KeyboardInterrupt:
        _fail("before any case finished", 130)
    except SweepFailed as exc:
        _fail(str(exc), 1)
    except OSError as exc:
        parts = parts_dir_for(out)
        kept = PartStore(parts).finished() if parts.is_dir() else set()
        room = "" if exc.errno == errno.EFBIG else "make room and "
        note = (f"; the {len(kept)} finished case(s) are kept in {parts}: {room}run again "
                "with --resume" if kept else "")
        _fail(f"cannot write {exc.filename or out}: {_reason(exc)}{note}", 1)


def _preflight(cfg, config: str, allow_large: bool) -> None:
    """What a run checks before it starts, compiling nothing (``simulation.preflight`` without
    the seated start): the packing (the guide's reach) and the step bound; an error names the
    file ``config``."""
    from .simulation import preflight

    try:
        preflight(cfg, allow_large=allow_large, seat=False)
    except ConfigError as exc:
        if exc.source != "<config>":
            raise
        raise ConfigError(exc.key, exc.value, exc.expected, config, exc.suggestion, exc.got,
                          exc.line) from None


@main.command()
@click.argument("config", type=_InFile(dir_okay=False))
@_overrides
@_allow_large
@click.option("-y", "--yes", is_flag=True,
              help=f"Sweep file: check a sweep of more than {MAX_CASES:,} cases (refused without it).")
@_quiet
def validate(config: str, overrides: tuple[str, ...], allow_large: bool, yes: bool,
             quiet: bool) -> None:
    """Check CONFIG and the work and memory it implies, running nothing.

    A case config is printed resolved as YAML (its steps, memory and time on
    stderr); a sweep file is checked case by case, and its dimensions, case
    count, steps, memory and time estimate are printed. With -q, only the exit status
    (and an error) tells whether it is valid.
    """
    if file_kind(read_yaml(config, config)) == "sweep":
        from .sweeping import expand

        plan = expand(config, overrides, allow_large=allow_large,
                      max_cases=None if yes else MAX_CASES,
                      too_many_hint="clearsweep validate --yes checks them all",
                      enumerate_cases=False)
        if not quiet:
            click.echo(plan.plan_text(_plan_workers(plan, None)))
        return
    cfg = load_config(config, overrides)
    est = check_budget(cfg, allow_large=allow_large, source=config)
    _preflight(cfg, config, allow_large)
    from .config import resolve_materials
    from .params import hertz_sink_warnings

    for text in hertz_sink_warnings(cfg, resolve_materials(cfg)):
        click.echo(f"clearsweep: warning: {config}: {text}", err=True)
    if not quiet:
        click.echo(dump_config(cfg), nl=False)
        click.echo(f"clearsweep: {config}: a valid case config: {est.steps:,} RK4 steps, memory "
                   f"up to {est.describe()}; run it with `clearsweep run {config}`", err=True)


@main.command()
@click.option("-m", "--materials-file", type=_InFile(dir_okay=False),
              help="User materials YAML that adds or overrides materials.")
@_quiet
def materials(materials_file: str | None, quiet: bool) -> None:
    """List the materials, their properties and the source of every value (with -q, only
    check the materials file)."""
    from .materials import format_materials, load_materials

    text = format_materials(load_materials(materials_file))
    if not quiet:
        click.echo(text)


def _check_results_size(path: str) -> None:
    """Refuse (exit 2) a results file that is not a regular file (a FIFO would be waited on),
    or whose metadata declares a variable larger than :data:`clearsweep.budget.MAX_READ_BYTES`,
    before any of it is read."""
    from .budget import MAX_READ_BYTES, format_bytes, largest_variable
    from .schema import special_file

    try:
        kind = special_file(os.stat(path).st_mode)
    except OSError as exc:
        raise click.BadParameter(f"{path!r} is not a results file ({exc.strerror})",
                                 param_hint="'PATH'") from None
    if kind is not None:
        raise click.BadParameter(f"{path!r} is {kind}, not a results file (a regular netCDF "
                                 "file)", param_hint="'PATH'")
    largest = largest_variable(path)
    if largest is not None and largest[2] > MAX_READ_BYTES:
        name, dims, size = largest
        shape = " x ".join(f"{n:,} {d}" for d, n in dims.items())
        raise click.BadParameter(
            f"{path!r} declares a variable {name!r} of {shape} values ({format_bytes(size)}); "
            f"this command reads whole variables, of at most {format_bytes(MAX_READ_BYTES)}",
            param_hint="'PATH'")


@contextmanager
def open_input(path: str) -> Iterator[xr.Dataset]:
    """Open the results file of a ``report``, ``plot`` or ``sensitivity`` command for a
    ``with`` block: a file xarray cannot read, or one that lacks a variable or dimension
    the command reads (a file of an older version, or edited since), is a usage error
    (exit 2), not a traceback; so is a FIFO or a device, and a file whose metadata declares
    a variable beyond :data:`clearsweep.budget.MAX_READ_BYTES`, before anything is read."""
    import xarray as xr

    _check_results_size(path)
    try:
        ds = xr.open_dataset(path)
    except (OSError, ValueError) as exc:
        reason = getattr(exc, "strerror", None) or "no netCDF reader can open it"
        raise click.BadParameter(f"{path!r} is not a results file ({reason})",
                                 param_hint="'PATH'") from None
    with ds:
        from .variables import layout_problem

        source = ds.attrs.get("source")
        ours = (any(name in ds for name in ("status", "stop_reason", "block_status"))
                or any(name in ds.attrs for name in ("sweep_store", "sweep_config")))
        if source != RESULTS_SOURCE and (source is not None or not ours):
            raise click.UsageError(f"{path}: not a clearsweep results file (its source attribute "
                                   f"is {source!r}, not {RESULTS_SOURCE!r}): give a file that "
                                   "run, life or sweep wrote")
        problem = layout_problem(ds)
        if problem:
            raise click.UsageError(f"{path}: the file is not as clearsweep writes it: {problem} "
                                   "(edited since, or written by another program); write it "
                                   "again with the command that made it")
        try:
            yield ds
        except KeyError as exc:
            text = str(exc.args[0]) if exc.args else ""
            found = re.match(r"No variable named '([^']+)'", text)
            name = found.group(1) if found else text
            if name in ds.variables or name in ds.dims:
                raise       # the file has it: not the file's fault
            raise click.UsageError(
                f"{path}: the file has no {name!r}, which this command reads (a results file "
                "of an older version of clearsweep, or edited since); write it again with the "
                "command that made it") from None


def _needs(ds: xr.Dataset, path: str, name: str, what: str) -> None:
    """A usage error unless the results file ``ds`` holds ``name``, which ``what`` report
    reads: the file of an older version (or an edited one) is refused, not misread."""
    if name not in ds:
        raise click.UsageError(f"{path}: the file has no {name!r}, which {what} report reads (a "
                               "results file of an older version of clearsweep, or edited since); "
                               "write it again with the command that made it")


@main.command("report")
@click.argument("path", type=_InFile(exists=True, dir_okay=False))
@click.option("--format", "fmt", type=click.Choice(REPORT_FORMATS), default="text", show_default=True,
              help="Output format.")
@click.option("--reference", multiple=True, metavar="DIM=VALUE",
              help="Reference case of a sweep (repeatable): print the change of every other case "
                   "against it (paper Table 6).")
@click.option("--metric", default=None, metavar="NAME",
              help="Print this summary metric over the sweep dimensions instead "
                   "(e.g. slider_acceleration_peak).")
@click.option("--full", is_flag=True,
              help="Sweep: print every case's tables after the summary (csv and json always "
                   "give them).")
@_quiet
def report_command(path: str, fmt: str, reference: tuple[str, ...], metric: str | None,
                   full: bool, quiet: bool) -> None:
    """Print the every-step statistics (settled first) and the wear table (paper Tables
    4-5) of a results file PATH (csv and json: one flat table, a row per case, joint and
    wear direction, with every statistic and the wear table's columns).

    A sweep (or an ensemble) prints a summary first: its design axes and, per headline
    metric, the best and worst design and their spread; every case's tables follow with
    --full, and csv and json give them without the summary.

    With --reference, the reduction of the maximum wear depth and the change
    of the wear range against that case (Table 6); with --metric, one summary
    metric over the sweep dimensions. An ensemble (a ``member`` dimension) prints
    each design's mean -+ the 95 % confidence half-width and the design
    comparisons, each "distinguishable" or "not distinguishable" (--reference
    then picks the designs compared against).

    A life run, a life sweep and a reliability sweep are printed as text: --format other
    than text, --reference and --full are refused for them (and --metric for a life run).
    With -q, nothing is printed: only the exit status says whether PATH can be reported.
    """
    from .analysis import (
        SelectionError,
        bushing_text,
        design_dims,
        format_metric_table,
        format_reduction_table,
        format_statistics_table,
        format_sweep_summary,
        format_wear_table,
        results_kind,
        short_settled_window,
    )

    if reference and metric:
        raise click.UsageError("--reference and --metric print different tables; give one of them")
    with open_input(path) as ds:
        study = STUDIES[results_kind(ds)]
        text_of = study.text_only(metric)
        if text_of is not None:
            kind, needed = study.described, study.report_reads
            given = [name for name, on in ((f"--format {fmt}", fmt != "text"),
                                           ("--reference", bool(reference)),
                                           ("--metric", bool(metric)), ("--full", full)) if on]
            if given:
                raise click.UsageError(f"{given[0]}: {path} is {kind}, which report prints as "
                                       "text only")
            if needed:
                _needs(ds, path, needed, f"{kind}'s")
            if not quiet:
                click.echo(text_of(ds))
            return
        try:
            summary = (format_sweep_summary(ds, fmt) if fmt in ("text", "markdown")
                       and not (metric or reference) and design_dims(ds) else "")
            if summary and not full:
                text = summary
            elif metric:
                text = format_metric_table(ds, metric, fmt)
            elif study.table_report is not None:
                text = study.table_report()(ds, fmt, reference)
            elif reference:
                text = format_reduction_table(ds, reference, fmt)
            else:
                statistics = format_statistics_table(ds, fmt) if fmt in ("text", "markdown") else ""
                bushings = bushing_text(ds) if fmt in ("text", "markdown") else ""
                text = "\n\n".join(t for t in (statistics, format_wear_table(
                    ds, fmt, with_statistics=fmt in ("csv", "json")), bushings) if t)
            if summary and full:
                text = f"{summary}\n\n{text}"
        except SelectionError as exc:
            raise click.UsageError(str(exc)) from exc
        except ValueError as exc:
            _fail(f"{path}: {exc}", 2)
        short = short_settled_window(ds) if fmt == "text" else None
    if short:
        warnings.warn(f"{path}: {short}", ClearsweepWarning, stacklevel=1)
    if not quiet:
        click.echo(text)


@main.command("plot")
@click.argument("path", type=_InFile(exists=True, dir_okay=False))
@click.option("--kind", required=True, type=click.Choice(KINDS), help="Figure to draw.")
@click.option("-o", "--out", required=True, type=_OUT_FILE,
              help="Output file; the suffix (.png, .pdf, .svg) sets the format.")
@click.option("--select", "select_items", multiple=True, metavar="DIM=VALUE",
              help="Draw only the sweep cases with this coordinate value; DIM may be the "
                   "dotted config key, VALUE may carry a unit (B_clearance=0.25mm, "
                   "speed_rpm=60rpm) (repeatable).")
@click.option("--x", "x_axis", default=None, metavar="AXIS",
              help="Abscissa of time series: angle (crank angle [degree], the default) or "
                   "time [s]; of --kind bifurcation, the swept key, by its dimension or its "
                   "dotted config key (default: the only one); of --kind dynamics-map, the "
                   "swept key along the abscissa.")
@click.option("--y", "y_axis", default=None, metavar="KEY",
              help="--kind dynamics-map: the swept key along the ordinate, by its dimension "
                   "or its dotted config key.")
@click.option("--metric", default=None, metavar="NAME",
              help=f"Summary metric of --kind sweep [default: {DEFAULT_SWEEP_METRIC}].")
@click.option("--dpi", type=click.IntRange(*DPI_RANGE), default=FIGURE_DPI, show_default=True,
              help=f"Resolution of raster output, {DPI_RANGE[0]} to {DPI_RANGE[1]}.")
@click.option("--b10", is_flag=True, help="--kind reliability: draw each design's B10 with its "
                                          "interval as error bars instead of R(N).")
@click.option("--overwrite", is_flag=True,
              help="Replace an existing OUT that is not a figure clearsweep drew.")
@_quiet
def plot_command(path: str, kind: str, out: str, select_items: tuple[str, ...], x_axis: str,
                 y_axis: str | None, metric: str | None, dpi: int, b10: bool, overwrite: bool,
                 quiet: bool) -> None:
    """Draw a figure from the results file PATH."""
    from .analysis import SelectionError
    from .plotting import PlotError, plot

    if kind not in SWEPT_X_KINDS and x_axis is not None and x_axis not in X_AXES:
        raise click.BadParameter(f"{x_axis!r} is not one of {', '.join(map(repr, X_AXES))}"
                                 " (a swept key is the abscissa of --kind bifurcation and "
                                 "dynamics-map only)",
                                 param_hint="'--x'")
    _check_figure_suffix(out, "'-o' / '--out'")
    _check_figure(out, "-o/--out", [("the results file", path)], overwrite)
    with open_input(path) as ds:
        _check_plot_kind(ds, path, kind, metric)
        try:
            plot(ds, kind, out, select_items, x=x_axis, y=y_axis, metric=metric, dpi=dpi,
                 b10=b10)
        except (SelectionError, PlotError) as exc:
            raise click.UsageError(str(exc)) from exc
        except OSError as exc:      # as `run`: an output that cannot be written exits 1
            _fail(f"cannot write {out}: {_reason(exc)}", 1)
    _wrote(out, quiet)


def _check_plot_kind(ds: xr.Dataset, path: str, kind: str, metric: str | None) -> None:
    """A usage error where ``--kind`` asks for a figure of another kind of results file
    than ``path`` is, naming what the file is and the kinds that draw it
    (:attr:`clearsweep.studies.StudyKind.refusals`)."""
    from .analysis import results_kind

    problem = STUDIES[results_kind(ds)].refusal(kind, path, metric)
    if problem:
        raise click.UsageError(problem)


def _check_figure_suffix(path: str, option: str) -> None:
    if Path(path).suffix.lower() not in OUTPUT_SUFFIXES:
        raise click.BadParameter(f"{path!r}: the suffix must be one of "
                                 f"{', '.join(OUTPUT_SUFFIXES)}", param_hint=option)


def _series_selection(text: str | None) -> str | tuple[int, ...]:
    """``--keep-series`` -> run_sweep's ``keep_series``."""
    if not text:
        return ()
    if text.strip() == "all":
        return "all"
    try:
        return tuple(int(item) for item in text.split(",") if item.strip())
    except ValueError:
        raise click.BadParameter(f"{text!r}: 'all' or comma-separated case positions (0, 1, ...)",
                                 param_hint="--keep-series") from None


@main.command("sensitivity")
@click.argument("path", type=_InFile(exists=True, dir_okay=False))
@click.option("--metric", required=True, metavar="NAME",
              help="Summary variable to analyse (the ensemble mean where the file is an ensemble).")
@click.option("--select", "select_items", multiple=True, metavar="DIM=VALUE",
              help="Fix another dimension of NAME (e.g. joint=B); repeatable.")
@click.option("-o", "--out", "plot_path", type=_OUT_FILE, default=None,
              help="Also draw the indices with their intervals to this file (.png, .pdf, .svg).")
@click.option("--overwrite", is_flag=True,
              help="Replace an existing -o/--out file that is not a figure clearsweep drew.")
@_quiet
def sensitivity_command(path: str, metric: str, select_items: tuple[str, ...],
                        plot_path: str | None, overwrite: bool, quiet: bool) -> None:
    """First-order and total Sobol' indices of --metric over the inputs of the Saltelli sampling
    sweep PATH (``sweep: sample: method: saltelli``), with 95 % confidence intervals (SALib),
    the inputs ranked by ST. Warns on stderr, with a larger n to try, when an influential
    input's interval overlaps the next one's (too wide to rank them)."""
    from .analysis import SelectionError
    from .sensitivity import (
        SensitivityError,
        format_indices,
        indices_figure,
        save_figure,
        sweep_indices,
    )

    if plot_path:
        _check_figure_suffix(plot_path, "'-o' / '--out'")
        _check_figure(plot_path, "-o/--out", [("the results file", path)], overwrite)
    elif overwrite:
        raise click.UsageError("--overwrite acts on the -o/--out figure; give -o")
    with open_input(path) as ds:
        try:
            result = sweep_indices(ds, metric, select_items)
        except SelectionError as exc:
            raise click.UsageError(str(exc)) from exc
        except SensitivityError as exc:
            _fail(f"{path}: {exc}", 2)
    if not quiet:
        click.echo(format_indices(result))
    warning = result.ranking_warning()
    if warning:
        click.echo(f"clearsweep: warning: {path}: {warning}", err=True)
    if plot_path:
        try:
            save_figure(indices_figure(result), plot_path)
        except OSError as exc:
            _fail(f"cannot write {plot_path}: {_reason(exc)}", 1)
        _wrote(plot_path, quiet)


def _out_of_memory(exc: MemoryError, what: str, note: str = "") -> NoReturn:
    """A run that this machine could not hold (the estimate passed, with --allow-large or
    memory taken by others since): one error line, exit 1, no traceback."""
    detail = f" ({exc})" if str(exc) else ""
    _fail(f"out of memory: this machine could not hold the arrays of the run, {what}{detail}"
          f"{note}; free memory, or make the run smaller", 1)


def _fail(message: str, code: int) -> NoReturn:
    """Stop the command: one error line on stderr (:func:`error_line`) and exit ``code``."""
    raise CommandFailed(message, code)


#: The address schemes of a Dask scheduler that a sweep can reach from another process.
SCHEDULER_SCHEMES = ("tcp", "tls", "ws", "wss", "ucx")


def _check_scheduler(address: str) -> None:
    """Refuse a ``--scheduler`` address that no scheduler can have, before any work: Dask's
    own ValueError came as a traceback after the plan and the compile."""
    scheme, sep, rest = address.strip().rpartition("://")
    scheme = scheme if sep else "tcp"
    host, colon, port = rest.rpartition(":")
    if host.startswith("[") and host.endswith("]"):
        host = host[1:-1]
    problem = ("no address" if not address.strip()
               else f"unknown scheme {scheme!r} (known: {', '.join(SCHEDULER_SCHEMES)})"
               if scheme not in SCHEDULER_SCHEMES
               else "no ':PORT' after the host" if not colon
               else "no host" if not host or any(c.isspace() or c in "/?#@" for c in host)
               else f"a port of 1 to 65535 after the host, not {port!r}"
               if not (port.isdecimal() and 0 < int(port) <= 65535) else None)
    if problem:
        raise click.BadParameter(f"{address!r}: {problem}; expected [SCHEME://]HOST:PORT, e.g. "
                                 "tcp://127.0.0.1:8786", param_hint="'--scheduler'")


def _resume_command(command: str, config: str, out: str, overrides: tuple[str, ...]) -> str:
    """The command line that continues interrupted work: the same overrides, as they are
    part of what identifies it (every sweep case's hash, a life checkpoint's config)."""
    return shlex.join([*_program(), command, config, "-o", out, "--resume",
                       *(a for o in overrides for a in ("--set", o))])


def _program() -> list[str]:
    """The program as the user invoked it (``.venv/bin/clearsweep`` stays so, and a run by
    ``python -m clearsweep.cli`` prints that); ``clearsweep`` where it cannot be told."""
    argv0 = sys.argv[0] if sys.argv else ""
    name = Path(argv0).name
    if name.startswith("clearsweep") and not name.endswith(".py"):
        return [argv0]
    if Path(argv0).resolve() == Path(__file__).resolve():
        # the interpreter as a path from here where it lies below (.venv/bin/python)
        python = os.path.relpath(sys.executable) if Path(sys.executable).is_relative_to(
            Path.cwd()) else "python"
        return [python, "-m", "clearsweep.cli"]
    return ["clearsweep"]


@main.command("sweep")
@click.argument("config", type=_InFile(dir_okay=False))
@click.option("-o", "--out", type=_OUT_FILE,
              help="Output netCDF file [default: <config stem>.nc in the current folder]; "
                   "finished cases are kept in OUT.parts/ until it is written.")
@click.option("--workers", type=click.IntRange(min=1), default=None,
              help="Worker processes [default: all cores]; 1 runs the cases in this process.")
@click.option("--resume", is_flag=True,
              help="Continue an interrupted sweep: keep the cases in OUT.parts/, run the others.")
@click.option("--overwrite", is_flag=True,
              help="Delete the parts of an earlier sweep in OUT.parts/, and replace an existing "
                   "OUT that is not a clearsweep results file.")
@click.option("--discard-parts", is_flag=True,
              help="Delete the parts in OUT.parts/ that belong to another sweep (another sweep "
                   "file or other --set values); without it such parts make the sweep refuse.")
@click.option("--scheduler", metavar="ADDRESS", help="Run on this Dask distributed scheduler.")
@click.option("--dask-local", type=click.IntRange(min=1), metavar="N",
              help="Start a local Dask cluster of N single-thread worker processes for this sweep.")
@click.option("--set", "overrides", multiple=True, metavar="KEY=VALUE",
              help="Override a value of the base config (VALUE in YAML); repeatable.")
@click.option("--keep-parts", is_flag=True, help="Keep OUT.parts/ after writing OUT.")
@click.option("--allow-large", is_flag=True,
              help="Run cases beyond the bounds on one case's work and memory (4 GiB of arrays, "
                   "1e9 RK4 steps).")
@click.option("--no-progress", is_flag=True, help="Do not show the progress bar.")
@_quiet
@_dry_run
@click.option("-y", "--yes", is_flag=True,
              help=f"Run a sweep of more than {MAX_CASES:,} cases (refused without it).")
@click.option("--backend", type=click.Choice(SWEEP_BACKENDS), default="processes", show_default=True,
              help="processes: this process, a process pool or Dask (--workers, --scheduler, "
                   "--dask-local); cuda: batches on a CUDA device, one thread per case, "
                   "summaries only.")
@click.option("--keep-series", metavar="SELECTION",
              help="With --backend cuda: the cases whose time series are kept (run on the CPU "
                   "and stored in full): 'all' or comma-separated case positions in sweep order "
                   "(0-based).")
def sweep_command(config: str, out: str | None, workers: int | None, resume: bool, overwrite: bool,
                  discard_parts: bool, scheduler: str | None, dask_local: int | None, overrides: tuple[str, ...],
                  keep_parts: bool, allow_large: bool, no_progress: bool, quiet: bool, dry_run: bool,
                  yes: bool, backend: str, keep_series: str | None) -> None:
    """Run the parameter sweep described by CONFIG (YAML) and write one netCDF file.

    Exit status: 0 all cases ok (or skipped), 1 some cases failed (their
    status and message are in the file) or the output cannot be written,
    2 invalid config or options,
    130 interrupted (finished cases kept; rerun with --resume).
    """
    from .sweeping import PartStore, expand, parts_dir_for

    if scheduler is not None:
        _check_scheduler(scheduler)
    if scheduler and dask_local:
        raise click.UsageError("--scheduler and --dask-local both choose the Dask cluster; give one")
    if resume and overwrite:
        raise click.UsageError("--resume keeps the finished cases and --overwrite deletes them; "
                               "give one")
    if backend == "cuda" and (scheduler or dask_local):
        raise click.UsageError("--backend cuda runs on the device; --scheduler and --dask-local "
                               "choose a Dask cluster: give one")
    if keep_series and backend != "cuda":
        raise click.UsageError("--keep-series selects the cases of --backend cuda that keep their "
                               "time series (the processes backend stores what the sweep file's "
                               "store says)")
    series = _series_selection(keep_series)
    workers = _cap_workers(workers)
    dask_local = _cap_workers(dask_local, "--dask-local")
    given, out = out, out or f"{Path(config).stem}.nc"
    cluster = local_client = None
    if dry_run:
        plan = expand(config, overrides, allow_large=allow_large,
                      max_cases=None if yes else MAX_CASES, enumerate_cases=False)
        click.echo(plan.plan_text(dask_local or _plan_workers(plan, workers)))
        return
    if backend == "cuda":
        from .gpu import NoCudaDevice, device_name

        try:
            name = device_name()
        except NoCudaDevice as exc:
            _fail(str(exc), 2)
        if not quiet:
            click.echo(f"clearsweep: CUDA device: {name}", err=True)
    try:
        plan = expand(config, overrides, allow_large=allow_large,
                      max_cases=None if yes else MAX_CASES)
        _check_out(given, out, plan.input_files(), overwrite, resume, kind=store_kind(plan.store))
        cores = dask_local or (None if scheduler else _plan_workers(plan, workers))
        kept = PartStore(parts_dir_for(out)).kept_on_resume() if resume else set()
        replacing = _replacing(out, "sweep_config", plan.text)
        if not quiet:
            click.echo(f"clearsweep: {plan.describe(cores, kept)}", err=True)
        if not scheduler and (backend != "cuda" or series):
            # compile once here so that the workers load the cached kernel
            announce_compile(quiet, plan.runnable().values())
        client: Any = scheduler
        if dask_local:
            from distributed import Client, LocalCluster

            cluster = LocalCluster(n_workers=dask_local, threads_per_worker=1, processes=True,
                                   host="127.0.0.1", dashboard_address=None)
            client = local_client = Client(cluster)
        ds = _run_sweep_or_fail(plan, out, "sweep", config, overrides, workers=workers,
                                client=client, resume=resume, progress=not (no_progress or quiet),
                                overwrite=overwrite, keep_parts=keep_parts,
                                discard_parts=discard_parts, allow_large=allow_large,
                                backend=backend, keep_series=series)
        with ds:
            n, failed = ds.attrs["sweep_cases"], ds.attrs["sweep_failed"]
            skipped = ds.attrs["sweep_skipped"]
    finally:
        if local_client is not None:
            local_client.close()
        if cluster is not None:
            cluster.close()
    note = f" ({skipped} skipped)" if skipped else ""
    _wrote(out, quiet, f": {n} cases{note}{replacing}")
    if failed:
        _fail(f"{failed} of {n} cases failed{note}; see the status and message variables in {out}", 1)


if __name__ == "__main__":
    main(prog_name="clearsweep")
