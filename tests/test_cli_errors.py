"""One command-line behaviour: every error path of every command is one ``clearsweep: error:``
line on stderr with its exit code (2 bad input or options, 1 failed work, 130 interrupted),
the same option names for the same things, -q everywhere, "wrote" on stderr, and
--dry-run that plans without simulating or writing.

The commands are enumerated from the click group, so a new command is checked as it lands.
"""

from __future__ import annotations

import ast
import sys
import types
from pathlib import Path

import pytest
import xarray as xr
from click.testing import CliRunner

import clearsweep.cli as cli
from clearsweep.cli import main

COMMANDS = sorted(main.commands)
#: Commands that simulate, and so plan with --dry-run.
SIMULATING = ("life", "run", "sweep")

CASE = "name: c\njoints: {B: {clearance: 2.5e-4}}\nsolver: {duration: 0.002}\n"
ENSEMBLE = CASE + "ensemble: {members: 3, seed: 1}\n"
SWEEP = ("name: s\nbase:\n  joints: {B: {clearance: 2.5e-4}}\n  solver: {duration: 0.002}\n"
         "sweep:\n  grid:\n    joints.B.coating: [none, PTFE]\n")


@pytest.fixture
def files(tmp_path, monkeypatch):
    """A case, an ensemble case, a sweep file and a file that is no netCDF, in the current
    folder (``tmp_path``)."""
    monkeypatch.chdir(tmp_path)
    for name, text in (("case.yaml", CASE), ("ens.yaml", ENSEMBLE), ("s.yaml", SWEEP)):
        (tmp_path / name).write_text(text)
    (tmp_path / "junk.nc").write_bytes(b"not a netCDF file")
    return tmp_path


def invoke(*args) -> object:
    return CliRunner().invoke(main, [str(a) for a in args])


def assert_error(result, code: int, *words: str) -> str:
    """``result`` exited ``code`` with exactly one error line in the one format, last on
    stderr, naming ``words`` (any line before it is one of clearsweep's, e.g. what it
    wrote); no usage block, no click "Error:", no traceback."""
    kind = "interrupted" if code == 130 else "error"
    assert result.exit_code == code, (result.exit_code, result.output)
    assert isinstance(result.exception, SystemExit), result.exception
    lines = result.stderr.splitlines()
    assert lines and all(line.startswith("clearsweep: ") for line in lines), lines
    errors = [line for line in lines if line.startswith(("clearsweep: error", "clearsweep: interr"))]
    assert errors == lines[-1:] and errors[0].startswith(f"clearsweep: {kind}: "), lines
    assert "Usage:" not in result.output and "Error:" not in result.output
    for word in words:
        assert word in errors[0], (word, errors[0])
    return result.stderr


@pytest.mark.parametrize("command", COMMANDS)
def test_every_command_has_help_quiet_and_one_line_usage_errors(command):
    helped = invoke(command, "--help")
    assert helped.exit_code == 0 and helped.stderr == ""
    assert "-q, --quiet" in helped.stdout
    assert ("--dry-run" in helped.stdout) == (command in SIMULATING)
    assert "--output" not in helped.stdout          # -o/--out names every output file
    assert_error(invoke(command, "--no-such-option"), 2, "no such option '--no-such-option'",
                 f"(see 'clearsweep {command} --help')")
    # the command called on its own (a script, a test) reports the same way
    alone = CliRunner().invoke(main.commands[command], ["--no-such-option"], prog_name=command)
    assert_error(alone, 2, "no such option '--no-such-option'", f"(see '{command} --help')")


