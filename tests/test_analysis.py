"""Wear tables (paper Tables 4-6), summaries and the report command, on synthetic data.

Expected numbers are recomputed by hand from the constants of ``synthetic``.
"""

from __future__ import annotations

import csv
import io
import json
import re

import numpy as np
import pytest
import synthetic as syn
import xarray as xr
from click.testing import CliRunner
from synthetic import case, sweep_ds, sweep_file  # noqa: F401  (pytest fixtures)

from clearsweep.analysis import (
    REPORT_FORMATS,
    SelectionError,
    case_summary,
    format_metric_table,
    format_reduction_table,
    format_wear_table,
    metric_table,
    parse_selection,
    reduction_table,
    run_summary_text,
    wear_table,
    worn_arc,
)
from clearsweep.cli import report_command
from clearsweep.dataset import write_netcdf_atomic
from clearsweep.variables import STATISTICS, SUMMARY_VARIABLES

# (joint, axis) -> (max depth [m], angle of max, min angle, max angle, range, arc [degree]) by
# hand from synthetic.WEAR_PROFILES: bins on [lo, hi], peak at peak_angle. A x wears every bin:
# range 179.5 - (-179.5) = 359, arc a full 360.
EXPECTED_WEAR = {
    ("A", "x"): (7.5e-11, -150.5, -179.5, 179.5, 360.0),     # every bin worn: the circle
    ("A", "y"): (7.0e-12, 44.5, -4.5, 44.5, 49.0),
    ("B", "x"): (8.0e-11, 20.5, -10.5, 40.5, 51.0),
    ("B", "y"): (2.7e-11, 10.5, -5.5, 46.5, 52.0),
    ("B", "z"): (1.2e-10, 27.5, -22.5, 27.5, 50.0),
}


@pytest.fixture(scope="module")
def case_file(tmp_path_factory, case) -> str:
    return str(write_netcdf_atomic(case, tmp_path_factory.mktemp("case") / "case.nc"))


def invoke(*args: str):
    return CliRunner().invoke(report_command, list(args))


# --------------------------------------------------------------------------- wear table

def test_wear_table_matches_hand_computed_bins(case):
    table = wear_table(case)
    assert table["wear_depth_axis_max"].dims == ("joint", "axis")
    for (joint, axis), (depth, at_max, lo, hi, width) in EXPECTED_WEAR.items():
        row = table.sel(joint=joint, axis=axis)
        assert float(row["wear_depth_axis_max"]) == pytest.approx(depth, rel=1e-12)
        assert float(row["wear_angle_of_max"]) == at_max
        assert float(row["wear_angle_min"]) == lo
        assert float(row["wear_angle_max"]) == hi
        assert float(row["wear_range"]) == width


def test_sub_threshold_bins_are_not_worn(case):
    # Every bin outside [lo, hi] holds 1e-15 m > 0 but < 1e-3 of the peak: the
    # angles must come from [lo, hi] only (B x would otherwise span -179.5..179.5).
    table = wear_table(case).sel(joint="B", axis="x")
    assert float(table["wear_angle_min"]) == -10.5


def test_no_wear_gives_zero_depth_and_nan_angles(case):
    row = wear_table(case).sel(joint="A", axis="z")
    assert float(row["wear_depth_axis_max"]) == 0.0
    for name in ("wear_angle_of_max", "wear_angle_min", "wear_angle_max", "wear_range"):
        assert np.isnan(float(row[name]))


