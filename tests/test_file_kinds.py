"""One file, one command: ``validate`` checks case and sweep files, and ``run``/``sweep``
given the other kind of file say which command fits (issue: "helpful either way")."""

from pathlib import Path

import pytest
from click.testing import CliRunner

from clearsweep.cli import main
from clearsweep.config import file_kind

CONFIGS = Path(__file__).resolve().parent.parent / "configs"
SWEEP = CONFIGS / "coating_clearance.yaml"
CASE = CONFIGS / "two_clearances.yaml"


def invoke(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def test_validate_prints_the_plan_of_the_main_sweep_file():
    result = invoke("validate", SWEEP)
    assert result.exit_code == 0, result.stderr
    text = result.stdout
    assert f"{SWEEP}: a valid sweep file" in text and f"clearsweep sweep {SWEEP}" in text
    assert "dimension B_coating (4): 'none', 'MoS2', 'lead', 'PTFE'" in text
    assert "dimension clearance_joints (2): 'B', 'AB'" in text
    # 6 revolutions at 150 r/min (2.4 s) at dt = 1e-5 per case, 48 cases: the steps, the
    # memory and the time estimate
    assert "one case: 240,000 RK4 steps; memory up to" in text
    assert "48 cases, 48 to simulate, 1.15e+07 RK4 steps: about" in text


def test_validate_a_sweep_file_applies_set_and_checks_every_case(tmp_path):
    result = invoke("validate", SWEEP, "--set", "solver.duration=0.02")
    assert result.exit_code == 0, result.stderr
    assert "one case: 2,000 RK4 steps" in result.stdout
    bad = tmp_path / "bad.yaml"
    bad.write_text(SWEEP.read_text().replace("[5.0e-5, 1.0e-4,", "[-5.0e-5, 1.0e-4,"))
    result = invoke("validate", bad)
    assert result.exit_code == 2 and result.stdout == ""
    assert result.stderr.startswith(f"clearsweep: error: {bad}: joints.B.clearance: got -5e-05")


def test_validate_a_case_config_names_its_work_on_stderr():
    result = invoke("validate", CASE)
    assert result.exit_code == 0, result.stderr
    assert result.stdout.startswith("name: two_clearances")       # the YAML alone on stdout
    assert result.stderr.startswith(f"clearsweep: {CASE}: a valid case config: 100,000 RK4 steps, "
                                    "memory up to")


@pytest.mark.parametrize("command", ["run", "life"])
def test_a_case_command_given_a_sweep_file_says_use_sweep(tmp_path, command):
    result = invoke(command, SWEEP, "-o", tmp_path / "out.nc")
    assert result.exit_code == 2
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"clearsweep: error: {SWEEP}: got a sweep file")
    assert f"run a sweep file with `clearsweep sweep {SWEEP}`" in lines[0]
    assert not (tmp_path / "out.nc").exists()


def test_sweep_given_a_case_config_says_use_run(tmp_path):
    result = invoke("sweep", CASE, "-o", tmp_path / "out.nc")
    assert result.exit_code == 2
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"clearsweep: error: {CASE}: got a case config "
                                                   "(top-level keys name, mechanism, joints, solver)")
    assert f"run a case config with `clearsweep run {CASE}`" in lines[0]
    assert not (tmp_path / "out.nc").exists()


@pytest.mark.parametrize("doc, kind", [
    ({"name": "x", "store": "full", "sweep": {}}, "sweep"),
    ({"base": "case.yaml"}, "sweep"),
    ({"name": "x", "joints": {}}, "case"),
    ({"name": "x"}, None),                       # both kinds admit it: the usual checks decide
    ({"mechanism": {}, "sweep": {}}, None),      # mixed: the unknown key is the error
    ({"joints": {}, "solverr": {}}, None),       # a misspelt key: its close match is the error
    ([1, 2], None),
])
def test_file_kind(doc, kind):
    assert file_kind(doc) == kind


def test_a_misspelt_key_keeps_its_close_match(tmp_path):
    path = tmp_path / "c.yaml"
    path.write_text("joints: {}\nsolverr: {}\n")
    result = invoke("run", path)
    assert result.exit_code == 2 and "did you mean 'solver'?" in result.stderr


def test_load_config_of_a_sweep_file_says_so(tmp_path):
    from clearsweep.config import ConfigError, load_config

    path = tmp_path / "s.yaml"
    path.write_text("sweep:\n  grid: {}\n")
    with pytest.raises(ConfigError) as info:
        load_config(path)
    assert str(info.value).startswith(f"{path}: got a sweep file (top-level keys sweep); "
                                      "expected a case config; run a sweep file with "
                                      f"`clearsweep sweep {path}`")
