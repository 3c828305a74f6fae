"""A clearance sweep read as a two-level design (clearsweep.analysis.factorial): main effects
and interactions of known synthetic responses are recovered exactly, the members' intervals
cover the truth and shrink with paired scatter, and the report and the figure answer."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
import xarray as xr
from click.testing import CliRunner

from clearsweep import summary
from clearsweep.analysis import factorial
from clearsweep.analysis.text import format_sweep_summary
from clearsweep.cli import main
from clearsweep.dataset import write_netcdf_atomic
from clearsweep.ensemble import ensemble_statistics

JOINTS = ("A", "B", "O", "P")
C = 2.5e-4
#: main effects and the one interaction of the synthetic vibration [m s-2]
EFFECT = {"A": 0.2, "B": 0.5, "O": -0.1, "P": 0.3}
AB = -0.4
BASE = 1.5
MEMBERS = 6


def synthetic(noise: float = 0.0, paired: bool = True, seed: int = 0,
              a_by_speed: float = 0.0) -> xr.Dataset:
    """A 2^4 x speed x member summary sweep whose vibration is BASE + sum of the effects of
    the joints with clearance + AB where A and B both have it (+ the member's scatter: the
    same in every design where ``paired``; + ``a_by_speed`` x (-1 at 60 r/min, +1 at 120)
    where A has clearance), and whose wear at each joint is 1e-15 m^3 x (1 + the number of
    other joints with clearance) where it has clearance (NaN where ideal)."""
    rng = np.random.default_rng(seed)
    shape = (2, 2, 2, 2, 2, MEMBERS)
    member_shift = rng.standard_normal(MEMBERS) * noise
    vib = np.empty(shape)
    wear = np.full(shape + (4,), np.nan)
    for a, b, o, p, s in itertools.product((0, 1), repeat=5):
        on = {"A": a, "B": b, "O": o, "P": p}
        value = BASE + sum(EFFECT[j] * on[j] for j in JOINTS) + AB * a * b + 0.1 * s
        value += a_by_speed * (2 * s - 1) * a
        shift = member_shift if paired else rng.standard_normal(MEMBERS) * noise
        vib[o, a, b, s, p] = value + shift
        for k, j in enumerate(JOINTS):
            if on[j]:
                wear[o, a, b, s, p, :, k] = 1e-15 * (1 + sum(on.values()) - 1)
    dims = ("O_clearance", "A_clearance", "B_clearance", "speed_rpm", "P_clearance", "member")
    coords = {"O_clearance": ("O_clearance", [0.0, C], {"config_key": "joints.O.clearance"}),
              "A_clearance": ("A_clearance", [0.0, C], {"config_key": "joints.A.clearance"}),
              "B_clearance": ("B_clearance", [0.0, C], {"config_key": "joints.B.clearance"}),
              "speed_rpm": ("speed_rpm", [60.0, 120.0], {"config_key": "mechanism.speed_rpm"}),
              "P_clearance": ("P_clearance", [0, 1]),
              "P_clearance_y": ("P_clearance", [0.0, C], {"config_key": "joints.P.clearance_y"}),
              "P_clearance_z": ("P_clearance", [0.0, C], {"config_key": "joints.P.clearance_z"}),
              "member": ("member", np.arange(MEMBERS)), "joint": ("joint", list(JOINTS))}
    ds = xr.Dataset({"slider_acceleration_rms_settled": (dims, vib, {"units": "m s-2"}),
                     "wear_volume": (dims + ("joint",), wear, {"units": "m3"}),
                     "status": (dims, np.full(shape, "ok"))}, coords=coords)
    ds.attrs["sweep_dims"] = " ".join(dims)
    ds.attrs["sweep_store"] = "summary"
    return ds.merge(ensemble_statistics(ds[["slider_acceleration_rms_settled", "wear_volume", "status"]]))


@pytest.fixture(scope="module")
def design():
    return synthetic()


def test_the_factors_are_the_joints_switched_on_and_off(design):
    factors = factorial.clearance_factors(design)
    assert set(factors) == set(JOINTS)
    assert factors["P"] == ("P_clearance", 0, 1)     # the guide's two clearances, zipped
    # the speed is not a clearance: not a factor
    assert all(dim != "speed_rpm" for dim, _, _ in factors.values())


def test_main_effects_and_the_interaction_are_recovered(design):
    f = factorial.clearance_factors(design)

    def effect(*joints):
        terms = {j: (f[j][2], f[j][1]) for j in joints}
        return factorial.contrast(design, "slider_acceleration_rms_settled", None, terms, f)

    for j in JOINTS:
        value, low, high = effect(j)
        # averaged over the other factors: A's and B's effects carry half the interaction
        truth = EFFECT[j] + (0.5 * AB if j in "AB" else 0.0)
        assert value == pytest.approx(truth, abs=1e-12)
        assert low == pytest.approx(value) and high == pytest.approx(value)    # no scatter
    # m(A,B) - m(A) - m(B) + m(none), averaged over O, P and the speed
    assert effect("A", "B")[0] == pytest.approx(AB, abs=1e-12)
    for pair in itertools.combinations(JOINTS, 2):
        if set(pair) != {"A", "B"}:
            assert effect(*pair)[0] == pytest.approx(0.0, abs=1e-12)


def test_paired_scatter_cancels_and_unpaired_scatter_widens_the_interval():
    f = factorial.clearance_factors(synthetic())
    terms = {"B": (f["B"][2], f["B"][1])}
    paired = factorial.contrast(synthetic(noise=0.05), "slider_acceleration_rms_settled", None, terms, f)
    unpaired = factorial.contrast(synthetic(noise=0.05, paired=False, seed=3),
                                  "slider_acceleration_rms_settled", None, terms, f)
    truth = EFFECT["B"] + 0.5 * AB
    assert paired[0] == pytest.approx(truth, abs=1e-12)       # a common shift cancels
    assert paired[2] - paired[1] < 1e-12
    assert unpaired[1] < truth < unpaired[2]                  # the interval holds the truth
    assert unpaired[2] - unpaired[1] > 1e-3


def test_a_joints_wear_is_read_where_it_has_clearance(design):
    f = factorial.clearance_factors(design)
    # wear at A = 1e-15 (number of joints with clearance): each other joint adds 1e-15
    for j in ("B", "O", "P"):
        value, _, _ = factorial.contrast(design, "wear_volume", "A", {j: (f[j][2], f[j][1])}, f,
                                         {f["A"][0]: f["A"][2]})
        assert value == pytest.approx(1e-15, rel=1e-12)


def test_the_report_answers_which_joint_and_whether_they_add(design):
    text = format_sweep_summary(design)
    assert "two-level design over joints A, B, O, P" in text
    assert "largest effect: clearance at B" in text
    assert "A and B together minus each alone: -0.4" in text and "they do not add" in text
    assert "worn volume at A" in text and "(cases with clearance at A)" in text
    assert max(map(len, text.splitlines())) <= 100


def test_a_sweep_without_two_switched_joints_has_no_such_section(design):
    one = design.isel(A_clearance=1, O_clearance=0, P_clearance=0)
    assert factorial.factorial_lines(one) == []


def test_the_effects_figure_and_its_refusal(tmp_path, design):
    path = write_netcdf_atomic(design, tmp_path / "mixed.nc")
    out = tmp_path / "effects.png"
    result = CliRunner().invoke(main, ["plot", str(path), "--kind", "effects", "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert out.stat().st_size > 0
    one = write_netcdf_atomic(design.isel(A_clearance=1, O_clearance=0, P_clearance=0),
                              tmp_path / "one.nc")
    result = CliRunner().invoke(main, ["plot", str(one), "--kind", "effects", "-o",
                                       str(tmp_path / "x.png")])
    assert result.exit_code == 2
    assert "switches the clearance of two or more joints" in result.output
    assert not (tmp_path / "x.png").exists()


# ------------------------------------- issue 41 item 9: intervals that hold the run's length
#: The settled-RMS metric and its drift between the settled window's halves.
RMS, DRIFT = factorial.VIBRATION[0], factorial.RUN_LENGTH[factorial.VIBRATION[0]]


def test_a_steady_window_has_no_drift_and_a_settling_one_has():
    """The halves' RMS of a steady sine over whole periods are its amplitude / sqrt 2; a
    decaying ringing makes the second half's smaller."""
    t = np.linspace(0.0, 10.0, 100_001)
    steady = np.sqrt(2.0) * np.sin(2 * np.pi * t)
    first, second = summary.settled_halves_rms(t, steady, 2.0)
    assert first == pytest.approx(1.0, rel=1e-3) and second == pytest.approx(1.0, rel=1e-3)
    ringing = steady + 3.0 * np.exp(-t / 2.0) * np.sin(2 * np.pi * 37.0 * t)
    first, second = summary.settled_halves_rms(t, ringing, 2.0)
    assert second < first
    assert np.isnan(summary.settled_halves_rms(t, steady, 20.0)[0])     # no settled window


