"""The command-line interface through its real entry points: exit codes, messages, files."""

import errno
import re
import shutil
import subprocess
import sys
import types
from pathlib import Path

import click
import pytest
import xarray as xr
import yaml
from click.testing import CliRunner

from clearsweep import __version__
from clearsweep.cli import main
from clearsweep.config import ConfigError, load_config
from clearsweep.core.jointset import label, named
from clearsweep.params import build_of

# (name, file text or None for the --set case, overrides, key, value received)
BAD_INPUTS = [
    ("unknown_key", "joints:\n  A:\n    clearence: 0.001\n", (), "joints.A.clearence", "0.001"),
    ("unknown_material", "joints:\n  B:\n    coating: ptfe\n", (), "joints.B.coating", "'ptfe'"),
    ("negative_clearance", "joints:\n  A:\n    clearance: -2.5e-4\n", (), "joints.A.clearance", "-0.00025"),
    ("ball_not_smaller", "joints:\n  B:\n    clearance: 0.015\n", (), "joints.B.clearance", "0.015"),
    ("dt_zero", "solver:\n  dt: 0\n", (), "solver.dt", "0"),
    ("dt_negative_set", "name: x\n", ("solver.dt=-1e-5",), "solver.dt", "-1e-05"),
    ("string_for_number", "mechanism:\n  speed_rpm: fast\n", (), "mechanism.speed_rpm", "'fast'"),
    ("malformed_yaml", "solver:\n  dt: [1.0e-5\n", (), "line ", "'dt: [1.0e-5'"),
    ("empty_file", "", (), "", "an empty file"),
]
EXTRA_WORDS = {"unknown_key": "did you mean 'joints.A.clearance'?",
               "unknown_material": "did you mean 'PTFE'?",
               "ball_not_smaller": "joints.B.socket_radius"}


@pytest.fixture
def fake_run(monkeypatch):
    """Stand-ins for the simulation and the summary, recording what they were given."""
    calls = []

    def simulate(cfg, allow_large=False):
        calls.append(cfg)
        if cfg.name == "unstable":
            raise ConfigError("solver.dt", cfg.solver.dt, "a step below the stability limit")
        status = "ok" if cfg.name != "diverges" else "diverged at t = 0.01 s"
        return xr.Dataset({"slider_position": ("time", [0.3, 0.31]), "status": ((), status)},
                          coords={"time": [0.0, 0.1]})

    monkeypatch.setitem(sys.modules, "clearsweep.simulation", types.SimpleNamespace(
        simulate=simulate, preflight=lambda cfg, allow_large=False, seat=True: None,
        kernel_needs_compiling=lambda method="rk4", build=None: False,
        prepare_kernel=lambda method="rk4", build=None: 0.0))
    monkeypatch.setitem(sys.modules, "clearsweep.analysis", types.SimpleNamespace(
        run_summary_text=lambda ds: f"summary: status {ds['status'].item()}"))
    return calls


def invoke(args, cwd):
    with pytest.MonkeyPatch.context() as mp:
        mp.chdir(cwd)
        return CliRunner().invoke(main, [str(a) for a in args])


def check_error(rc, stderr, path, key, value, words, out):
    assert rc == 2, stderr
    assert stderr.startswith(f"clearsweep: error: {path}: {key}"), stderr
    assert f"got {value}" in stderr and words in stderr
    assert not out.exists()


@pytest.mark.parametrize("name, text, overrides, key, value", BAD_INPUTS, ids=[b[0] for b in BAD_INPUTS])
@pytest.mark.parametrize("command", ["run", "validate"])
def test_bad_input_exit_2(tmp_path, fake_run, command, name, text, overrides, key, value):
    path = tmp_path / f"{name}.yaml"
    path.write_text(text)
    out = tmp_path / "out.nc"
    args = [command, path, *(["-o", out] if command == "run" else [])]
    args += [a for o in overrides for a in ("--set", o)]
    result = invoke(args, tmp_path)
    check_error(result.exit_code, result.stderr, path, key, value, EXTRA_WORDS.get(name, ""), out)
    assert result.stdout == "" and fake_run == []  # nothing computed
    assert list(tmp_path.iterdir()) == [path]


