"""The motion's figures and report lines (docs/physics.md section 11): ``--kind spectrum``
and ``--kind bifurcation`` keep their text apart and read right, a bifurcation diagram
without a swept key says what it needs, the summaries carry ``period`` and ``chaos_k``
wherever Poincaré samples exist, and ``report`` names the periodic and chaotic designs."""

from __future__ import annotations

import numpy as np
import pytest
import synthetic as syn
from click.testing import CliRunner
from synthetic import case  # noqa: F401  (pytest fixture)
from test_figure_layout import layout_problems

from clearsweep.analysis import case_summary, format_sweep_summary, run_summary_text
from clearsweep.cli import main
from clearsweep.dataset import write_netcdf_atomic
from clearsweep.motion import PERIOD_NONE, PERIOD_UNKNOWN
from clearsweep.plotting import BIFURCATION_REVOLUTIONS, PlotError, figure

#: r of the logistic map per case of the synthetic bifurcation sweep, and the period of each
#: (the first case NaN-padded after 30 of its 40 revolutions: 10 settled, still period 1)
R_VALUES = (2.9, 3.2, 3.5, 3.83, 4.0)
PERIODS = (1, 2, 4, 3, PERIOD_NONE)


@pytest.fixture(scope="module")
def bifurcation():
    return syn.bifurcation_sweep(R_VALUES)


@pytest.fixture(scope="module")
def bifurcation_file(tmp_path_factory, bifurcation):
    return str(write_netcdf_atomic(bifurcation, tmp_path_factory.mktemp("bif") / "bif.nc"))


def plot_cli(*args):
    return CliRunner().invoke(main, ["plot", *map(str, args)])


def test_the_summary_has_each_cases_period_over_three_joints(bifurcation):
    summary = case_summary(bifurcation)
    assert tuple(int(p) for p in summary["period"].values) == PERIODS
    assert summary["period"].dtype.kind == "i" and summary["period"].attrs["units"] == "1"
    # 20 settled revolutions: too few for the 0-1 test
    assert np.isnan(summary["chaos_k"].values).all()
    assert summary["chaos_k"].attrs["units"] == "1"


def test_the_zero_one_test_reads_the_settled_revolutions_where_there_are_enough():
    summary = case_summary(syn.bifurcation_sweep((3.5, 4.0), revolutions=600))
    k = summary["chaos_k"].values
    assert k[0] < 0.1 and k[1] > 0.9


def test_a_run_without_settled_revolutions_has_an_unknown_period(case):
    ds = syn.with_poincare(case, np.arange(5.0), first_s=-10.0)
    ds.attrs["settle_time_s"] = 100.0
    assert int(case_summary(ds)["period"]) == PERIOD_UNKNOWN
    assert "undetermined" in run_summary_text(ds)


def test_the_report_names_the_periodic_and_chaotic_designs():
    text = format_sweep_summary(syn.bifurcation_sweep((2.9, 3.2, 3.9, 4.0), revolutions=300))
    lines = text.splitlines()
    assert "- periodic, period 1: 1 design: speed_rpm=2.9" in lines
    assert "- periodic, period 2: 1 design: speed_rpm=3.2" in lines
    assert ("- non-periodic, chaotic by the 0-1 test (K > 0.5): 2 designs: speed_rpm=3.9 "
            "(K = 0.99), speed_rpm=4 (K = 1.00)") in " ".join(text.split())    # lines wrapped
    assert max(map(len, lines)) <= 100


def test_the_report_of_a_sweep_file_says_which_designs_are_non_periodic(bifurcation_file):
    result = CliRunner().invoke(main, ["report", bifurcation_file])
    assert result.exit_code == 0, result.output
    assert ("- non-periodic (no period up to 8 revolutions), 0-1 test n/a (too few revolutions): "
            "1 design: speed_rpm=4") in " ".join(result.stdout.split())


def test_a_bifurcation_diagram_keeps_its_text_apart(bifurcation):
    assert layout_problems(figure(bifurcation, "bifurcation")) == []


