"""The host's features on the planar slider-crank (issue 44): its results name their
mechanism, the slider's labels hold for either guide, and the orbit figure draws each joint
in the mechanism's plane. Short runs: the benchmark's speed and clearance for a few
revolutions."""

from __future__ import annotations

import numpy as np
import pytest

from clearsweep.analysis import is_planar, mechanism_kind
from clearsweep.config import MECHANISM_KINDS
from clearsweep.plotting import plot
from clearsweep.simulation import simulate
from clearsweep.variables import CASE_VARIABLES, LIFE_VARIABLES, MECHANISM_NAMES

TEST_DPI = 40

#: The published benchmark's speed and clearance (B, 0.5 mm in a 10 mm socket), three
#: revolutions at 5000 r/min; A with the same clearance, so that two socket frames show.
SLIDER_CRANK = {
    "name": "sc",
    "mechanism": {"kind": "slider_crank", "preset": "flores_benchmark", "speed_rpm": 5000.0},
    "joints": {"A": {"clearance": 5.0e-4, "socket_radius": 0.01},
               "B": {"clearance": 5.0e-4, "socket_radius": 0.01}},
    "solver": {"dt": 1.0e-5, "revolutions": 3},
    "metrics": {"settle_revolutions": 1},
    "wear": {"map": [18, 36]},
}


@pytest.fixture(scope="module")
def sc():
    ds = simulate(SLIDER_CRANK)
    assert str(ds["status"].values) == "ok"
    return ds


def test_every_mechanism_has_a_name():
    assert set(MECHANISM_NAMES) == set(MECHANISM_KINDS)


def test_a_case_file_names_its_mechanism(sc):
    """(was: the slider-crank's file said "clearsweep RSSP mechanism simulation" and had no
    mechanism attribute); the RSSP's title stays."""
    assert sc.attrs["mechanism"] == "slider_crank"
    assert sc.attrs["title"] == "clearsweep slider-crank mechanism simulation"
    assert mechanism_kind(sc) == "slider_crank" and is_planar(sc)
    rssp = simulate({"solver": {"duration": 1e-3}})
    assert rssp.attrs["title"] == "clearsweep RSSP mechanism simulation"
    assert rssp.attrs["mechanism"] == "rssp" and not is_planar(rssp)


def test_mechanism_of_a_file_without_the_attribute(sc):
    """A file written before the attribute: its config's mechanism.kind, else the RSSP."""
    older = sc.copy()
    del older.attrs["mechanism"]
    assert mechanism_kind(older) == "slider_crank"
    older.attrs["config"] = "name: old\n"
    assert mechanism_kind(older) == "rssp" and not is_planar(older)


def test_slider_labels_hold_for_either_guide(sc):
    """(was: "slider position x_B" and a motion error |x_slider - x_ideal|; the slider-crank's
    guide runs along y)."""
    position = sc["slider_position"].attrs["long_name"]
    assert position == "slider position along its guide"
    # the slider-crank's slider moves along y: its stroke 2 l2 = 0.1 m, longer by at most
    # the two clearances at each end (2 x 1 mm) and the contacts' penetrations
    assert float(np.ptp(sc["slider_position"].values)) == pytest.approx(0.1, abs=2.5e-3)
    for text in (position, sc["slider_position"].attrs["description"],
                 LIFE_VARIABLES["slider_motion_error_settled"].description,
                 CASE_VARIABLES["slider_position"].description):
        assert "x_B" not in text and "x_slider" not in text
    assert "along its guide" in LIFE_VARIABLES["slider_motion_error_settled"].description


def test_orbit_draws_each_joint_in_the_mechanism_plane(tmp_path, sc):
    """One panel per joint, the plane of the crank's: the slider-crank's pins A and B are
    bearings, each journal in its bearing's y-z plane (A's frame turns with the rod, y along
    it) (was: A drawn as a ball in its socket on the rod, d_x along the rod and d_z, titled
    "joint A"). A file written when the pins were balls (its recorded types spherical) draws
    them as balls, each in the plane its offsets span (was, before either: three panels per
    joint, xy, xz and yz, two of them a line along the axis off the plane)."""
    fig = plot(sc, "orbit", tmp_path / "orbit.png", dpi=TEST_DPI)
    axes = [(ax.get_xlabel(), ax.get_ylabel(), ax.get_title()) for ax in fig.axes]
    assert len(axes) == 2
    for (x_label, y_label, title), name in zip(axes, ("A", "B"), strict=True):
        assert (x_label, y_label) == ("d_y [mm]", "d_z [mm]")
        assert title == f"bearing {name}: journal in the bearing's plane, yz"
    # the figure's title names journals in bearings where every panel is one (was: "Ball-
    # centre orbit in the socket frame" over two bearings)
    assert fig.get_suptitle().startswith("Journal-centre orbit in the bearing's frame")
    older = sc.copy()
    older.attrs = {**sc.attrs, "joint_A_type": "spherical", "joint_B_type": "spherical"}
    fig = plot(older, "orbit", tmp_path / "older.png", dpi=TEST_DPI)
    assert fig.get_suptitle().startswith("Ball-centre orbit in the socket frame")
    title_a, title_b = (ax.get_title() for ax in fig.axes)
    assert title_a.startswith("joint A: the mechanism's plane")
    assert title_b.startswith("joint B: the mechanism's plane") and "off it" not in title_b