def test_the_halves_are_whole_revolutions_so_a_steady_motion_does_not_drift():
    """A periodic motion with odd and even harmonics, 5 settled revolutions from a start
    phase of 20 degree: cut at the window's middle (2.5 revolutions each) the halves differ;
    the first and last 2 whole revolutions do not."""
    t = np.arange(0.0, 10.0 + 1e-9, 1e-3)
    theta = 2 * np.pi * t + np.deg2rad(20.0)
    acc = np.cos(theta) + 0.4 * np.cos(2 * theta + 0.3) + 0.2 * np.sin(3 * theta)
    middle = summary.settled_halves_rms(t, acc, 5.0)
    whole = summary.settled_halves_rms(t, acc, 5.0, period=1.0)
    assert abs(middle[1] - middle[0]) > 1e-3
    assert whole[1] - whole[0] == pytest.approx(0.0, abs=1e-9)
    assert np.isnan(summary.settled_halves_rms(t, acc, 9.5, period=1.0)[0])   # under 2 revolutions


def test_the_interval_adds_the_run_length_term_in_quadrature():
    """h = sqrt(h_m^2 + h_r^2), h_r the RMS over the members of the drift's contrast."""
    design = synthetic(noise=0.05, paired=False, seed=3)
    f = factorial.clearance_factors(design)
    terms = {"B": (f["B"][2], f["B"][1])}
    members_only = factorial.contrast(design, RMS, None, terms, f)
    # the drift: 0.1 m s-2 more in every member where B has clearance, so its contrast is 0.1
    drift = xr.zeros_like(design[RMS]) + 0.1 * (design["B_clearance"] > 0)
    with_drift = design.assign({DRIFT: drift})
    value, low, high = factorial.contrast(with_drift, RMS, None, terms, f)
    assert value == members_only[0]
    h_m = members_only[2] - members_only[0]
    assert high - value == pytest.approx(np.hypot(h_m, 0.1), rel=1e-12)
    assert value - low == pytest.approx(high - value, rel=1e-12)
    assert factorial.contrast_parts(with_drift, RMS, None, terms, f)[2] == pytest.approx(0.1)
    # the worn volume has no drift twin: its interval is the members' alone
    assert factorial.contrast_parts(with_drift, "wear_volume", "A", {"B": (f["B"][2], f["B"][1])},
                                    f, {f["A"][0]: f["A"][2]})[2] == 0.0


