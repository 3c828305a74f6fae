"""Inputs are never outputs: every command that writes a file refuses an output that is one of
its inputs (the config, a sweep's base file, a materials file, the results file it reads),
through a symbolic or a hard link too, and replaces an existing file only if clearsweep wrote
it, unless --overwrite (clearsweep/outputs.py).

Once, `clearsweep run same.yaml -o same.yaml` exited 0 and replaced the config with a netCDF
file; so did `life`, `sweep` and `plot` pointed at their inputs.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest
import yaml
from click.testing import CliRunner
from synthetic import one_case

from clearsweep.cli import main
from clearsweep.dataset import write_netcdf_atomic
from clearsweep.outputs import is_own_figure, is_results_file

#: A case of a few hundred RK4 steps with a materials file of its own.
CASE = {"name": "tiny", "materials_file": "mats.yaml",
        "joints": {"A": {"clearance": 0.0}, "B": {"clearance": 2.5e-4, "coating": "bronze"}},
        "wear": {"map": [8, 16]}, "solver": {"duration": 0.002}}
MATERIALS = {"bronze": {"youngs_modulus_Pa": {"value": 1.1e11, "source": "handbook"},
                        "poisson_ratio": {"value": 0.34, "source": "handbook"},
                        "friction_coefficient": {"value": 0.1, "source": "handbook"},
                        "wear_coefficient_m2_per_N": {"value": 1e-14, "source": "handbook"}}}
#: A life run of one block (1/50 s at 3000 r/min).
LIFE = ["--set", "mechanism.speed_rpm=3000", "--set", "life.max_blocks=1"]


@pytest.fixture
def files(tmp_path, monkeypatch) -> Path:
    """A folder with case.yaml (naming mats.yaml), an ensemble, a sweep over a base file,
    a results file and a Saltelli sample; the tests run inside it."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "mats.yaml").write_text(yaml.safe_dump(MATERIALS))
    (tmp_path / "case.yaml").write_text(yaml.safe_dump(CASE))
    (tmp_path / "ens.yaml").write_text(yaml.safe_dump({**CASE, "ensemble": {"members": 2}}))
    (tmp_path / "sweep.yaml").write_text(yaml.safe_dump(
        {"name": "s", "store": "summary", "base": "case.yaml",
         "sweep": {"grid": {"joints.B.clearance": [2.5e-4]}}}))
    write_netcdf_atomic(one_case(), tmp_path / "results.nc")
    from test_sensitivity import linear_sample

    linear_sample(8).to_netcdf(tmp_path / "sample.nc")
    return tmp_path


def invoke(*args: str):
    return CliRunner().invoke(main, list(args))


def one_error_line(result, *words: str) -> str:
    """The result's stderr is one `clearsweep: error:` line holding ``words``; no traceback."""
    assert result.exception is None or isinstance(result.exception, SystemExit), result.exception
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("clearsweep: error: "), result.output
    for word in words:
        assert word in lines[0], lines[0]
    return lines[0]


def _link(folder: Path, kind: str, name: str, target: str) -> str:
    if kind == "symlink":
        (folder / name).symlink_to(target)
    elif kind == "hardlink":
        os.link(folder / target, folder / name)
    return name if kind != "same" else target


#: (command line with OUT for the output, the input that OUT names, how OUT names it)
REFUSED = [
    (["run", "case.yaml", "-q", "-o", "OUT"], "case.yaml", "same"),
    (["run", "case.yaml", "-q", "-o", "OUT"], "case.yaml", "symlink"),
    (["run", "case.yaml", "-q", "-o", "OUT"], "case.yaml", "hardlink"),
    (["run", "case.yaml", "-q", "-o", "OUT", "--overwrite"], "mats.yaml", "same"),
    (["run", "ens.yaml", "-q", "--workers", "1", "-o", "OUT", "--overwrite"], "ens.yaml", "symlink"),
    (["life", "case.yaml", "-q", "-o", "OUT"], "case.yaml", "same"),
    (["life", "case.yaml", "-q", "-o", "OUT", "--overwrite"], "mats.yaml", "hardlink"),
    (["sweep", "sweep.yaml", "--workers", "1", "-o", "OUT"], "sweep.yaml", "same"),
    (["sweep", "sweep.yaml", "--workers", "1", "-o", "OUT", "--overwrite"], "case.yaml", "symlink"),
    (["sweep", "sweep.yaml", "--workers", "1", "-o", "OUT", "--overwrite"], "mats.yaml", "same"),
    (["plot", "results.nc", "--kind", "slider", "-o", "OUT", "--overwrite"], "results.nc", "symlink"),
    (["plot", "results.nc", "--kind", "slider", "-o", "OUT"], "results.nc", "hardlink"),
    (["sensitivity", "sample.nc", "--metric", "y", "-o", "OUT", "--overwrite"], "sample.nc",
     "symlink"),
]


@pytest.mark.parametrize("args, target, kind", REFUSED,
                         ids=[f"{a[0]}-{t}-{k}" for a, t, k in REFUSED])
def test_an_output_that_is_an_input_is_refused(files, args, target, kind):
    """Whatever --overwrite, an output that names an input (itself, or through a symbolic or
    a hard link) ends in one error line naming the option and the input, exit 2, and leaves
    the input as it was."""
    suffix = {"plot": ".png", "sensitivity": ".svg"}.get(args[0], ".nc")
    out = _link(files, kind, "out" + suffix, target)
    before = (files / target).read_bytes()
    option = "-o/--out"
    result = invoke(*[out if a == "OUT" else a for a in args])
    assert result.exit_code == 2, result.output
    one_error_line(result, f"{option} {out} ", target, "which this command reads")
    assert (files / target).read_bytes() == before
    assert (files / out).is_symlink() == (kind == "symlink")
    assert not list(files.glob(".*.tmp")) and not list(files.glob("*.parts"))