# (args, exit code, words of the error line); files from the `files` fixture
USAGE_ERRORS = [
    (["frob"], 2, "no such command 'frob'", "(see 'clearsweep --help')"),
    (["run"], 2, "missing argument 'CONFIG' (see 'clearsweep run --help')"),
    (["report"], 2, "missing argument 'PATH'"),
    (["materials", "extra"], 2, "unexpected extra argument (extra)"),
    (["run", "case.yaml", "--workers", "0"], 2, "invalid value for '--workers'"),
    (["plot", "junk.nc", "--kind", "nope", "-o", "f.png"], 2, "invalid value for '--kind'"),
    (["plot", "junk.nc", "--kind", "slider"], 2, "missing option '-o' / '--out'"),
    (["plot", "junk.nc", "--kind", "slider", "-o", "f.gif"], 2, "'f.gif': the suffix must be"),
    (["sensitivity", "junk.nc", "--metric", "y", "-o", "f.gif"], 2, "'-o' / '--out'", "f.gif"),
    (["sensitivity", "junk.nc"], 2, "missing option '--metric'"),
    (["report", "missing.nc"], 2, "'missing.nc' does not exist"),
    (["report", "junk.nc"], 2, "'junk.nc' is not a results file"),
    (["report", "junk.nc", "--reference", "a=1", "--metric", "m"], 2, "give one of them"),
    (["sweep", "s.yaml", "--resume", "--overwrite"], 2, "give one"),
    (["sweep", "s.yaml", "--scheduler", "tcp://x:1", "--dask-local", "2"], 2, "give one"),
    (["sweep", "s.yaml", "--keep-series", "1"], 2, "--keep-series selects the cases"),
    (["sweep", "s.yaml", "--backend", "cuda", "--keep-series", "x"], 2, "--keep-series"),
    (["run", "case.yaml", "--resume"], 2, "act on the parts of an ensemble"),
    (["run", "ens.yaml", "--resume", "--overwrite"], 2, "give one"),
    (["validate", "missing.yaml"], 2, "missing.yaml"),
    (["run", "s.yaml"], 2, "got a sweep file", "clearsweep sweep s.yaml"),
    (["life", "s.yaml", "--dry-run"], 2, "got a sweep file"),
    (["sweep", "case.yaml", "--dry-run"], 2, "case.yaml"),
    (["run", "case.yaml", "--set", "solver.dt=-1"], 2, "solver.dt: got -1"),
    (["life", "case.yaml", "--set", "life.cycles=0"], 2, "life.cycles: got 0"),
]


@pytest.mark.parametrize("args, code, words", [(a, c, w) for a, c, *w in USAGE_ERRORS],
                         ids=[" ".join(a) for a, *_ in USAGE_ERRORS])
def test_usage_and_input_errors_are_one_line_exit_2(files, args, code, words):
    assert_error(invoke(*args), code, *words)
    assert sorted(p.name for p in files.iterdir()) == ["case.yaml", "ens.yaml", "junk.nc", "s.yaml"]


def _life_file(path: Path, **attrs) -> Path:
    """A file that ``report`` recognises as a life run (``attrs`` empty) or as a
    reliability or life sweep (``sweep_store``)."""
    ds = (xr.Dataset({"stop_reason": ((), "cycles"), "x": ("cycle", [1.0])}) if not attrs
          else xr.Dataset({"b10": (("d", "limit"), [[1.0]]), "x": ("d", [1.0])}, attrs=attrs))
    ds.to_netcdf(path)
    return path


@pytest.mark.parametrize("kind", ["life run", "reliability sweep", "life sweep"])
@pytest.mark.parametrize("option", [["--format", "csv"], ["--format", "json"],
                                    ["--format", "markdown"], ["--reference", "joint=B"],
                                    ["--full"]])
def test_report_refuses_by_name_what_a_text_only_file_ignores(tmp_path, kind, option):
    """report printed a life file's text whatever --format, --reference or --full said."""
    attrs = {} if kind == "life run" else {"sweep_store": kind.split()[0]}
    path = _life_file(tmp_path / "l.nc", **attrs)
    named = " ".join(option) if option[0] == "--format" else option[0]
    assert_error(invoke("report", path, *option), 2, f"{named}: {path} is a {kind}", "text only")