def test_wear_straddling_180_degree_is_read_on_the_circle(case):
    # Worn bin centres 173.5..179.5 and -179.5..-174.5: the smallest arc holding them goes
    # through 180, from the centre 173.5 to the centre -174.5 = 185.5 (12 degree), as the polar
    # plot shows; min/max of the angles read 359 degree (the table printed "Wear range 359.0
    # deg" beside a 12 degree worn arc).
    straddling = case.copy(deep=True)
    centres = straddling["angle"].values
    worn = (centres >= 173.5) | (centres <= -174.5)
    straddling["wear_projection"].loc[dict(joint="A", axis="z")] = np.where(worn, 1e-11, 0.0)
    row = wear_table(straddling).sel(joint="A", axis="z")
    assert float(row["wear_range"]) == 12.0
    assert float(row["wear_angle_min"]) == 173.5 and float(row["wear_angle_max"]) == -174.5


@pytest.mark.parametrize("flags, arc", [
    ([0, 0, 0, 0], (-1, -1, -1)), ([1, 1, 1, 1], (0, 3, 4)), ([0, 1, 0, 0], (1, 1, 0)),
    ([0, 1, 1, 0], (1, 2, 1)), ([1, 0, 0, 1], (3, 0, 1)), ([1, 0, 1, 0], (0, 2, 2)),  # equal arcs: not across +-180
    ([1, 1, 0, 1], (3, 1, 2)),
])
def test_worn_arc_on_four_bins(flags, arc):
    assert worn_arc(np.array(flags, dtype=bool)) == arc


def test_all_nan_projection_gives_nan_not_error(case):
    failed = case.copy()
    failed["wear_projection"] = case["wear_projection"] * np.nan
    table = wear_table(failed)
    assert np.isnan(table["wear_depth_axis_max"]).all()
    assert np.isnan(table["wear_range"]).all()


def test_wear_table_units_come_from_registry(case):
    table = wear_table(case)
    for name in table.data_vars:
        assert table[name].attrs["units"] == SUMMARY_VARIABLES[name].units
        assert table[name].attrs["long_name"] == SUMMARY_VARIABLES[name].long_name


def test_wear_table_broadcasts_over_sweep_dims(sweep_ds):
    table = wear_table(sweep_ds)
    assert table["wear_depth_axis_max"].dims == ("B_coating", "B_clearance", "joint", "axis")
    for (coating, clearance), (lo, hi, peak) in syn.SWEEP_B_X.items():
        row = table.sel(B_coating=coating, B_clearance=clearance, joint="B", axis="x")
        assert float(row["wear_depth_axis_max"]) == pytest.approx(peak, rel=1e-12)
        assert float(row["wear_angle_min"]) == lo
        assert float(row["wear_range"]) == hi - lo


# --------------------------------------------------------------------------- summaries

def test_case_summary_numbers(case):
    s = case_summary(case)
    # Square wave +-3 everywhere but one spike of 50 (before 0.05 s); the summary copies
    # the stored every-step statistics, it does not recompute them from the rows.
    assert float(s["slider_acceleration_peak"]) == syn.ACC_SPIKE
    assert float(s["slider_acceleration_peak_settled"]) == syn.ACC_LEVEL
    assert float(s["slider_acceleration_rms_settled"]) == pytest.approx(syn.ACC_LEVEL, rel=1e-12)
    for name in STATISTICS:
        xr.testing.assert_identical(s[name], case[name])
    for joint in ("A", "B"):
        assert float(s["normal_force_peak"].sel(joint=joint)) == syn.NORMAL_FORCE_PEAK[joint]
        assert float(s["wear_depth_max_final"].sel(joint=joint)) == pytest.approx(
            syn.WEAR_MAP_PEAK[joint], rel=1e-12)
    assert str(s["status"].values) == "ok"
    assert int(s["substeps_used"]) == 4 and int(s["rk4_steps"]) == 80_000
    assert float(s["wall_time"]) == 2.0
    # the Poincare sections pass through (small: summary stores keep them)
    assert set(s.dims) <= {"joint", "axis", "revolution"}
    for name in ("poincare_offset", "poincare_velocity", "poincare_slider_acc", "poincare_time"):
        xr.testing.assert_identical(s[name], case[name])
    assert s.attrs["config"] == case.attrs["config"]


