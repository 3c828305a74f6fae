"""Messages that diagnose what the user did (issue: a user's first hour, round 2)."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest
import xarray as xr
from click.testing import CliRunner

from clearsweep import cli
from clearsweep.analysis.selection import MAX_OFFER_CHARS, choice_message
from clearsweep.cli import main
from clearsweep.config import load_config
from clearsweep.service_life import life, life_stop_hint, life_summary_text
from clearsweep.variables import format_length

ROOT = Path(__file__).resolve().parents[1]
LIFE = str(ROOT / "configs" / "life.yaml")
#: One short block of configs/life.yaml.
SHORT = ["life.max_blocks=1", "mechanism.speed_rpm=3000", "wear.map=[12, 24]"]


def invoke(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def test_validate_of_a_results_file_says_it_is_one_not_a_size_limit(tmp_path):
    path = tmp_path / "x.nc"
    xr.Dataset({"a": ("t", [1.0])}).to_netcdf(path, engine="netcdf4")
    result = invoke("validate", path)
    assert result.exit_code == 2
    line = result.stderr.strip()
    assert line.startswith("clearsweep: error: ") and "\n" not in line
    assert "netCDF results file" in line and "bytes" not in line


@pytest.fixture(scope="module")
def short_life():
    return life(LIFE, SHORT)


def test_life_limits_never_set_read_not_set(short_life):
    text = life_summary_text(short_life)
    assert "revolutions to life.max_normal_force: not set" in text     # configs/life.yaml sets none
    assert "revolutions to life.max_clearance_growth: not reached" in text  # set, not reached


def test_life_report_scales_depths_and_stays_within_100_characters(short_life):
    text = life_summary_text(short_life)
    depth = float(short_life.wear_depth_max.isel(cycle=-1).sel(joint="B"))
    assert f"B at the end: max depth {format_length(depth)}," in text
    assert " um" in text and "e-0" not in text
    assert max(len(line) for line in text.splitlines()) <= 100


@pytest.mark.parametrize("value, text", [(2.745e-6, "2.745 um"), (1.2e-4, "120 um"),
                                         (2.5e-4, "250 um"), (1.5e-3, "1.5 mm"), (3e-10, "0.3 nm")])
def test_lengths_print_in_um_or_mm(value, text):
    assert format_length(value) == text


def test_a_block_that_stops_a_life_run_read_bin_by_bin_hints_at_interpolate():
    binned = load_config(LIFE, ["wear.interpolate=false"])
    hint = life_stop_hint(binned, "block_status:energy_residual")
    assert "wear.interpolate=true" in hint
    assert life_stop_hint(load_config(LIFE), "block_status:energy_residual") == ""
    assert life_stop_hint(binned, "max_blocks") == ""


def test_the_life_command_prints_that_hint(tmp_path, monkeypatch):
    import clearsweep.service_life as service_life

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(cli, "announce_compile", lambda *a, **k: None)
    stopped = xr.Dataset({"stop_reason": ((), "block_status:energy_residual"), "x": ("cycle", [1.0])})
    monkeypatch.setattr(service_life, "life", lambda cfg, **kwargs: stopped)
    monkeypatch.setattr(service_life, "life_summary_text", lambda ds: "life summary")
    result = invoke("life", LIFE, "--set", "wear.interpolate=false", "-o", "l.nc")
    assert result.exit_code == 1
    assert "life run stopped: block_status:energy_residual" in result.stderr
    assert "--set wear.interpolate=true" in result.stderr


@pytest.mark.parametrize("argv0, program", [
    (".venv/bin/clearsweep", ".venv/bin/clearsweep"),
    ("/usr/local/bin/clearsweep", "/usr/local/bin/clearsweep"),
    (cli.__file__, "python -m clearsweep.cli"),     # an interpreter outside the current folder
    ("pytest", "clearsweep"),
])
def test_resume_commands_are_printed_as_the_program_was_invoked(monkeypatch, tmp_path, argv0,
                                                                program):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "argv", [argv0, "sweep"])
    command = cli._resume_command("sweep", "s.yaml", "s.nc", ("solver.duration=0.1",))
    assert command == f"{program} sweep s.yaml -o s.nc --resume --set solver.duration=0.1"


def test_a_resume_command_names_the_interpreter_below_the_current_folder(monkeypatch, tmp_path):
    python = tmp_path / ".venv" / "bin" / "python"
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "argv", [cli.__file__, "life"])
    monkeypatch.setattr(sys, "executable", str(python))
    assert cli._resume_command("life", "l.yaml", "l.nc", ()).startswith(
        ".venv/bin/python -m clearsweep.cli life l.yaml")


def test_an_unknown_name_among_hundreds_is_one_short_line():
    names = [f"metric_number_{i}_settled" for i in range(200)]
    message = choice_message("metric", "metric_number_7_setled", names)
    assert "did you mean metric_number_7_settled" in message
    assert len(message) < MAX_OFFER_CHARS + 200 and message.endswith(" more")
    short = choice_message("metric", "x", ["a", "b"])
    assert short.endswith("choose from: a, b")


def test_a_sampled_design_is_named_by_its_inputs():
    """The sensitivity sweep's best design read "sample=45", without the values drawn."""
    from clearsweep.analysis.text import _design_text

    ds = xr.Dataset(coords={"sample": [0, 1], "B_clearance": ("sample", [1e-4, 3.123456e-4]),
                            "speed_rpm": ("sample", [40.0, 52.34])})
    assert _design_text(ds, {"sample": 1}) == "sample=1 (B_clearance=0.0003123, speed_rpm=52.34)"
    grid = xr.Dataset(coords={"B_coating": ["none", "PTFE"]})
    assert _design_text(grid, {"B_coating": "PTFE"}) == "B_coating=PTFE"