def test_report_refuses_metric_for_a_life_run(tmp_path):
    path = _life_file(tmp_path / "l.nc")
    assert_error(invoke("report", path, "--metric", "x"), 2, "--metric: ", "a life run")


@pytest.fixture
def no_compile(monkeypatch):
    monkeypatch.setattr(cli, "announce_compile", lambda *a, **k: None)


def test_a_life_run_stopped_by_a_block_exits_1(files, monkeypatch, no_compile):
    """life exited 0 when a block stopped early (status other than ok)."""
    import clearsweep.service_life as service_life

    stopped = xr.Dataset({"stop_reason": ((), "block_status:diverged"), "x": ("cycle", [1.0])})
    monkeypatch.setattr(service_life, "life", lambda cfg, **kwargs: stopped)
    monkeypatch.setattr(service_life, "life_summary_text", lambda ds: "life summary")
    result = invoke("life", "case.yaml", "-o", "l.nc")
    stderr = assert_error(result, 1, "life run stopped: block_status:diverged", "l.nc")
    # the plan's time first, as a sweep prints its plan
    assert stderr.startswith("clearsweep: a life run of at most 200 blocks: ")
    assert result.stdout == "life summary\n" and "\nclearsweep: wrote l.nc\n" in stderr
    assert (files / "l.nc").exists()


def test_an_interrupted_case_is_one_line_exit_130(files, monkeypatch):
    def interrupted(cfg, allow_large=False):
        raise KeyboardInterrupt

    monkeypatch.setitem(sys.modules, "clearsweep.simulation", types.SimpleNamespace(
        simulate=interrupted, preflight=lambda cfg, allow_large=False, seat=True: None,
        kernel_needs_compiling=lambda method="rk4", build=None: False,
        prepare_kernel=lambda method="rk4", build=None: 0.0))
    assert_error(invoke("run", "case.yaml", "-o", "o.nc"), 130, "stopped by Ctrl-C")
    assert not (files / "o.nc").exists()


def _sweep_failures():
    from clearsweep.sweeping import StoreError, SweepFailed, SweepInterrupted

    return [
        (StoreError("o.parts belongs to another sweep"), 2, ["o.parts belongs to another sweep"]),
        (SweepFailed("every worker died"), 1, ["every worker died"]),
        (OSError(28, "No space left on device", "o.nc"), 1, ["cannot write o.nc: the disk is full"]),
        (KeyboardInterrupt(), 130, ["before any case finished"]),
        (SweepInterrupted(1, 2, Path("o.nc.parts")), 130,
         ["1 of 2 cases are finished and kept in o.nc.parts; continue with: clearsweep "]),
    ]


@pytest.mark.parametrize("failure, code, words", _sweep_failures(),
                         ids=["store", "failed", "oserror", "ctrl-c", "interrupted"])
@pytest.mark.parametrize("command", ["sweep", "run"])
def test_an_ensemble_run_fails_as_a_sweep_does(files, monkeypatch, no_compile, command, failure,
                                               code, words):
    """`run` of an ensemble handled only OSError (without the kept parts) and named no
    --resume command as `sweep` does."""
    import clearsweep.sweeping as sweeping

    def fail(*args, **kwargs):
        raise failure

    monkeypatch.setattr(sweeping, "run_sweep", fail)
    config = "s.yaml" if command == "sweep" else "ens.yaml"
    line = assert_error(invoke(command, config, "-o", "o.nc", "--set", "name=x", "-q"), code,
                        *words)
    if "continue with" in line:
        assert line.endswith(f"clearsweep {command} {config} -o o.nc --resume --set name=x\n")


