"""Reports that answer first: a sweep's report starts with a short summary (design axes,
best and worst design per headline metric), the full tables only with --full or in
csv/json, and no rows for ideal joints."""

import csv
import io
import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from click.testing import CliRunner

from clearsweep.analysis import case_summary, format_sweep_summary, joint_clearances
from clearsweep.cli import main

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def main_job(tmp_path_factory) -> Path:
    """The main job's sweep file (configs/coating_clearance.yaml), its settled window from
    0.05 s (not its first revolution), shortened to 0.02 s per
    case and two of its six clearances: 16 cases, run through the CLI."""
    folder = tmp_path_factory.mktemp("main_job")
    text = (ROOT / "configs" / "coating_clearance.yaml").read_text()
    text = text.replace("[5.0e-5, 1.0e-4, 2.5e-4, 5.0e-4, 7.5e-4, 1.0e-3]", "[5.0e-5, 1.0e-3]")
    assert "[5.0e-5, 1.0e-3]" in text
    sweep = folder / "coating_clearance.yaml"
    sweep.write_text(text)
    out = folder / "coating_clearance.nc"
    result = CliRunner().invoke(main, ["sweep", str(sweep), "-o", str(out), "--workers", "1",
                                       "--no-progress", "--set", "solver.duration=0.02",
                                       "--set", "metrics.settle_time=0.05"])
    assert result.exit_code == 0, result.stderr
    return out


def report(*args) -> str:
    result = CliRunner().invoke(main, ["report", *map(str, args)])
    assert result.exit_code == 0, result.stderr
    return result.stdout


def test_the_main_jobs_report_is_a_short_summary(main_job):
    text = report(main_job)
    lines = text.splitlines()
    assert len(lines) <= 60 and max(map(len, lines)) <= 100
    assert lines[0] == "Sweep coating_clearance: 16 cases (ok 16); design axes:"
    assert "  B_coating (socket coating of joint B): none, MoS2, lead, PTFE" in lines
    assert "  clearance_joints: B, AB; A_clearance [m]: 0, 0.00025" in lines
    assert "n/a" not in text and "nan" not in text
    # the runs end before the settled window: the whole run's statistics, said so
    assert "- RMS slider acceleration, whole run (the runs end before the settled window) " \
           "[m s-2]" in lines
    assert "Every case's tables: --full (text), or --format csv / json." in lines
    assert "Wear prediction" not in text


def _block(text: str, title: str) -> list[str]:
    lines = text.splitlines()
    i = lines.index(title)
    return lines[i + 1:i + 4]


def test_the_summary_names_the_best_and_worst_design(main_job):
    text = report(main_job)
    with xr.open_dataset(main_job) as ds:
        summary = case_summary(ds)
        rms = summary["slider_acceleration_rms"]
        # joint A's wear: only the cases where A has a clearance (clearance_joints=AB)
        wear_a = summary["wear_depth_max_final"].sel(joint="A", clearance_joints="AB")
        for values, title in (
                (rms, "- RMS slider acceleration, whole run (the runs end before the settled "
                      "window) [m s-2]"),
                (wear_a, "- maximum wear depth at the end of the run, joint A [m]")):
            lowest, highest, spread = _block(text, title)
            low = values.where(values == values.min(), drop=True)
            high = values.where(values == values.max(), drop=True)
            assert lowest.split()[1] == f"{float(values.min()):.4g}"
            assert highest.split()[1] == f"{float(values.max()):.4g}"
            assert f"B_coating={low.B_coating.values.item()}" in lowest
            assert f"B_coating={high.B_coating.values.item()}" in highest
            assert spread.strip().startswith(f"spread {float(values.max() - values.min()):.3g}")
        # joint A's ideal cases (depth 0) would have been the lowest
        assert float(summary["wear_depth_max_final"].sel(joint="A").min()) == 0.0
        assert "clearance_joints=B" not in _block(text, "- maximum wear depth at the end of "
                                                        "the run, joint A [m]")[0]