def _ringing_sweep(revolutions: float, members: int = 4) -> tuple[xr.Dataset, float]:
    """A 2^2 (A, B) x member sweep of slider accelerations built from time series with a known
    long-run answer: each design a steady 1 Hz motion of RMS L (B adds 0.5, A 0.2) plus, where
    B has clearance, a ringing of 40 Hz that decays with a 3 s time constant (as a start-up
    transient that has not died out by the settled window); members differ by a tiny phase
    (crank phase within +-5 degree). Settled window: the second half of ``revolutions`` s.
    Returns the sweep and the true effect of B in the long run (the ringing gone)."""
    level = {(0, 0): 1.5, (1, 0): 1.7, (0, 1): 2.0, (1, 1): 2.2}
    t = np.arange(0.0, revolutions, 1e-3)
    start = revolutions / 2.0
    settled = summary.is_settled(t, start)
    rms = np.empty((2, 2, members))
    drift = np.empty((2, 2, members))
    for (a, b), level_ab in level.items():
        for k in range(members):
            phase = np.deg2rad(5.0) * (k - (members - 1) / 2) / members
            acc = np.sqrt(2.0) * level_ab * np.sin(2 * np.pi * t + phase)
            if b:
                acc = acc + 4.0 * np.exp(-t / 3.0) * np.sin(2 * np.pi * 40.0 * t + 3 * phase)
            rms[a, b, k] = np.sqrt(np.mean(acc[settled] ** 2))
            first, second = summary.settled_halves_rms(t, acc, start)
            drift[a, b, k] = second - first
    dims = ("A_clearance", "B_clearance", "member")
    coords = {"A_clearance": ("A_clearance", [0.0, C], {"config_key": "joints.A.clearance"}),
              "B_clearance": ("B_clearance", [0.0, C], {"config_key": "joints.B.clearance"}),
              "member": ("member", np.arange(members)), "joint": ("joint", ["A", "B"])}
    ds = xr.Dataset({RMS: (dims, rms, {"units": "m s-2"}), DRIFT: (dims, drift, {"units": "m s-2"}),
                     "status": (dims, np.full(rms.shape, "ok"))}, coords=coords)
    ds.attrs["sweep_dims"] = " ".join(dims)
    ds.attrs["sweep_store"] = "summary"
    return ds.merge(ensemble_statistics(ds[[RMS, DRIFT, "status"]])), 0.5