def test_a_bifurcation_diagram_draws_the_last_revolutions_of_each_case_per_clearance_joint(
        bifurcation):
    fig = figure(bifurcation, "bifurcation", x="speed_rpm")
    titles = [ax.get_title() for ax in fig.axes]
    # the slider and joint B, the only clearance joint of three (A and O ideal: NaN)
    assert titles == ["slider acceleration at the section",
                      "joint B: ball-centre offset x (socket frame)"]
    assert fig.axes[1].get_ylabel() == "offset x / clearance [-]"
    assert fig.axes[-1].get_xlabel() == "crank speed [r/min]"
    xs, ys = fig.axes[1].get_lines()[0].get_data()
    for r, period in zip(R_VALUES, PERIODS):
        column = ys[(xs == r) & np.isfinite(ys)]
        assert column.size == BIFURCATION_REVOLUTIONS
        distinct = np.unique(np.round(column, 6)).size
        assert distinct == (period if period > 0 else BIFURCATION_REVOLUTIONS)
    # the padded case's last revolutions with samples: 21-30 of its orbit
    first = ys[(xs == R_VALUES[0]) & np.isfinite(ys)]
    assert first == pytest.approx(syn.logistic_orbit(R_VALUES[0], 30)[-BIFURCATION_REVOLUTIONS:])


def test_a_bifurcation_diagram_draws_against_a_key_of_a_zip_group(bifurcation):
    ds = bifurcation.assign_coords(duration=("speed_rpm", 60.0 / np.asarray(R_VALUES),
                                             {"units": "s", "long_name": "simulated duration"}))
    fig = figure(ds, "bifurcation", x="duration")
    xs, _ = fig.axes[0].get_lines()[0].get_data()
    assert set(np.round(xs, 9)) == set(np.round(60.0 / np.asarray(R_VALUES), 9))
    assert fig.axes[-1].get_xlabel() == "simulated duration [s]"


def test_a_bifurcation_of_a_run_or_of_an_unswept_key_says_what_it_needs(case, bifurcation):
    with pytest.raises(PlotError, match="this file sweeps none"):
        figure(case, "bifurcation")
    with pytest.raises(PlotError, match="--x B_clearance: not a swept key of this file; "
                                        "--kind bifurcation draws against one of speed_rpm"):
        figure(bifurcation, "bifurcation", x="B_clearance")
    with pytest.raises(PlotError, match=r"needs the Poincaré samples \(poincare_time, "
                                        r"poincare_slider_acc\), which this file lacks"):
        unsampled = syn.sweep().drop_vars(["poincare_time", "poincare_slider_acc", "poincare_offset",
                                           "poincare_velocity", "revolution"])
        figure(unsampled, "bifurcation", x="B_clearance", select=["B_coating=none"])


def test_the_cli_refuses_a_bifurcation_without_a_swept_key_in_one_line(tmp_path, case,
                                                                       bifurcation_file):
    run = write_netcdf_atomic(case, tmp_path / "run.nc")
    for args, message in (
            ([run], "--kind bifurcation draws a sweep over one parameter against the swept key; "
                    "this file sweeps none"),
            ([bifurcation_file, "--x", "time"], "--x time: not a swept key of this file")):
        result = plot_cli(*args, "--kind", "bifurcation", "-o", tmp_path / "b.png")
        assert result.exit_code == 2
        assert message in result.stderr and "Traceback" not in result.output
        assert len(result.stderr.strip().splitlines()) == 1
        assert not (tmp_path / "b.png").exists()
    result = plot_cli(bifurcation_file, "--kind", "bifurcation", "-o", tmp_path / "b.png")
    assert result.exit_code == 0, result.output
    assert (tmp_path / "b.png").stat().st_size > 0
    # a swept key is the abscissa of bifurcation only
    result = plot_cli(run, "--kind", "slider", "--x", "speed_rpm", "-o", tmp_path / "s.png")
    assert result.exit_code == 2 and "'speed_rpm' is not one of 'angle', 'time'" in result.stderr


