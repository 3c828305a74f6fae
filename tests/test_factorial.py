"""A clearance sweep read as a two-level design (clearsweep.analysis.factorial): main effects
and interactions of known synthetic responses are recovered exactly, the members' intervals
cover the truth and shrink with paired scatter, and the report and the figure answer."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
import xarray as xr
from click.testing import CliRunner

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


def synthetic(noise: float = 0.0, paired: bool = True, seed: int = 0) -> xr.Dataset:
    """A 2^4 x speed x member summary sweep whose vibration is BASE + sum of the effects of
    the joints with clearance + AB where A and B both have it (+ the member's scatter: the
    same in every design where ``paired``), and whose wear at each joint is 1e-15 m^3 x
    (1 + the number of other joints with clearance) where it has clearance (NaN where ideal)."""
    rng = np.random.default_rng(seed)
    shape = (2, 2, 2, 2, 2, MEMBERS)
    member_shift = rng.standard_normal(MEMBERS) * noise
    vib = np.empty(shape)
    wear = np.full(shape + (4,), np.nan)
    for a, b, o, p, s in itertools.product((0, 1), repeat=5):
        on = {"A": a, "B": b, "O": o, "P": p}
        value = BASE + sum(EFFECT[j] * on[j] for j in JOINTS) + AB * a * b + 0.1 * s
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