def _entry_points():
    """``python -m clearsweep.cli`` and the installed console script (beside the interpreter or on PATH)."""
    script = shutil.which("clearsweep", path=str(Path(sys.executable).parent)) or shutil.which("clearsweep")
    return [[sys.executable, "-m", "clearsweep.cli"]] + ([[script]] if script else [])


@pytest.mark.parametrize("name", ["unknown_material", "malformed_yaml", "negative_clearance"])
@pytest.mark.parametrize("entry", _entry_points(), ids=lambda e: e[-1].rsplit("/", 1)[-1])
def test_bad_input_exit_2_subprocess(tmp_path, entry, name):
    _, text, overrides, key, value = next(b for b in BAD_INPUTS if b[0] == name)
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    out = tmp_path / "out.nc"
    proc = subprocess.run([*entry, "run", str(path), "-o", str(out)], capture_output=True, text=True,
                          timeout=60)
    check_error(proc.returncode, proc.stderr, path, key, value, EXTRA_WORDS.get(name, ""), out)
    assert "Traceback" not in proc.stderr and proc.stdout == ""


def test_run_writes_default_output_and_summary(tmp_path, fake_run):
    (tmp_path / "cases").mkdir()
    path = tmp_path / "cases" / "two_clearances.yaml"
    path.write_text("joints:\n  A: {clearance: 2.5e-4}\n  B: {clearance: 2.5e-4}\n")
    result = invoke(["run", path, "--set", "joints.B.coating=PTFE", "--set", "solver.baumgarte=[50,50]"],
                    tmp_path)
    assert result.exit_code == 0, result.output
    out = tmp_path / "two_clearances.nc"
    assert "summary: status ok" in result.stdout
    assert result.stderr == f"clearsweep: wrote {out.name}\n"
    assert fake_run == [load_config(path, ["joints.B.coating=PTFE", "solver.baumgarte=[50,50]"])]
    with xr.open_dataset(out) as ds:
        assert ds["status"].item() == "ok"


def run_case(tmp_path, text, *options):
    """``clearsweep run c.yaml -o r.nc OPTIONS`` in ``tmp_path``: (result, config path, output path)."""
    path, out = tmp_path / "c.yaml", tmp_path / "r.nc"
    path.write_text(text)
    return invoke(["run", path, "-o", out, *options], tmp_path), path, out


def test_run_quiet_prints_nothing(tmp_path, fake_run):
    result, _, out = run_case(tmp_path, "name: quiet\n", "--quiet")
    assert result.exit_code == 0 and result.output == ""
    assert out.exists()


def test_run_status_not_ok_keeps_file_exits_1(tmp_path, fake_run):
    result, _, out = run_case(tmp_path, "name: diverges\n")
    assert result.exit_code == 1
    assert "diverged at t = 0.01 s" in result.stderr
    with xr.open_dataset(out) as ds:
        assert ds["status"].item() == "diverged at t = 0.01 s"


def test_config_error_from_simulation_exit_2_no_file(tmp_path, fake_run):
    result, path, _ = run_case(tmp_path, "name: unstable\nsolver: {dt: 1.0e-3}\n")
    assert result.exit_code == 2
    assert result.stderr.startswith(f"clearsweep: error: {path}: solver.dt: got 0.001; expected a step")
    assert list(tmp_path.iterdir()) == [path]


def test_unwritable_output_exit_1_without_traceback(tmp_path, fake_run, monkeypatch):
    import clearsweep.dataset as dataset

    def read_only(ds, path, *args, **kwargs):
        raise PermissionError(errno.EACCES, "Permission denied", str(path))

    monkeypatch.setattr(dataset, "write_netcdf_atomic", read_only)
    result, path, out = run_case(tmp_path, "name: ok\n")
    assert result.exit_code == 1 and isinstance(result.exception, SystemExit), result.output
    assert result.stderr.startswith(f"clearsweep: error: cannot write {out}: Permission denied")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.yaml"]


def test_an_output_under_a_file_is_refused_before_the_run(tmp_path, fake_run):
    """Before: the whole run, then "cannot write ...: File exists" (exit 1)."""
    result, path, _ = run_case(tmp_path, "name: ok\n")
    out = path / "r.nc"                         # its folder is a file
    result = invoke(["run", path, "-o", out], tmp_path)
    assert result.exit_code == 2 and isinstance(result.exception, SystemExit), result.output
    assert result.stderr == (f"clearsweep: error: -o/--out {out}: {path} is a file, not a "
                             "folder; choose an output in a folder\n")
    assert len(fake_run) == 1           # the first run_case's only: nothing ran for this one