def test_full_prints_the_tables_after_the_summary_without_ideal_rows(main_job):
    text = report(main_job, "--full")
    assert text.index("Headline metrics") < text.index("Slider and crank") \
        < text.index("Wear prediction")
    assert "n/a" not in text.split("Contacts", 1)[0]      # the motion table of a short run
    # in every case with clearance at B only, no row of joint A
    for block in text.split("\n\n"):
        head, *rows = block.splitlines() or [""]
        if "clearance_joints=B," in head:
            assert rows and not any(r.startswith("A ") for r in rows), block
        if "clearance_joints=AB," in head:
            assert any(r.startswith("A ") for r in rows), block


def test_csv_and_json_give_the_tables_without_the_summary_or_ideal_rows(main_job):
    rows = list(csv.DictReader(io.StringIO(report(main_job, "--format", "csv"))))
    assert len(rows) == 16 * 3 + 8 * 3          # B in every case, A where it has a clearance
    assert not [r for r in rows if r["joint"] == "A" and r["clearance_joints"] == "B"]
    assert "Headline" not in report(main_job, "--format", "json")


def test_joint_clearances_from_the_sweep_and_its_base(main_job):
    with xr.open_dataset(main_job) as ds:
        gap = joint_clearances(ds)
        gap = gap.transpose("joint", "B_clearance", "clearance_joints")
        assert gap.sel(joint="A").values.tolist() == [[0.0, 2.5e-4]] * 2      # the zip group
        assert gap.sel(joint="B").values.tolist() == [[5e-5, 5e-5], [1e-3, 1e-3]]  # the grid


def test_an_ensembles_summary_gives_intervals_and_a_verdict():
    from tests.test_ensemble import synthetic_ensemble

    ds = synthetic_ensemble()
    text = format_sweep_summary(ds)
    assert "(ensemble mean +- half-width of its 95% interval)" in text
    assert "+- " in text and "lowest vs highest: " in text


def test_a_failed_case_is_left_out_of_best_and_worst():
    from tests.synthetic import sweep

    ds = sweep()
    ds["status"] = ds["status"].astype(object)
    ds["status"][0, 0] = "penetration_exceeded"
    text = format_sweep_summary(ds)
    assert "(ok 3, penetration_exceeded 1)" in text.splitlines()[0]
    values = case_summary(ds)["slider_acceleration_rms_settled"].values.ravel()[1:]
    lowest = next(ln for ln in text.splitlines() if ln.strip().startswith("lowest"))
    assert float(lowest.split()[1]) == pytest.approx(float(np.min(values)), rel=1e-3)
    assert math.isfinite(float(lowest.split()[1]))


@pytest.mark.slow
def test_a_life_run_says_nothing_of_an_ideal_uncoated_joint(short_life_cli):
    """configs/one_clearance.yaml: A ideal and uncoated; the life run printed "max depth
    (A, B) nan, ..." per block and "coating of A: not worn through"."""
    out, result = short_life_cli        # `clearsweep life` of test_service_life's SHORT_LIFE
    blocks = [ln for ln in result.stderr.splitlines() if ln.startswith("  block at")]
    assert blocks and all(": max depth B " in ln and "nan" not in ln for ln in blocks)
    for text in (result.stdout, report(out)):
        assert "coating of B" in text and "coating of A" not in text and "nan" not in text


def test_report_warns_in_one_line_when_a_settled_window_holds_less_than_a_revolution(tmp_path):
    """Issue 41, item 8: 0.1 s at 600 r/min settled from 0.05 s holds half a revolution; 2
    revolutions settled after 1 hold one, and the file records what was asked."""
    one = str(ROOT / "configs" / "one_clearance.yaml")
    runs = {"seconds": ["--set", "solver.duration=0.1"],
            "revolutions": ["--set", "solver.revolutions=2", "--set", "metrics.settle_revolutions=1"]}
    for name, options in runs.items():
        result = CliRunner().invoke(main, ["run", one, "-o", str(tmp_path / f"{name}.nc"),
                                           "--set", "mechanism.speed_rpm=600", *options])
        assert result.exit_code == 0, result.stderr
    short = tmp_path / "seconds.nc"
    result = CliRunner().invoke(main, ["report", str(short)])
    assert result.exit_code == 0
    warning = [ln for ln in result.stderr.splitlines() if "warning" in ln]
    assert warning == [f"clearsweep: warning: {short}: the settled window (t >= 0.05 s) holds 0.5 "
                       "crank revolutions: its statistics cover part of a cycle; set "
                       "metrics.settle_revolutions and solver.revolutions for whole revolutions "
                       "(docs/runs.md)"]
    assert "warning" not in CliRunner().invoke(main, ["report", str(short), "--format",
                                                      "csv"]).stderr
    whole = tmp_path / "revolutions.nc"
    result = CliRunner().invoke(main, ["report", str(whole)])
    assert result.exit_code == 0 and "warning" not in result.stderr
    with xr.open_dataset(whole) as ds:
        assert (ds.attrs["duration_s"], ds.attrs["revolutions"]) == (0.2, 2.0)
        assert (ds.attrs["settle_time_s"], ds.attrs["settle_revolutions"]) == (0.1, 1.0)
        assert "revolutions: 2.0" in ds.attrs["config"]