def test_the_default_output_of_a_config_named_like_it_is_refused(files):
    """`run case.nc` writes <stem>.nc by default: the config itself."""
    (files / "case.nc").write_bytes((files / "case.yaml").read_bytes())
    result = invoke("run", "case.nc", "-q")
    assert result.exit_code == 2, result.output
    one_error_line(result, "-o/--out (default) case.nc is the config file case.nc")
    assert (files / "case.nc").read_bytes() == (files / "case.yaml").read_bytes()


#: (command line with OUT for the output, the output's name, what the command writes there)
WRITERS = [
    (["run", "case.yaml", "-q", "-o", "OUT"], "out.nc", is_results_file),
    (["run", "ens.yaml", "-q", "--workers", "1", "-o", "OUT"], "out.nc", is_results_file),
    (["life", "case.yaml", "-q", "-o", "OUT", *LIFE], "out.nc", is_results_file),
    (["sweep", "sweep.yaml", "--workers", "1", "--no-progress", "-o", "OUT"], "out.nc",
     is_results_file),
    (["plot", "results.nc", "--kind", "slider", "-o", "OUT"], "out.png", is_own_figure),
    (["plot", "results.nc", "--kind", "slider", "-o", "OUT"], "out.pdf", is_own_figure),
    (["sensitivity", "sample.nc", "--metric", "y", "-o", "OUT"], "out.svg", is_own_figure),
]


@pytest.mark.parametrize("args, name, own", WRITERS, ids=[f"{a[0]}-{a[1]}-{n}" for a, n, own in WRITERS])
def test_an_existing_file_clearsweep_did_not_write_needs_overwrite(files, args, name, own):
    """A file that is not clearsweep's (here text, then a real figure or netCDF file that
    another program wrote) is replaced only with --overwrite; a file that clearsweep wrote is
    replaced as before."""
    out = files / name
    command = [name if a == "OUT" else a for a in args]
    foreign = b"my notes, not a results file\n"
    out.write_bytes(foreign)
    result = invoke(*command)
    assert result.exit_code == 2, result.output
    one_error_line(result, f" {name} exists and is not", "--overwrite")
    assert out.read_bytes() == foreign
    result = invoke(*command, "--overwrite")
    assert result.exit_code == 0, result.output
    assert own(out) and out.read_bytes() != foreign
    stamp = out.stat().st_mtime_ns
    os.utime(out, ns=(stamp - 10**9, stamp - 10**9))
    result = invoke(*command)                       # its own file: replaced as before
    assert result.exit_code == 0, result.output
    assert own(out) and out.stat().st_mtime_ns > stamp - 10**9


def test_files_of_the_same_format_from_elsewhere_are_not_clearsweeps(tmp_path):
    """A netCDF file without `source: clearsweep` and a figure matplotlib drew for someone else
    are not recognised as clearsweep's; every figure clearsweep draws is."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    from clearsweep.sensitivity import save_figure

    other = one_case()
    other.attrs["source"] = "another model"
    write_netcdf_atomic(other, tmp_path / "other.nc")
    assert not is_results_file(tmp_path / "other.nc")
    write_netcdf_atomic(one_case(), tmp_path / "ours.nc")
    assert is_results_file(tmp_path / "ours.nc")
    for suffix in (".png", ".pdf", ".svg"):
        fig = Figure()
        fig.add_subplot().plot([0, 1], [1, 0])
        fig.savefig(tmp_path / f"other{suffix}")
        assert not is_own_figure(tmp_path / f"other{suffix}")
        save_figure(fig, tmp_path / f"ours{suffix}")
        assert is_own_figure(tmp_path / f"ours{suffix}")
    # a clearsweep netCDF file named like a figure is not a figure
    write_netcdf_atomic(one_case(), tmp_path / "fake.png")
    assert not is_own_figure(tmp_path / "fake.png")


def test_sensitivity_overwrite_without_plot_is_a_usage_error(files):
    result = invoke("sensitivity", "sample.nc", "--metric", "y", "--overwrite")
    assert result.exit_code == 2 and "--overwrite acts on the -o/--out figure" in result.output


@pytest.mark.parametrize("command", [["run", "ens.yaml", "-q"], ["sweep", "sweep.yaml"]],
                         ids=["run", "sweep"])
def test_resume_onto_a_file_clearsweep_did_not_write_says_to_move_it(files, command):
    """--resume and --overwrite exclude each other: the message does not send the user from
    one refusal to the other."""
    (files / "out.nc").write_text("notes\n")
    result = invoke(*command, "--workers", "1", "-o", "out.nc", "--resume")
    assert result.exit_code == 2, result.output
    one_error_line(result, "out.nc exists and is not a clearsweep results file; move it away")
    assert (files / "out.nc").read_text() == "notes\n"


@pytest.mark.parametrize("args", [["run", "case.yaml", "-q", "-o", "OUT", "--overwrite"],
                                  ["plot", "results.nc", "--kind", "slider", "-o", "OUT",
                                   "--overwrite"]], ids=["run", "plot"])
def test_an_output_that_is_a_pipe_or_device_is_refused_even_with_overwrite(files, args):
    """The atomic write renames a new file over the path: `-o /dev/null` (run as root)
    replaced the device with a results file. A FIFO stands in for it here."""
    name = "pipe.png" if args[0] == "plot" else "pipe.nc"
    os.mkfifo(files / name)
    result = invoke(*[name if a == "OUT" else a for a in args])
    assert result.exit_code == 2, result.output
    one_error_line(result, f"{name} is not a regular file")
    assert (files / name).is_fifo()