def test_config_error_in_any_subcommand_exit_2(monkeypatch):
    @click.command()
    def boom():
        raise ConfigError("wear.map", [0, 1], "a list of 2 integers >= 1", "s.yaml")

    monkeypatch.setitem(main.commands, "boom", boom)
    result = CliRunner().invoke(main, ["boom"])
    assert result.exit_code == 2
    assert result.stderr == ("clearsweep: error: s.yaml: wear.map: got [0, 1]; "
                             "expected a list of 2 integers >= 1\n")


def test_other_exceptions_propagate(tmp_path, monkeypatch):
    def simulate(cfg, allow_large=False):
        raise RuntimeError("kernel exploded")

    monkeypatch.setitem(sys.modules, "clearsweep.simulation", types.SimpleNamespace(
        simulate=simulate, preflight=lambda cfg, allow_large=False, seat=True: None,
        kernel_needs_compiling=lambda method="rk4", build=None: False,
        prepare_kernel=lambda method="rk4", build=None: 0.0))
    result, _, out = run_case(tmp_path, "name: x\n")
    assert result.exit_code != 0 and isinstance(result.exception, RuntimeError)
    assert not out.exists()


def test_validate_prints_resolved_yaml(tmp_path):
    path = tmp_path / "c.yaml"
    path.write_text("joints:\n  B: {clearance: 0.00025}\n")
    result = invoke(["validate", path, "--set", "joints.B.coating=PTFE"], tmp_path)
    assert result.exit_code == 0, result.stderr
    printed = yaml.safe_load(result.stdout)
    assert load_config(printed) == load_config(path, ["joints.B.coating=PTFE"])
    assert printed["joints"]["B"]["coating"] == "PTFE" and printed["solver"]["dt"] == 1e-5


def test_materials_lists_sources(tmp_path):
    result = CliRunner().invoke(main, ["materials"])
    assert result.exit_code == 0
    assert "PTFE" in result.stdout and "Jing & Liu 2023" in result.stdout and "(assumed)" in result.stdout
    user = tmp_path / "m.yaml"
    user.write_text("lead:\n  friction_coefficient: {value: 0.2, source: lab}\n")
    result = CliRunner().invoke(main, ["materials", "-m", str(user)])
    assert result.exit_code == 0 and "lead.friction_coefficient: lab" in result.stdout
    user.write_text("lead:\n  friction_coefficient: {value: -0.2, source: lab}\n")
    result = CliRunner().invoke(main, ["materials", "-m", str(user)])
    assert result.exit_code == 2
    assert result.stderr.startswith(f"clearsweep: error: {user}: lead.friction_coefficient.value: got -0.2")


def test_version_and_help_list_every_command():
    assert CliRunner().invoke(main, ["--version"]).stdout.strip() == f"clearsweep, version {__version__}"
    for args in (["--help"], []):           # a bare `clearsweep` prints its help too
        result = CliRunner().invoke(main, args)
        assert result.exit_code == 0 and result.stderr == ""
        listed = result.stdout.split("Commands:\n", 1)[1].splitlines()
        assert sorted(line.split()[0] for line in listed) == sorted(main.commands)


def test_help_names_every_joint_of_the_mechanism():
    """The help describes the mechanism as it is: clearance in the bearing O, the spherical
    joints A and B and the guide P (it once spoke of spherical joints only)."""
    from clearsweep.core.joints import JOINTS

    text = " ".join(CliRunner().invoke(main, ["--help"]).stdout.split("Options:")[0].split())
    for joint in JOINTS:
        assert re.search(rf"\b{joint.name}\b", text), joint.name
    assert "bearing O" in text and "guide P" in text


def test_a_broken_module_is_an_error_not_an_unknown_command(tmp_path, monkeypatch):
    """A plotting module that cannot be imported (a broken matplotlib) fails the command
    that needs it with its ImportError; it is not hidden as "No such command 'plot'"."""
    path = tmp_path / "r.nc"
    path.write_bytes(b"")
    monkeypatch.setitem(sys.modules, "clearsweep.plotting", None)   # import fails
    result = CliRunner().invoke(main, ["plot", str(path), "--kind", "slider", "-o",
                                       str(tmp_path / "f.png")])
    assert result.exit_code != 0
    assert "No such command" not in result.output
    assert isinstance(result.exception, ImportError)
    # the commands that do not need it still run
    assert CliRunner().invoke(main, ["materials"]).exit_code == 0