def test_case_summary_lists_settled_statistics_first(case):
    names = [n for n in case_summary(case).data_vars if n in STATISTICS]
    settled = [n.endswith("_settled") for n in names]
    assert settled == sorted(settled, reverse=True) and any(settled) and not all(settled)


def test_case_summary_does_not_recompute_from_the_rows(case):
    """Thinning the rows (as save_every does) leaves the summary statistics as stored."""
    thinned = case.isel(time=slice(None, None, 7))
    assert float(abs(thinned["slider_acceleration"]).max()) != syn.ACC_SPIKE
    assert float(case_summary(thinned)["slider_acceleration_peak"]) == syn.ACC_SPIKE


def test_case_summary_of_a_summary_is_the_summary(sweep_ds):
    summary = case_summary(sweep_ds)
    again = case_summary(summary)
    xr.testing.assert_identical(summary, again)
    xr.testing.assert_identical(wear_table(summary), wear_table(sweep_ds))


def test_run_summary_text(case):
    text = run_summary_text(case)
    assert "status: ok" in text
    assert "settled (t >= 0.05 s), whole run in brackets" in text
    assert "slider acceleration: peak 3 m s-2 (50 m s-2), RMS 3 m s-2" in text
    assert "peak normal force: A 40 N (40 N), B 120 N (120 N)" in text
    assert "sub-steps used: 4" in text
    assert "energy residual (relative): 2.50e-06" in text
    assert "40,000 RK4 steps/s" in text          # 80 000 steps in 2 s


def test_run_summary_text_reports_a_failed_case():
    text = run_summary_text(syn.one_case(status="unstable_step"))
    assert text.startswith("status: unstable_step")


# --------------------------------------------------------------------------- Table 6 and metrics

def test_reduction_table_recomputed_by_hand(sweep_ds):
    red = reduction_table(sweep_ds, {"B_coating": "none"})
    b_x = red.sel(joint="B", axis="x")
    for clearance in syn.SWEEP_CLEARANCES:
        ref_lo, ref_hi, ref_peak = syn.SWEEP_B_X[("none", clearance)]
        lo, hi, peak = syn.SWEEP_B_X[("PTFE", clearance)]
        row = b_x.sel(B_coating="PTFE", B_clearance=clearance)
        assert float(row["wear_depth_reduction"]) == pytest.approx(ref_peak - peak, rel=1e-12)
        assert float(row["wear_depth_reduction_percent"]) == pytest.approx(75.0, rel=1e-12)
        # Range 51 -> 61 degree: a reduction of -10 degree, -19.608 %.
        assert float(row["wear_range_reduction"]) == pytest.approx(-10.0, abs=1e-12)
        assert float(row["wear_range_reduction_percent"]) == pytest.approx(-1000.0 / 51.0, rel=1e-12)
        reference = b_x.sel(B_coating="none", B_clearance=clearance)
        assert float(reference["wear_depth_reduction"]) == 0.0
    assert red["is_reference"].sel(B_coating="none").all()
    assert not red["is_reference"].sel(B_coating="PTFE").any()
    # No wear in the reference (A z): percentages are NaN, not inf.
    assert np.isnan(red["wear_depth_reduction_percent"].sel(joint="A", axis="z")).all()


def test_reduction_table_reproduces_paper_table_6():
    """Paper Tables 5 and 4 (two clearances) give Table 6's first row: 6.25e-11 m, 75.32 %,
    -24.38 degree, -18.10 %."""
    none = {("B", "x"): (0.0, 134.5, 134.5, 8.3004e-11)}       # Table 4: range 134.66
    coated = {("B", "x"): (0.5, 159.5, 159.5, 2.0485e-11)}     # Table 5: range 159.04
    ds = xr.concat([syn.one_case(profiles=none), syn.one_case(profiles=coated)], dim="B_coating")
    ds = ds.assign_coords(B_coating=["none", "PTFE"])
    row = reduction_table(ds, ["B_coating=none"]).sel(B_coating="PTFE", joint="B", axis="x")
    assert float(row["wear_depth_reduction"]) == pytest.approx(6.2519e-11, rel=1e-12)
    assert float(row["wear_depth_reduction_percent"]) == pytest.approx(75.32, abs=0.01)
    # Bin centres: ranges 134.0 and 159.0 -> -25 degree, -18.66 %.
    assert float(row["wear_range_reduction"]) == pytest.approx(-25.0)
    assert float(row["wear_range_reduction_percent"]) == pytest.approx(-2500 / 134.0)