def test_sweep_failed_cases_exit_1_after_saying_what_it_wrote(files, monkeypatch, no_compile):
    import clearsweep.sweeping as sweeping

    done = xr.Dataset(attrs={"sweep_cases": 2, "sweep_failed": 1, "sweep_skipped": 0})
    monkeypatch.setattr(sweeping, "run_sweep", lambda *a, **k: done)
    result = invoke("sweep", "s.yaml", "-o", "o.nc", "-q")
    assert result.exit_code == 1 and result.stdout == ""
    assert result.stderr == ("clearsweep: error: 1 of 2 cases failed; see the status and message "
                             "variables in o.nc\n")
    loud = invoke("sweep", "s.yaml", "-o", "o.nc", "--no-progress")
    assert loud.stderr.splitlines()[-2:] == ["clearsweep: wrote o.nc: 2 cases",
                                             "clearsweep: error: 1 of 2 cases failed; see the "
                                             "status and message variables in o.nc"]


@pytest.fixture
def nothing_runs(monkeypatch):
    """Simulating, compiling or running a sweep or a life run fails the test."""
    import clearsweep.service_life as service_life
    import clearsweep.sweeping as sweeping

    def forbidden(*args, **kwargs):
        raise AssertionError("--dry-run ran something")

    monkeypatch.setattr(cli, "announce_compile", forbidden)
    monkeypatch.setattr(sweeping, "run_sweep", forbidden)
    monkeypatch.setattr(service_life, "life", forbidden)
    monkeypatch.setitem(sys.modules, "clearsweep.simulation", types.SimpleNamespace(
        simulate=forbidden, kernel_needs_compiling=forbidden, prepare_kernel=forbidden,
        # the checks a run makes before it starts, which compile and run nothing
        preflight=lambda cfg, allow_large=False, seat=True: None))


@pytest.mark.parametrize("args, words", [
    (["run", "case.yaml"], ["case.yaml: one case, 200 RK4 steps, memory up to", "on one core"]),
    (["run", "ens.yaml", "--workers", "1"], ["dimension member (3)", "3 cases, 3 to simulate",
                                            "600 RK4 steps", "on 1 worker "]),
    (["sweep", "s.yaml", "--workers", "1"], ["dimension B_coating (2): 'none', 'PTFE'",
                                            "2 cases, 2 to simulate, 400 RK4 steps"]),
    (["life", "case.yaml"], ["case.yaml: a life run to 1e+06 revolutions, at most 200 blocks",
                             "at most 2e+07 RK4 steps"]),
], ids=["run", "ensemble", "sweep", "life"])
def test_dry_run_prints_the_plan_and_writes_nothing(files, nothing_runs, args, words):
    result = invoke(*args, "-o", "o.nc", "--dry-run")
    assert result.exit_code == 0 and result.stderr == "", result.output
    for word in words:
        assert word in result.stdout, (word, result.stdout)
    assert "us per step" in result.stdout
    assert sorted(p.name for p in files.iterdir()) == ["case.yaml", "ens.yaml", "junk.nc", "s.yaml"]


def test_quiet_prints_nothing(files):
    for args in (["validate", "case.yaml"], ["validate", "s.yaml"], ["materials"]):
        loud, quiet = invoke(*args), invoke(*args, "-q")
        assert loud.exit_code == quiet.exit_code == 0 and loud.output
        assert quiet.output == "", args


def test_cli_has_one_error_format():
    """No string in cli.py (docstrings aside) spells an error line: error_line() is the one
    place, and it writes "clearsweep: {kind}: ...". click's own exits are not called."""
    source = Path(cli.__file__).read_text()
    tree = ast.parse(source)
    docstrings = {id(node.body[0].value) for node in ast.walk(tree)
                  if isinstance(node, (ast.Module, ast.FunctionDef, ast.ClassDef))
                  and node.body and isinstance(node.body[0], ast.Expr)}
    texts = [node.value for node in ast.walk(tree)
             if isinstance(node, ast.Constant) and isinstance(node.value, str)
             and id(node) not in docstrings]
    assert not [t for t in texts if "error:" in t.lower() or "usage:" in t.lower()]
    assert "ctx.exit(" not in source and source.count("sys.exit(") == 1