def test_orbit_names_a_departure_from_the_plane(tmp_path, sc):
    """A ball's centre that leaves the plane by more than round-off says by how much in its
    panel (a file written when the slider-crank's pins were balls: a bearing's offset has
    no axial part)."""
    off = sc.copy(deep=True)
    off.attrs = {**sc.attrs, "joint_A_type": "spherical", "joint_B_type": "spherical"}
    off["ball_offset"].loc[{"joint": "B", "axis": "x"}] = 2.0e-5
    fig = plot(off, "orbit", tmp_path / "orbit.png", dpi=TEST_DPI)
    title = fig.axes[1].get_title()
    assert "off it, |d_x| up to 0.02 mm" in title
    # the RSSP's three planes per joint stay
    rssp = off.copy()
    rssp.attrs["mechanism"] = "rssp"
    assert len(plot(rssp, "orbit", tmp_path / "rssp.png", dpi=TEST_DPI).axes) == 6


def test_sweep_file_names_its_mechanism(tmp_path):
    """(was: "clearsweep RSSP mechanism parameter sweep" for a sweep of slider-cranks)."""
    from clearsweep.sweeping import run_sweep

    base = {**SLIDER_CRANK, "joints": {"B": {"clearance": 5.0e-4, "socket_radius": 0.01}},
            "solver": {"dt": 1.0e-5, "revolutions": 1}}
    ds = run_sweep({"name": "s", "store": "summary", "base": base,
                    "sweep": {"grid": {"joints.B.clearance": [2.5e-4, 5.0e-4]}}},
                   tmp_path / "s.nc", workers=1, progress=False)
    assert ds.attrs["mechanism"] == "slider_crank"
    assert ds.attrs["title"] == "clearsweep slider-crank mechanism parameter sweep"
    assert is_planar(ds)


#: A short life run of the benchmark: blocks of two revolutions (24 ms at 5000 r/min).
SLIDER_CRANK_LIFE = {
    **{k: v for k, v in SLIDER_CRANK.items() if k != "solver"},
    "joints": {"B": {"clearance": 5.0e-4, "socket_radius": 0.01}},
    "solver": {"dt": 1.0e-5},
    "life": {"cycles": 1.0e4, "block_revolutions": 2, "max_motion_error": 2.0e-3,
             "max_blocks": 2},
}


def test_life_reads_the_settled_window_of_a_fast_crank():
    """The default settling (0.05 s, four revolutions at 5000 r/min) lies beyond a block of
    two: a settled limit is refused naming the settle key (was: every block's settled
    statistics NaN and the limit 'not reached'); settled within the block, the run reads
    the slider's motion error along its guide, about the clearance (0.5 mm)."""
    from clearsweep.schema import ConfigError
    from clearsweep.service_life import life

    with pytest.raises(ConfigError, match="metrics.settle_time: got 0.05"):
        life({**SLIDER_CRANK_LIFE, "metrics": {}})
    ds = life(SLIDER_CRANK_LIFE)
    assert ds.attrs["mechanism"] == "slider_crank"
    error = ds["slider_motion_error_settled"].values
    assert np.isfinite(error).all()
    assert (error > 0.5 * 5.0e-4).all() and (error < 2.0e-3).all()


def test_lyapunov_twin_stays_in_the_plane():
    """The twin runs of the slider-crank's Lyapunov exponent perturb and measure its state
    in the crank's plane alone (was: every component, the ones across the plane too, which a
    planar mechanism does not have); the RSSP's every position, angle and rate as before."""
    from clearsweep.config import load_config
    from clearsweep.core import layout as L
    from clearsweep.simulation import OFF_PLANE_STATE, lyapunov_scale, preflight

    scale = lyapunov_scale(preflight(load_config(SLIDER_CRANK)))
    across = list(OFF_PLANE_STATE) + [L.Y_QD + i for i in OFF_PLANE_STATE]
    assert np.isinf(scale[across]).all()
    # in the plane: the bodies' y and z, the crank angle, the rod's beta3, their rates
    inside = [L.Y_R2 + 1, L.Y_R2 + 2, L.Y_CRANK_ANGLE, L.Y_R3 + 1, L.Y_R3 + 2, L.Y_ROD_BETA,
              L.Y_R4 + 1, L.Y_R4 + 2]
    assert np.isfinite(scale[inside + [L.Y_QD + i for i in inside]]).all()
    rssp = lyapunov_scale(preflight(load_config({"joints": {"B": {"clearance": 2.5e-4}}})))
    assert np.isfinite(rssp[:L.Y_WORK]).all()