def test_the_interval_of_a_run_still_settling_holds_the_long_run_answer():
    """Known answer: B's effect in the long run is 0.5 m s-2. In 10 s (5 settled) the ringing
    is still there; the members agree on it, so their spread alone gives an interval that
    misses the answer (the interval before the run-length term), while the run-length term
    covers it, and doubling the run moves the effect within the shorter run's interval."""
    short, truth = _ringing_sweep(10.0)
    f = factorial.clearance_factors(short)
    terms = {"B": (f["B"][2], f["B"][1])}
    value, h_m, h_r = factorial.contrast_parts(short, RMS, None, terms, f)
    assert h_m > 0.0                                         # the members do scatter
    assert not value - h_m <= truth <= value + h_m           # but their spread alone misses it
    _, low, high = factorial.contrast(short, RMS, None, terms, f)
    assert low <= truth <= high
    doubled, _ = _ringing_sweep(20.0)
    longer = factorial.contrast(doubled, RMS, None, terms, f)[0]
    assert low <= longer <= high
    assert abs(longer - truth) < abs(value - truth)          # and is nearer the answer


def test_a_steady_run_keeps_the_members_interval():
    """With the ringing gone before the settled window, the run-length term is negligible."""
    steady, truth = _ringing_sweep(80.0)
    f = factorial.clearance_factors(steady)
    value, h_m, h_r = factorial.contrast_parts(steady, RMS, None, {"B": (f["B"][2], f["B"][1])}, f)
    assert value == pytest.approx(truth, abs=1e-3)
    assert h_r < 1e-3 and h_m < 1e-3


# ------------------------------------------------ issue 41 item 9: effects per speed
def test_an_effect_that_changes_sign_with_the_speed_is_given_at_each_speed():
    """A's effect: -0.3 at 60 r/min, +0.3 at 120 (0 averaged over both): the report gives it
    at each speed and says its sign changes; B's, the same sign at both, is given once."""
    design = synthetic(a_by_speed=0.3)
    f = factorial.clearance_factors(design)
    changes = factorial.sign_changes(design, RMS, None, {"A": (f["A"][2], f["A"][1])}, f)
    assert list(changes) == ["speed_rpm"]
    (s60, at60), (s120, at120) = changes["speed_rpm"]
    assert (s60, s120) == ("60", "120")
    assert at60[0] == pytest.approx(-0.3, abs=1e-12) and at120[0] == pytest.approx(0.3, abs=1e-12)
    assert factorial.sign_changes(design, RMS, None, {"B": (f["B"][2], f["B"][1])}, f) == {}
    text = format_sweep_summary(design)
    assert "its sign changes with speed_rpm" in text
    assert "speed_rpm 60: -0.3" in text and "speed_rpm 120: +0.3" in text
    assert "its sign changes" not in format_sweep_summary(synthetic())
    assert max(map(len, text.splitlines())) <= 100