def test_a_rerun_that_replaces_a_result_says_what_it_replaced(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    case = str(ROOT / "configs" / "two_clearances.yaml")
    first = invoke("run", case, "-o", "r.nc", "--set", "solver.duration=0.004", "-q")
    assert first.exit_code == 0, first.output
    again = invoke("run", case, "-o", "r.nc", "--set", "solver.duration=0.002")
    assert again.exit_code == 0, again.output
    last = again.stderr.strip().splitlines()[-1]
    assert last.startswith("clearsweep: wrote r.nc, replacing the result of 20")
    assert last.endswith("made with --set solver.duration=0.004")
    fresh = invoke("run", case, "-o", "new.nc", "--set", "solver.duration=0.002")
    assert fresh.stderr.strip().splitlines()[-1] == "clearsweep: wrote new.nc"


@pytest.fixture(scope="module")
def run_file(tmp_path_factory):
    from clearsweep.dataset import write_netcdf_atomic
    from clearsweep.simulation import simulate

    path = tmp_path_factory.mktemp("run") / "run.nc"
    write_netcdf_atomic(simulate(str(ROOT / "configs" / "two_clearances.yaml"),
                                 ["solver.duration=0.002"]), path)
    return path


@pytest.mark.parametrize("kind, wanted, not_said", [
    ("sweep", "is a single run: draw it with --kind slider", "--select"),
    ("life", "--kind life draws a life run (`clearsweep life CONFIG` writes one)", "summary-only"),
])
def test_plot_of_a_single_run_names_what_the_file_is(run_file, tmp_path, kind, wanted, not_said):
    result = invoke("plot", run_file, "--kind", kind, "-o", tmp_path / "f.png")
    assert result.exit_code == 2
    assert wanted in result.stderr and not_said not in result.stderr
    assert not (tmp_path / "f.png").exists()


def test_plot_sweep_of_a_life_run_points_to_kind_life(short_life, tmp_path):
    from clearsweep.dataset import write_netcdf_atomic

    write_netcdf_atomic(short_life, tmp_path / "l.nc")
    result = invoke("plot", tmp_path / "l.nc", "--kind", "sweep", "-o", tmp_path / "f.png")
    assert result.exit_code == 2
    assert "is a life run: --kind life draws it" in result.stderr
    assert "slider_acceleration" not in result.stderr     # no default metric the user never typed


def test_the_sweep_time_left_is_a_steps_weighted_rate_that_never_restarts():
    """The bifurcation's time left jumped from 42 min to 20 s: the bar's clock restarted at
    the first finished case and every case counted alike, whatever its steps (issue 45)."""
    from clearsweep.sweeping.run import StepEta

    now = [100.0]
    eta = StepEta({"a": 1000.0, "b": 3000.0, "c": 6000.0}, lambda: now[0])
    assert eta.seconds_left() is None and eta.text() == "?"
    now[0] += 10.0                      # 10 s for the first 1000 steps, start-up included
    eta.finished("a")
    assert eta.seconds_left() == pytest.approx(10.0 * 9000.0 / 1000.0)
    now[0] += 30.0                      # the next 3000 steps at the same rate
    eta.finished("b")
    # one clock from the start: 40 s for 4000 steps, so 6000 steps left take 60 s
    assert eta.seconds_left() == pytest.approx(60.0)
    now[0] += 60.0
    eta.finished("c")
    assert eta.seconds_left() == 0.0


def test_the_sweep_progress_bar_keeps_its_clock_and_shows_the_steps_weighted_time_left(
        tmp_path, monkeypatch):
    import tqdm.auto

    from clearsweep.sweeping import run_sweep

    bars = []
    real = tqdm.auto.tqdm

    def keep(*args, **kwargs):
        bars.append(real(*args, **kwargs))
        return bars[-1]

    monkeypatch.setattr(tqdm.auto, "tqdm", keep)
    spec = {"base": str(ROOT / "configs/two_clearances.yaml"),
            "sweep": {"grid": {"joints.B.coating": ["none", "PTFE", "lead"]}}}
    run_sweep(spec, workers=1, overrides=["solver.duration=0.002"])
    (bar,) = bars
    assert bar.initial == 0                     # the clock was not restarted at the first case
    assert "left=0 s" in bar.postfix and "{remaining}" not in bar.bar_format


def test_a_life_run_gives_its_expected_time_left_from_the_blocks_so_far():
    """The plan's "at most about 21.3 min" was the only time a life run gave."""
    from clearsweep.budget import duration_text
    from clearsweep.service_life import life_time_left

    cfg = load_config(LIFE, ["life.max_blocks=100", "life.cycles=1000"])
    # 10 blocks, 10 s, 500 of 1000 revolutions: 10 s more at this pace (90 blocks would be 90 s)
    assert life_time_left(cfg, 500.0, 10, 10.0) == f"about {duration_text(10.0)} left at this pace"
    # 10 blocks, 10 s, 1 revolution: the blocks left bound it (90 more at 1 s each)
    assert life_time_left(cfg, 1.0, 10, 10.0) == f"about {duration_text(90.0)} left at this pace"
    assert life_time_left(cfg, 1000.0, 10, 10.0) == ""
    assert life_time_left(cfg, 5.0, 100, 10.0) == ""
    # resumed at block 10, 500 revolutions: this process's 1 block, 1 s, took 100 of them,
    # so 4 s more at this pace (0.67 s when the 600 revolutions were all taken as its own)
    assert life_time_left(cfg, 600.0, 1, 1.0, before=(10, 500.0)) == \
        f"about {duration_text(4.0)} left at this pace"
    assert life_time_left(cfg, 600.0, 1, 1.0, before=(99, 500.0)) == ""      # max_blocks


@pytest.mark.parametrize("beta", [0.5, 1.0])
def test_the_blocks_left_follow_the_depth_s_power_law(beta):
    """A life run whose deepest bin grows as a N^beta, by the same depth each block: after
    three blocks the blocks left are those that reach life.cycles exactly (configs/life.yaml
    ran 40 blocks where its plan's cap said 101, and the time left at the first blocks was
    4-7x the run's)."""
    from clearsweep.service_life import blocks_left, forecast_blocks

    cfg = load_config(LIFE, ["life.max_blocks=10000", "life.cycles=1e6"])
    step = 2e-6                           # each block's jump [m]
    a = 50 * step / 1e6 ** beta           # h = a N^beta [m]: 1e6 revolutions at block 50
    revolutions = [(step * b / a) ** (1.0 / beta) for b in range(1, 6)]
    depths = [(n, a * n ** beta) for n in revolutions]
    forecast = forecast_blocks(cfg)
    cap, planned = forecast.to_limits - 5, forecast.blocks - 5
    assert cap > 45 and planned < cap
    assert blocks_left(cfg, 5, depths) == pytest.approx(45, rel=1e-9)   # 50, less the 5 run
    # too few blocks, or no growth seen: the plan's forecast (to life.cycles at the plan's
    # wear pace), less the blocks run
    assert blocks_left(cfg, 5, depths[:2]) == planned
    assert blocks_left(cfg, 5, [(n, 1e-6) for n, _ in depths]) == planned
    # a steep fit (two blocks a revolution apart, the depth doubled) is the cap (the wear
    # limit's blocks), not an OverflowError that would stop the run from its progress line
    assert blocks_left(cfg, 5, [(1e4, 1e-6), (1e4 + 1, 2e-6), (1e4 + 2, 4e-6)]) == cap


def test_plot_sweep_of_a_life_sweep_without_metric_asks_for_one(tmp_path):
    """It failed on the default metric, a name the user never typed."""
    path = tmp_path / "ls.nc"
    xr.Dataset({"cycles_reached": ("d", [1.0, 2.0])}, attrs={"sweep_store": "life"}).to_netcdf(path)
    result = invoke("plot", path, "--kind", "sweep", "-o", tmp_path / "f.png")
    assert result.exit_code == 2
    assert "a life sweep, needs --metric" in result.stderr and "--metric cycles_reached" in result.stderr


def test_a_missing_series_is_blamed_on_the_summary_store_only_where_it_is_one():
    """Was: every dataset lacking a series got "(a summary-only sweep holds no time series or
    wear maps)", a single run and a life run too."""
    import xarray as xr

    from clearsweep.plotting.common import PlotError, _require

    def message(ds):
        with pytest.raises(PlotError) as exc:
            _require(ds, ("slider_acceleration",), "--kind slider")
        return str(exc.value)

    run = xr.Dataset({"status": ((), "ok")})
    summary = xr.Dataset({"x": ("B_clearance", [1.0])}, attrs={"sweep_store": "summary"})
    assert message(run) == ("--kind slider needs slider_acceleration, which this dataset lacks")
    assert "summary-only sweep" in message(summary) and "store: full" in message(summary)
    assert "summary-only" not in message(
        xr.Dataset({"x": ("B_clearance", [1.0])}, attrs={"sweep_store": "full"}))


def test_validate_refuses_the_step_that_run_refuses():
    """Was: `validate` called a case with solver.dt = 5e-3 s valid, and `run` then refused
    it (the step bound is checked when the case is packed, which validate did not do). Now
    both refuse it in one line that names the file and the key, compiling nothing."""
    config = str(ROOT / "configs" / "one_clearance.yaml")
    for command in (["validate", config], ["run", config, "--dry-run"]):
        result = CliRunner().invoke(main, [*command, "--set", "solver.dt=5e-3"])
        assert result.exit_code == 2, result.output
        line = result.output.strip().splitlines()[-1]
        assert line.startswith("clearsweep: error: ") and "one_clearance.yaml: solver.dt" in line