def test_reference_errors_name_the_choices(sweep_ds):
    with pytest.raises(SelectionError, match="B_coating"):
        reduction_table(sweep_ds, ["coating=none"])
    with pytest.raises(SelectionError, match="choose from: none, PTFE"):
        reduction_table(sweep_ds, ["B_coating=MoS2"])
    with pytest.raises(SelectionError, match="DIM=VALUE"):
        reduction_table(sweep_ds, ["B_coating"])


def test_selection_matches_numbers_by_value(sweep_ds):
    assert parse_selection(sweep_ds, ["B_clearance=2.5e-4"]) == {"B_clearance": 2.5e-4}
    assert parse_selection(sweep_ds, {"B_clearance": 0.00025, "B_coating": "PTFE"}) == {
        "B_clearance": 2.5e-4, "B_coating": "PTFE"}
    with pytest.raises(SelectionError, match="0.0001, 0.00025"):
        parse_selection(sweep_ds, ["B_clearance=3e-4"])


def test_selection_takes_the_swept_dotted_config_key_as_well_as_the_dimension(sweep_ds):
    ds = sweep_ds.copy()
    ds["B_coating"].attrs["config_key"] = "joints.B.coating"     # as a sweep file writes it
    ds["B_clearance"].attrs["config_key"] = "joints.B.clearance"
    assert parse_selection(ds, ["joints.B.coating=PTFE", "joints.B.clearance=2.5e-4"]) == {
        "B_coating": "PTFE", "B_clearance": 2.5e-4}
    with pytest.raises(SelectionError, match="unknown sweep dimension 'joints.A.coating'"):
        parse_selection(ds, ["joints.A.coating=PTFE"])


def test_metric_table(sweep_ds):
    values = metric_table(sweep_ds, "slider_acceleration_peak_settled")
    assert values.dims == ("B_coating", "B_clearance")
    for coating, level in syn.SWEEP_ACC_LEVEL.items():
        np.testing.assert_array_equal(values.sel(B_coating=coating).values, level)
    assert values.attrs["units"] == "m s-2"
    with pytest.raises(SelectionError, match="slider_acceleration_peak"):
        metric_table(sweep_ds, "slider_acceleration_peek")


def test_metric_table_text_has_a_row_per_case(sweep_ds):
    text = format_metric_table(sweep_ds, "normal_force_peak")
    lines = [ln for ln in text.splitlines() if ln.startswith(("none", "PTFE"))]
    assert len(lines) == 4 * 2                           # cases x joints
    assert "[N]" in text


# --------------------------------------------------------------------------- formats

def test_wear_table_text_layout(case):
    text = format_wear_table(case)
    lines = text.splitlines()
    at = next(i for i, ln in enumerate(lines) if ln.startswith("Joint"))
    first, second = lines[at:at + 2]        # headings on two lines (the table <= 100 wide)
    for heading in ("Max projected", "Max wear angle", "Min wear angle", "Wear range"):
        assert heading in first
    assert second.split()[:3] == ["direction", "depth", "[nm]"] and second.count("[degree]") == 4
    assert max(len(ln) for ln in lines) <= 100
    b_x = next(ln for ln in lines if ln.split()[:2] == ["B", "x"])
    assert b_x.split()[2:6] == ["0.08", "40.5", "-10.5", "51.0"]    # depth in nm
    a_z = next(ln for ln in lines if ln.split()[:2] == ["A", "z"])
    assert a_z.split()[2:] == ["0"] + ["n/a"] * 4