def test_a_sweeps_report_counts_its_designs_with_a_short_settled_window(main_job):
    """The main job shortened to 0.02 s a case ends before its settled window (0.05 s)."""
    result = CliRunner().invoke(main, ["report", str(main_job)])
    warning = [ln for ln in result.stderr.splitlines() if "warning" in ln]
    assert len(warning) == 1 and "the settled window holds less than one crank revolution in " \
        "16 of 16 designs (fewest: 0 crank revolutions, t >= 0.05 s, at " in warning[0], warning


# ------------------------------------------------------- what drives the differences (issue 45, item 4)

def _drivers(sources: list[str], forces: list[float]) -> str:
    """drivers_line of four designs (B_clearance) whose peak force sources and peak contact
    forces at B are given; A ideal (no force)."""
    from clearsweep.analysis.text import drivers_line

    dims = ("B_clearance",)
    coords = {"B_clearance": [5e-5, 2.5e-4, 5e-4, 1e-3], "joint": ["A", "B"]}
    force = np.array([[np.nan, f] for f in forces])
    summary = xr.Dataset({"peak_force_source": (dims, np.array(sources)),
                          "normal_force_peak_settled": (("B_clearance", "joint"), force)},
                         coords=coords)
    usable = xr.DataArray(np.ones(4, bool), dims=dims, coords={"B_clearance": coords["B_clearance"]})
    line = drivers_line(summary, summary, usable, dims)
    assert line is not None
    return line


def test_impacts_drive_the_differences_where_the_highest_peak_is_an_impacts():
    line = _drivers(["quasi-static", "quasi-static", "impacts (B)", "impacts (A, B)"],
                    [50.0, 60.0, 300.0, 1775.0])
    assert line.startswith("What drives the differences between designs: impacts. 2 of 4 designs "
                           "impact (joints A, B)"), line
    assert "1775 N at B_clearance=0.001" in line and "50-60 N" in line


def test_friction_drives_them_where_the_highest_peak_is_an_oscillations():
    """The main job at 60 r/min before: no impact, PTFE at 0.05 mm oscillating at 115.5 N."""
    line = _drivers(["in-contact oscillation (B)", "quasi-static", "quasi-static", "quasi-static"],
                    [115.5, 11.9, 12.1, 12.7])
    assert line.startswith("What drives the differences between designs: friction."), line
    assert "no design impacts" in line and "115.5 N at B_clearance=5e-05" in line


def test_nothing_beyond_the_spread_where_every_design_is_quasi_static():
    line = _drivers(["quasi-static"] * 4, [11.86, 12.0, 12.4, 12.7])
    assert line.startswith("What drives the differences between designs: nothing beyond the "
                           "spread."), line
    assert "11.86-12.7 N (7.1 % apart)" in line


def test_an_impact_below_a_quasi_static_peak_does_not_drive_them():
    """A design that impacts softly while another carries a larger load: the load decides."""
    line = _drivers(["impacts (B)", "quasi-static", "quasi-static", "quasi-static"],
                    [20.0, 11.0, 12.0, 30.0])
    assert "nothing beyond the spread" in line and "1 of 4 designs impact, below it" in line


def test_the_main_jobs_report_says_what_drives_it(main_job):
    """The shortened main job (0.02 s from the seated start): no impact, no oscillation."""
    text = report(main_job)
    (line,) = [x for x in text.splitlines() if x.startswith("What drives the differences")]
    assert line.endswith("nothing beyond the spread. The highest peak contact"), line