@pytest.fixture(scope="module")
def ideal_run():
    """Eight revolutions of the ideal slider acceleration with the start-up window cut:
    the spectrum's known answer (tests/test_motion.py)."""
    return syn.ideal_acceleration_case(revolutions=8.0, settle_s=1.0)


def test_a_spectrum_keeps_its_text_apart(ideal_run):
    assert layout_problems(figure(ideal_run, "spectrum")) == []


def test_a_spectrum_draws_log_power_against_orders_with_the_summary_in_the_title(ideal_run):
    fig = figure(ideal_run, "spectrum")
    ax = fig.axes[0]
    assert ax.get_yscale() == "log"
    assert ax.get_xlabel() == "crank order (frequency / crank frequency) [-]"
    assert ax.get_ylabel() == "power of the slider acceleration [(m s-2)^2]"
    orders, power = ax.get_lines()[0].get_data()
    assert orders[np.argmax(power)] == pytest.approx(1.0)
    # order 2 below order 1 by the closed form's ratio squared (0.3130 / 2.014)^2
    ratio = power[np.argmin(np.abs(orders - 2.0))] / power.max()
    assert ratio == pytest.approx((0.31297 / 2.0141) ** 2, rel=1e-3)
    assert "dominant order 1," in fig.get_suptitle()
    assert "of the power above order 10" in fig.get_suptitle()


def test_a_spectrum_of_a_run_too_short_says_how_long_it_must_be(case):
    with pytest.raises(PlotError, match="needs at least 2 crank revolutions in the settled "
                                        "window .* run longer"):
        figure(case, "spectrum")


def test_the_report_of_a_run_prints_its_period_and_leaves_out_what_it_lacks(tmp_path, case):
    ds = syn.with_poincare(case, 10.0 * syn.logistic_orbit(3.2, 30), first_s=-1.0)
    path = write_netcdf_atomic(ds, tmp_path / "run.nc")
    result = CliRunner().invoke(main, ["report", str(path)])
    assert result.exit_code == 0, result.output
    lines = result.stdout.splitlines()
    at = lines.index("Motion: spectrum and periodicity (settled = t >= 0.05 s)")
    assert "Period in revolutions (0: none, -1: n/a) [1]" in lines[at + 2]
    # the period, and the class the indicators give (no exponent: the period speaks)
    assert "Motion class" in lines[at + 2]
    assert lines[at + 3].split() == ["2", "periodic"]
    # 0.2 s at one revolution a second: no spectrum, and 30 samples: no 0-1 test; not printed
    assert "Dominant order" not in result.stdout and "0-1 test K" not in result.stdout


def test_a_summary_sweep_keeps_the_poincare_samples_and_their_period_for_its_diagram(tmp_path):
    """Through the sweep machinery (worker, summary, parts, assembly) with the kernel's
    Poincaré samples stood in for: each case's samples are the logistic map's at an r set
    by its crank speed, the slowest case with fewer revolutions (NaN-padded in the file)."""
    from clearsweep.simulation import simulate as real
    from clearsweep.sweeping import run_sweep

    r_of = {60.0: 3.2, 90.0: 3.5, 120.0: 4.0}
    revolutions = {60.0: 30, 90.0: 40, 120.0: 40}

    def with_samples(cfg):
        ds = real(cfg)
        rpm = cfg.mechanism.speed_rpm
        x = syn.logistic_orbit(r_of[rpm], revolutions[rpm])
        offset = np.full((x.size, ds.sizes["joint"]), np.nan)
        offset[:, -1] = x
        return syn.with_poincare(ds, 10.0 * x, offset, first_s=-20.0)  # 20 settled or more

    spec = {"store": "summary",
            "base": {"solver": {"duration": 0.002}, "joints": {"B": {"clearance": 2.5e-4}}},
            "sweep": {"grid": {"mechanism.speed_rpm": list(r_of)}}}
    path = tmp_path / "bif.nc"
    run_sweep(spec, path, workers=1, progress=False, _simulate=with_samples).close()
    import xarray as xr

    with xr.open_dataset(path) as ds:
        assert ds.sizes["revolution"] == 40
        assert np.isnan(ds["poincare_slider_acc"].sel(speed_rpm=60.0).values[30:]).all()
        assert list(ds["period"].values) == [2, 4, PERIOD_NONE]
        fig = figure(ds, "bifurcation")
        xs, ys = fig.axes[1].get_lines()[0].get_data()
        assert [np.unique(np.round(ys[xs == rpm], 6)).size for rpm in r_of] == [2, 4, 10]
        text = format_sweep_summary(ds)
    assert "- periodic, period 4: 1 design: speed_rpm=90" in text.splitlines()