def test_wear_table_sweep_blocks(sweep_ds):
    text = format_wear_table(sweep_ds, "markdown")
    assert text.count("### B_coating=") == 4
    assert "### B_coating=PTFE, B_clearance=0.00025 (status: ok)" in text
    assert "| Joint | Wear direction | Max projected depth [nm] |" in text
    assert "| B | x | 0.02 | 40.5 | -20.5 | 61.0 | 20.5 |" in text


def test_reduction_text_leaves_out_the_reference(sweep_ds):
    text = format_reduction_table(sweep_ds, ["B_coating=none"])
    assert "B_coating=none, B_clearance" not in text
    assert text.count("B_coating=PTFE") == 2
    b_x = [ln.split() for ln in text.splitlines() if ln.split()[:2] == ["B", "x"]]
    assert b_x[0][2:] == ["0.03", "75.00", "-10.00", "-19.61"]     # nm
    assert b_x[1][2:] == ["0.06", "75.00", "-10.00", "-19.61"]


@pytest.mark.parametrize("fmt", REPORT_FORMATS)
def test_report_cli_every_format(sweep_file, fmt):
    result = invoke(sweep_file, "--format", fmt, "--full")
    assert result.exit_code == 0, result.output
    out = result.output
    if fmt in ("text", "markdown"):     # the summary first (tests/test_report_summary.py)
        summary, _, out = out.partition("\n\n## " if fmt == "markdown" else "\n\nSlider")
        out = ("## " if fmt == "markdown" else "Slider") + out
        assert "Headline metrics" in summary
    if fmt == "json":
        doc = json.loads(out)
        rows = doc["rows"]
        assert len(rows) == 4 * 2 * 3
        assert doc["columns"]["wear_depth_axis_max"]["units"] == "m"
        row = next(r for r in rows if (r["B_coating"], r["B_clearance"], r["joint"], r["axis"])
                   == ("PTFE", 1e-4, "B", "x"))
        assert row["wear_depth_axis_max"] == pytest.approx(1e-11) and row["wear_range"] == 61.0
        assert next(r for r in rows if r["joint"] == "A" and r["axis"] == "z")["wear_range"] is None
    elif fmt == "csv":
        rows = list(csv.reader(io.StringIO(out)))
        assert rows[0][:5] == ["B_coating", "B_clearance", "status", "joint", "axis"]
        # what sets the peak force, the statistics, then the wear
        assert rows[0][5:7] == ["Peak force set by", "Peak slider acc., settled [m s-2]"]
        assert "Max projected depth [m]" in rows[0]     # csv and json stay SI
        assert len(rows) == 1 + 4 * 2 * 3
    elif fmt == "markdown":
        assert out.startswith("## Slider and crank (every-step statistics")
        assert "\n## Wear prediction" in out
        assert "| Joint | Wear direction | Max projected depth [nm] |" in out
    else:
        assert out.startswith("Slider and crank (every-step statistics")
        assert "\nWear prediction" in out


@pytest.mark.parametrize("fmt", REPORT_FORMATS)
def test_report_cli_reference_every_format(sweep_file, fmt):
    result = invoke(sweep_file, "--reference", "B_coating=none", "--format", fmt)
    assert result.exit_code == 0, result.output
    if fmt == "json":
        rows = json.loads(result.output)["rows"]
        assert {r["B_coating"] for r in rows} == {"PTFE"}
        row = next(r for r in rows if r["joint"] == "B" and r["axis"] == "x")
        assert row["wear_depth_reduction_percent"] == pytest.approx(75.0)
    elif fmt == "csv":
        header = next(csv.reader(io.StringIO(result.output)))
        assert "Percentage of reduction [%]" in header
    else:
        assert "Table 6" in result.output