@pytest.mark.slow
def test_run_end_to_end(tmp_path):
    path = tmp_path / "short.yaml"
    path.write_text("joints:\n  B: {clearance: 2.5e-4, coating: PTFE}\n"
                    "solver: {duration: 2.0e-3, save_every: 10}\n")
    proc = subprocess.run([sys.executable, "-m", "clearsweep.cli", "run", str(path), "-o",
                           str(tmp_path / "short.nc")], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    with xr.open_dataset(tmp_path / "short.nc") as ds:
        assert ds["status"].item() == "ok"
        assert yaml.safe_load(ds.attrs["config"])["joints"]["B"]["coating"] == "PTFE"


@pytest.mark.parametrize("text, words", [
    ("solver: {dt: 1.0e-5}\nsolver: {dt: 2.0e-5}\n", "got the key 'solver' a second time"),
    ("x: " + "[" * 20000 + "]" * 20000 + "\n", "levels of nesting"),
], ids=["duplicate_key", "deep_nesting"])
@pytest.mark.parametrize("command", ["run", "validate"])
def test_hostile_yaml_is_one_error_line_exit_2(tmp_path, fake_run, command, text, words):
    path = tmp_path / "c.yaml"
    path.write_text(text)
    result = invoke([command, path, *(["-o", tmp_path / "o.nc"] if command == "run" else [])], tmp_path)
    assert result.exit_code == 2, result.output
    assert result.stderr.startswith(f"clearsweep: error: {path}: line ") and words in result.stderr
    assert result.stderr.count("\n") == 1 and fake_run == []


def test_full_disk_during_the_write_is_one_error_line_and_no_file(tmp_path, fake_run, monkeypatch):
    """netCDF-C reports a full disk as RuntimeError("NetCDF: HDF error"), after writing part of it."""
    real = xr.Dataset.dump_to_store      # what dataset.write_netcdf_atomic writes through

    def full(self, store, *args, **kwargs):
        real(self, store, *args, **kwargs)
        raise RuntimeError("NetCDF: HDF error")

    monkeypatch.setattr(xr.Dataset, "dump_to_store", full)
    result, path, out = run_case(tmp_path, "name: ok\n")
    assert result.exit_code == 1 and isinstance(result.exception, SystemExit), result.output
    assert result.stderr.startswith(f"clearsweep: error: cannot write {out}: NetCDF: HDF error")
    assert result.stderr.count("\n") == 1
    assert list(tmp_path.iterdir()) == [path]


def test_run_says_when_it_compiles_and_times_stepping_only(tmp_path, monkeypatch):
    """A cold kernel is announced on stderr and compiled before the timed run, so that the
    run's wall time (and steps/s) counts stepping only."""
    import clearsweep.simulation as simulation

    calls = []
    monkeypatch.setattr(simulation, "kernel_needs_compiling", lambda method="rk4", build=None: True)
    real = simulation.prepare_kernel
    monkeypatch.setattr(simulation, "prepare_kernel",
                        lambda method="rk4", build=None: calls.append((method, build)) or real(method, build))
    cfg = tmp_path / "c.yaml"
    cfg.write_text("joints: {A: {clearance: 2.5e-4}, B: {clearance: 2.5e-4}}\n"
                   "solver: {duration: 0.01}\n")
    result = CliRunner().invoke(main, ["run", str(cfg), "-o", str(tmp_path / "o.nc")])
    assert result.exit_code == 0, result.output
    build = build_of(named("A", "B"))
    assert f"compiling the kernel build that allows clearance at {label(build)} (once, about" in result.stderr
    # compiled before the run: the integrator asked for, built for the case's joint set
    assert calls and set(calls) == {("rk4", build)}
    quiet = CliRunner().invoke(main, ["run", str(cfg), "-q", "-o", str(tmp_path / "q.nc")])
    assert quiet.exit_code == 0 and "compiling" not in quiet.stderr