def test_the_effects_figure_marks_an_effect_at_each_speed_where_its_sign_changes():
    """A's markers at -0.3 (60 r/min) and +0.3 (120 r/min) on its row; none for B."""
    from matplotlib.figure import Figure

    from clearsweep.plotting.effects import _draw_effects

    fig = Figure()
    _draw_effects(fig, synthetic(a_by_speed=0.3))
    ax = fig.axes[0]                                   # the slider's vibration
    rows = [t.get_text() for t in ax.get_yticklabels()]
    marks = {line.get_label(): (float(line.get_xdata()[0]), float(line.get_ydata()[0]))
             for line in ax.get_lines() if line.get_label().startswith("at ")}
    assert set(marks) == {"at 60 r/min", "at 120 r/min"}
    assert marks["at 60 r/min"] == pytest.approx((-0.3, rows.index("clearance at A")))
    assert marks["at 120 r/min"] == pytest.approx((0.3, rows.index("clearance at A")))
    plain = Figure()
    _draw_effects(plain, synthetic())
    assert not [line for line in plain.axes[0].get_lines() if line.get_label().startswith("at ")]


def test_the_pages_script_compares_a_doubled_run_against_the_intervals(tmp_path, capsys):
    """docs/mixed_clearances.py FILE DOUBLED: a run that moves B's effect by more than its
    interval is counted outside; the same file twice moves nothing."""
    import importlib.util
    from pathlib import Path

    spec = importlib.util.spec_from_file_location(
        "mixed_page", Path(__file__).resolve().parents[1] / "docs" / "mixed_clearances.py")
    page = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(page)
    first = synthetic(noise=0.05, paired=False, seed=3)
    path = write_netcdf_atomic(first, tmp_path / "mixed.nc")
    page.main(str(path), str(path))
    out = capsys.readouterr().out
    assert "0 of 30 outside" in out                    # 4 effects + 6 pairs, averaged and at 2 speeds
    assert "h_m" in out and "h_r 0.000" in out         # no drift in the file: no run-length term
    moved = first.copy()
    moved[RMS] = first[RMS] + 1.0 * (first["B_clearance"] > 0)
    page.main(str(path), str(write_netcdf_atomic(moved, tmp_path / "doubled.nc")))
    out = capsys.readouterr().out
    assert "B                        " in out and "OUTSIDE" in out
    assert "3 of 30 outside" in out                    # B averaged and at each speed


def test_the_pages_script_compares_a_doubled_run_of_fewer_members_over_those_members(
        tmp_path, capsys):
    """A doubled run of the first 2 members, equal to the first run's values there, moved
    nothing, though the 2 members' mean differs from the 6 members'."""
    import importlib.util
    from pathlib import Path

    spec = importlib.util.spec_from_file_location(
        "mixed_page", Path(__file__).resolve().parents[1] / "docs" / "mixed_clearances.py")
    page = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(page)
    first = synthetic(noise=0.05, paired=False, seed=3)
    path = write_netcdf_atomic(first, tmp_path / "mixed.nc")
    two = first.isel(member=slice(0, 2))
    page.main(str(path), str(write_netcdf_atomic(two, tmp_path / "doubled.nc")))
    out = capsys.readouterr().out
    assert "0 of 30 outside" in out and "(moved +0.000" in out


def test_a_drift_that_could_not_be_measured_leaves_no_interval():
    """A settled window under 2 revolutions has no whole halves (NaN drift): the effect is
    given without an interval, not with the members' alone."""
    design = synthetic(noise=0.05, paired=False, seed=3)
    f = factorial.clearance_factors(design)
    unmeasured = design.assign({DRIFT: xr.full_like(design[RMS], np.nan)})
    value, low, high = factorial.contrast(unmeasured, RMS, None, {"B": (f["B"][2], f["B"][1])}, f)
    assert np.isfinite(value) and np.isnan(low) and np.isnan(high)