def test_a_zip_groups_diagram_is_drawn_against_its_first_key_by_default(bifurcation):
    """configs/bifurcation.yaml's dimension is a zip group ``speed`` (labels, no units) with
    the keys speed_rpm, duration and metrics_settle_time along it."""
    ds = bifurcation.rename(speed_rpm="speed").assign_coords(
        speed_rpm=("speed", list(R_VALUES), {"units": "min-1", "config_key": "mechanism.speed_rpm",
                                             "long_name": "crank speed in revolutions per minute"}),
        duration=("speed", [1.0] * len(R_VALUES), {"units": "s", "config_key": "solver.duration"}))
    ds["speed"].attrs = {"long_name": "sweep zip group speed",
                         "config_keys": "mechanism.speed_rpm solver.duration"}
    fig = figure(ds, "bifurcation")
    assert fig.axes[-1].get_xlabel() == "crank speed in revolutions per minute [r/min]"


def test_the_shipped_bifurcation_sweep_runs_110_revolutions_a_speed_with_10_of_start_up():
    """100 settled revolutions: the samples the 0-1 test for chaos needs. The file gives its
    speeds only (issue 41, item 8): each case's seconds are resolved from its revolutions."""
    from pathlib import Path

    from clearsweep.sweeping import expand

    path = Path(__file__).resolve().parents[1] / "configs" / "bifurcation.yaml"
    plan = expand(path)
    configs = [case.config for case in plan.cases]
    assert len(configs) == 60 and plan.store == "summary" and list(plan.dims) == ["speed_rpm"]
    for cfg in configs:
        assert (cfg.solver.revolutions, cfg.metrics.settle_revolutions) == (110.0, 10.0)
        assert cfg.solver.duration == 110 * 60.0 / cfg.mechanism.speed_rpm
        assert cfg.metrics.settle_time == 10 * 60.0 / cfg.mechanism.speed_rpm
        assert cfg.joints.A.clearance == 0.0 and cfg.joints.B.clearance == 2.5e-4
    speeds = [cfg.mechanism.speed_rpm for cfg in configs]
    assert speeds == [50.0 + 10.0 * k for k in range(60)]
    text = path.read_text()
    assert "solver.duration" not in text and "metrics.settle_time" not in text


def test_the_swept_key_is_named_by_its_dotted_config_key_as_well(tmp_path, bifurcation):
    """The sweep file names the key ``mechanism.speed_rpm``, the results file's coordinate
    ``speed_rpm`` (with ``config_key`` naming the key): ``--x`` takes either."""
    ds = bifurcation.copy()
    ds["speed_rpm"].attrs["config_key"] = "mechanism.speed_rpm"
    path = write_netcdf_atomic(ds, tmp_path / "bif.nc")
    for x in ("speed_rpm", "mechanism.speed_rpm"):
        result = plot_cli(path, "--kind", "bifurcation", "--x", x, "-o", tmp_path / f"{x}.png")
        assert result.exit_code == 0, result.output
    by_key = figure(ds, "bifurcation", x="mechanism.speed_rpm")
    by_dim = figure(ds, "bifurcation", x="speed_rpm")
    for a, b in zip(by_key.axes[0].get_lines(), by_dim.axes[0].get_lines(), strict=True):
        np.testing.assert_array_equal(a.get_xydata(), b.get_xydata())
    assert by_key.axes[-1].get_xlabel() == by_dim.axes[-1].get_xlabel()