def test_report_cli_metric(sweep_file):
    result = invoke(sweep_file, "--metric", "slider_acceleration_peak_settled", "--format", "csv")
    assert result.exit_code == 0, result.output
    rows = list(csv.reader(io.StringIO(result.output)))
    assert rows[0][:2] == ["B_coating", "B_clearance"] and rows[0][2].endswith("[m s-2]")
    assert [float(r[2]) for r in rows[1:]] == [3.0, 3.0, 1.5, 1.5]


def test_report_cli_one_case(case_file):
    result = invoke(case_file)
    assert result.exit_code == 0, result.output
    assert "status" not in result.output            # one case, status ok: no heading
    assert "0.08" in result.output and "[nm]" in result.output


@pytest.mark.parametrize("args, names", [
    (["--reference", "B_coatin=none"], ["B_coating", "B_clearance"]),
    (["--reference", "B_coating=teflon"], ["none", "PTFE"]),
    (["--metric", "peak_acceleration"], ["slider_acceleration_peak"]),
    (["--metric", "x", "--reference", "B_coating=none"], ["--reference", "--metric"]),
])
def test_report_cli_bad_input_exit_2(sweep_file, args, names):
    result = invoke(sweep_file, *args)
    assert result.exit_code == 2
    for name in names:
        assert name in result.output


def test_report_cli_file_that_is_not_netcdf_exit_2(tmp_path):
    path = tmp_path / "sweep.yaml"
    path.write_text("name: s\n")
    result = CliRunner().invoke(report_command, [str(path)])
    assert result.exit_code == 2 and isinstance(result.exception, SystemExit)
    assert "is not a results file" in result.output


def test_report_cli_summary_only_file(tmp_path, sweep_ds):
    path = write_netcdf_atomic(case_summary(sweep_ds), tmp_path / "summary.nc")
    full = CliRunner().invoke(report_command, [str(path), "--reference", "B_coating=none"])
    assert full.exit_code == 0, full.output
    assert "0.06" in full.output


def test_case_dimension_with_zip_coordinates_and_without_coordinates():
    cases = [syn.one_case(profiles=syn.sweep_case_profiles(c, 2.5e-4)) for c in syn.SWEEP_COATINGS]
    bare = xr.concat(cases, dim="case")
    text = format_wear_table(bare)
    assert "\ncase=0 (status: ok)\n" in text and "\ncase=1 (status: ok)\n" in text
    zipped = bare.assign_coords(B_coating=("case", list(syn.SWEEP_COATINGS)),
                                B_clearance=("case", [2.5e-4, 2.5e-4]))
    rows = json.loads(format_wear_table(zipped, "json"))["rows"]
    assert {(r["case"], r["B_coating"], r["B_clearance"]) for r in rows} == {
        (0, "none", 2.5e-4), (1, "PTFE", 2.5e-4)}
    assert metric_table(bare, "wear_depth_max_final").dims == ("case", "joint")
    zipped_csv = format_metric_table(zipped, "wall_time", "csv").splitlines()
    assert zipped_csv[0] == "case,B_coating,B_clearance,wall-clock time of the simulation [s]"
    assert zipped_csv[2] == "1,PTFE,0.00025,2.0"
    csv_lines = format_metric_table(bare, "wear_depth_max_final", "csv").splitlines()
    assert csv_lines[0] == "case,joint,maximum wear depth at the end of the run [m]"
    assert csv_lines[1] == f"0,A,{syn.WEAR_MAP_PEAK['A']!r}"


def test_reference_on_a_zip_group_and_skipped_points(tmp_path):
    """Table 6 against a zip-group dimension (whose keys are non-index coordinates), from a
    real sweep with a skip rule; skipped points are not reported."""
    import yaml

    from clearsweep.analysis import (
        format_metric_table,
        format_reduction_table,
        format_wear_table,
        reduction_table,
    )
    from clearsweep.sweeping import run_sweep

    doc = {"base": {"joints": {"A": {"clearance": 2.5e-4}, "B": {"clearance": 2.5e-4}},
                    "solver": {"duration": 0.02}},
           "sweep": {"zip": [{"name": "coating_joints", "labels": ["none", "B", "AB"],
                              "joints.A.coating": ["none", "none", "PTFE"],
                              "joints.B.coating": ["none", "PTFE", "PTFE"]}],
                     "grid": {"mechanism.speed_rpm": [60.0, 90.0]},
                     "skip": [{"coating_joints": "AB", "speed_rpm": 90.0}]}}
    path = tmp_path / "z.yaml"
    path.write_text(yaml.safe_dump(doc))
    with run_sweep(path, tmp_path / "z.nc", workers=1, progress=False) as ds:
        table = reduction_table(ds, {"coating_joints": "none"})
        by_hand = (wear_table(ds.sel(coating_joints="none", drop=True))["wear_depth_axis_max"]
                   - wear_table(ds.sel(coating_joints="B", drop=True))["wear_depth_axis_max"])
        got = table["wear_depth_reduction"].sel(coating_joints="B", drop=True)
        np.testing.assert_allclose(got.transpose(*by_hand.dims).values, by_hand.values)
        for text in (format_wear_table(ds, "markdown"),
                     format_reduction_table(ds, {"coating_joints": "none"}, "markdown")):
            assert "skipped" not in text
            assert text.count("coating_joints=AB") == 1
        rows = [r for r in format_metric_table(ds, "slider_acceleration_peak", "csv").splitlines()[1:]
                if r.strip()]
        assert len(rows) == 5  # 3 x 2 points, one skipped


def test_statistics_table_puts_settled_first_with_whole_run_beside(sweep_ds):
    from clearsweep.analysis import format_statistics_table

    text = format_statistics_table(sweep_ds)
    lines = text.splitlines()
    at = next(i for i, line in enumerate(lines) if line.startswith("B_coating"))
    first, second = lines[at:at + 2]        # headings on two lines (the table <= 100 wide)
    assert first.count("Peak slider acc.,") == 2
    assert second.index("settled") < second.index("whole run")
    assert max(len(line) for line in lines) <= 100
    assert "settled = t >= 0.05 s" in text
    # the cells, what sets the peak force ("impacts (A, B)") one of them
    rows = [re.split(r"\s{2,}", line) for line in text.splitlines()
            if line.startswith(("none ", "PTFE "))]
    assert {r[2] for r in rows[:4]} == {"impacts (A, B)"}
    # settled peak = the coating's acceleration level, whole-run peak = the start-up spike
    assert {(r[0], float(r[3]), float(r[4])) for r in rows[:4]} == {
        ("none", syn.SWEEP_ACC_LEVEL["none"], syn.ACC_SPIKE),
        ("PTFE", syn.SWEEP_ACC_LEVEL["PTFE"], syn.ACC_SPIKE)}


def test_report_prints_the_statistics_before_the_wear_table(case_file):
    result = invoke(case_file)
    assert result.exit_code == 0, result.output
    assert result.output.index("every-step statistics") < result.output.index("Wear prediction")


def _smallest_arc(worn: np.ndarray) -> tuple[float, float, float]:
    """(first, last, bins) of the smallest arc holding every worn bin, by trying every
    start and length; of equal arcs one that does not cross the end of the bins, else the
    one whose last bin comes first."""
    n = worn.size
    if not worn.any():
        return np.nan, np.nan, np.nan
    for length in range(n):
        ends = [(first + length >= n, (first + length) % n, first) for first in range(n)
                if all(worn[i] <= (((i - first) % n) <= length) for i in range(n))]
        if ends:
            _, last, first = min(ends)
            return first, last, length
    raise AssertionError("unreachable")


def _wear_table_by_xarray(ds):
    """The wear table written with xarray reductions and a brute-force smallest arc: the
    oracle of the numpy version."""
    from clearsweep.summary import WEAR_THRESHOLD_FRACTION, with_attrs

    projection = ds["wear_projection"]
    angle = projection["angle"]
    depth = projection.max("angle")
    first_max = projection.fillna(-np.inf).argmax("angle")
    angle_of_max = angle.isel(angle=first_max).drop_vars("angle").where(depth > 0)
    worn = projection > WEAR_THRESHOLD_FRACTION * depth
    first, last, bins = xr.apply_ufunc(_smallest_arc, worn, input_core_dims=[["angle"]],
                                       output_core_dims=[[], [], []], vectorize=True,
                                       output_dtypes=[float, float, float])
    def centre(i):
        return np.where(np.isnan(i), np.nan, angle.values[np.nan_to_num(i).astype(int)])

    angle_min, angle_max = xr.apply_ufunc(centre, first), xr.apply_ufunc(centre, last)
    width = xr.where(worn.all("angle"), 360.0, bins * (360.0 / angle.size))
    thr = {"wear_threshold_fraction": WEAR_THRESHOLD_FRACTION}
    return xr.Dataset({
        "wear_depth_axis_max": with_attrs(depth, "wear_depth_axis_max"),
        "wear_angle_max": with_attrs(angle_max, "wear_angle_max", **thr),
        "wear_angle_min": with_attrs(angle_min, "wear_angle_min", **thr),
        "wear_range": with_attrs(width, "wear_range", **thr),
        "wear_angle_of_max": with_attrs(angle_of_max, "wear_angle_of_max"),
    })


def test_wear_table_matches_its_xarray_definition_on_a_sweep_with_empty_nan_and_wrapping_rows():
    rng = np.random.default_rng(0)
    p = rng.random((3, 2, 3, 36)) ** 8
    p[0, 0] = 0.0                        # no wear on a joint
    p[1, 1] = np.nan                     # a failed case's projection
    p[2, 0, 1, 5:30] = 0.0               # one worn stretch
    p[2, 1, 0, :] = 0.0
    p[2, 1, 0, [3, 35]] = 1.0            # worn bins either side of 0 degrees
    ds = xr.Dataset({"wear_projection": (("B_coating", "joint", "axis", "angle"), p)},
                    coords={"B_coating": ["a", "b", "c"], "joint": ["A", "B"],
                            "axis": ["x", "y", "z"], "angle": np.arange(36) * 10 + 5.0})
    xr.testing.assert_identical(wear_table(ds), _wear_table_by_xarray(ds))
    # the angle axis need not be last
    xr.testing.assert_identical(wear_table(ds.transpose("angle", ...)), _wear_table_by_xarray(ds))


@pytest.mark.parametrize("fmt", ["csv", "json"])
def test_report_csv_and_json_of_a_sweep_carry_every_headline_metric(sweep_file, fmt):
    """csv and json of a sweep held only the wear table."""
    from clearsweep.analysis import HEADLINE_METRICS

    result = invoke(sweep_file, "--format", fmt)
    assert result.exit_code == 0, result.output
    if fmt == "json":
        doc = json.loads(result.output)
        names = set(doc["columns"])
        assert all(name in row for row in doc["rows"] for name in HEADLINE_METRICS)
    else:
        from clearsweep.analysis import tables

        headings = {n.split(" [")[0] for n in next(csv.reader(io.StringIO(result.output)))}
        columns = (*tables._MOTION_COLUMNS, *tables._CONTACT_COLUMNS, *tables._FINAL_WEAR_COLUMNS,
                   *tables._WEAR_COLUMNS)
        names = {c.name for c in columns if c.heading in headings}
    assert set(HEADLINE_METRICS) <= names
    assert "wear_depth_axis_max" in names
