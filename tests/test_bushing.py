"""The elastic bushing joint type (core/bushing.py, docs/physics.md 3.8) at A, B and O.

Every kernel run here uses one build, :data:`BUILD` (every joint's clearance and a bushing at
A, B and O, each tested at run time), the ideal references included: one cold compile for
the file (about 45 s) rather than one per joint set.

Tolerances of "a stiff bushing moves as the ideal joint" (k = 1e9 N/m, damping near
critical on the joint's lightest mass, so that the start's transient, the bushing loaded
from zero deflection, dies within about 0.1 ms):

- slider position: the bushing's deflection e = F / k is the only difference from the ideal
  joint, a few 1e-8 m under the mechanism's 10-30 N joint loads; the slider moves by at most
  that (the linkage passes a joint's offset to the slider with a factor of order 1). The
  test accepts 2 F_max / k, F_max the bushing's largest force in the run (measured: 1.3e-9 m
  at O, 7.5e-9 m with all three, against 2 F_max / k = 6e-8 m);
- slider acceleration after the transient (t >= 2 ms): the deflection's own acceleration,
  about e times the square of the loads' frequencies (crank orders up to ~10 at 1 rev/s),
  some 1e-5 m/s^2; the test accepts 1e-4 of the peak |acceleration| (1.7e-4 m/s^2;
  measured 7e-6 at O and 2.5e-6 with all three). A bushing 100 times softer misses it.
"""

from __future__ import annotations

import inspect

import numpy as np
import pytest
from click.testing import CliRunner

from clearsweep.config import load_config
from clearsweep.core import bushing, joints, jointset, spherical
from clearsweep.core import layout as L
from clearsweep.params import joint_attributes, kernel_build
from clearsweep.simulation import preflight, run_kernel

#: The build every run here uses: clearance anywhere, a bushing at A, B or O.
BUILD = jointset.ALL | jointset.named("A(bushing)", "B(bushing)", "O(bushing)")

STIFF = "[1e9,1e9]"
#: about critical on the lightest mass a joint meets (0.3-1.3 kg): 2 sqrt(k m) = 3.5e4-7e4
CRITICAL = "[6e4,6e4]"
SHORT = ["solver.duration=0.02", "joints.A.clearance=0", "joints.B.clearance=0"]


def bushed(*names: str, stiffness: str = STIFF, damping: str = CRITICAL) -> list[str]:
    out = []
    for name in names:
        out += [f"joints.{name}.type=bushing", f"joints.{name}.bushing_stiffness={stiffness}",
                f"joints.{name}.bushing_damping={damping}"]
    return out


def run(overrides):
    cfg = load_config({}, overrides)
    packed = preflight(cfg)
    raw = run_kernel(packed, build=BUILD)
    assert raw.status == "ok", raw.status
    return cfg, packed, raw


@pytest.fixture(scope="module")
def ideal():
    return run(SHORT)[2]


@pytest.mark.parametrize("names", [("A",), ("B",), ("O",), ("A", "B", "O")])
def test_a_stiff_bushing_moves_as_the_ideal_joint(ideal, names):
    _, packed, raw = run(SHORT + bushed(*names))
    assert jointset.of(packed.jp) == jointset.named(*(f"{n}(bushing)" for n in names))
    rows = [joints.INDEX[n] for n in names]
    fmax = max(np.nanmax(raw.d[:, L.D_FN + j]) for j in rows)
    assert fmax > 1.0       # the bushing carries the joint's load
    x, x0 = raw.y[:, L.Y_SLIDER_X], ideal.y[:, L.Y_SLIDER_X]
    assert np.max(np.abs(x - x0)) <= 2.0 * fmax / 1e9
    later = raw.t >= 0.002
    acc, acc0 = raw.d[later, L.D_SLIDER_ACC], ideal.d[later, L.D_SLIDER_ACC]
    assert np.max(np.abs(acc - acc0)) <= 1e-4 * np.max(np.abs(acc0))
    # the joint's offset is the deflection F / k, not a clearance's
    for j in rows:
        ecc = raw.d[:, L.D_ECC + j]
        assert np.nanmax(ecc) <= 1.01 * np.nanmax(raw.d[:, L.D_FN + j]) / 1e9 + 1e-12


def test_a_soft_bushing_does_not_pass_for_the_ideal_joint(ideal):
    """The tolerance above has teeth: 1e7 N/m at O (its damping critical again) misses it."""
    _, _, raw = run(SHORT + bushed("O", stiffness="[1e7,1e7]", damping="[6e3,6e3]"))
    later = raw.t >= 0.002
    acc, acc0 = raw.d[later, L.D_SLIDER_ACC], ideal.d[later, L.D_SLIDER_ACC]
    assert np.max(np.abs(acc - acc0)) > 1e-4 * np.max(np.abs(acc0))


def test_the_bushing_books_its_energy():
    """The default (rubber) bushings at A, B and O: the spring's energy counts with the
    mechanism's (D_UEL, as a contact's elastic energy) and the damper's power as
    dissipated, so that the residual stays at rounding; without the spring's energy the
    balance would miss by its size."""
    _, packed, raw = run(["solver.duration=0.02"] + [
        item for n in "ABO" for item in (f"joints.{n}.type=bushing", f"joints.{n}.clearance=0")])
    assert raw.deepest <= 1
    d, y = raw.d, raw.y
    k = packed.jp[:, L.J_K_RADIAL]
    uel = d[:, L.D_UEL:L.D_UEL + L.N_JOINTS]
    assert np.all(uel[-1, :3] > 0.0)
    # at O (axial ideal) U = k_r e^2 / 2 with e the offset in the bearing's plane
    e_o = d[-1, L.D_OFFSET + 3 * joints.INDEX["O"] + 1:L.D_OFFSET + 3 * joints.INDEX["O"] + 3]
    assert uel[-1, joints.INDEX["O"]] == pytest.approx(0.5 * k[joints.INDEX["O"]] * e_o @ e_o,
                                                       rel=1e-9)
    ke, pe = d[:, L.D_KE], d[:, L.D_PE_GRAV]
    work, diss = y[:, L.Y_WORK], y[:, L.Y_DISS]
    assert diss[-1] > 0.0
    residual = ke + pe + uel.sum(axis=1) - work + diss - (ke[0] + pe[0] + uel[0].sum())
    missing = ke + pe - work + diss - (ke[0] + pe[0])
    scale = max(np.max(np.abs(work)), np.max(ke))
    assert np.max(np.abs(residual)) <= 1e-9 * scale
    assert np.max(np.abs(residual)) < 1e-3 * np.max(np.abs(missing))
    assert raw.residual_max <= 1e-9 * scale


def test_the_bushing_keeps_the_joint_type_signatures():
    """gap and contact take the arguments of the spherical joint's, which it stands in for;
    a bushing does not wear: it never touches (no contact points), its wear surface is
    zero, and its gap reports no penetration."""
    for name in ("gap", "contact"):
        assert (inspect.signature(getattr(bushing, name).py_func)
                == inspect.signature(getattr(spherical, name).py_func))
    assert bushing.CONTACTS == 0
    assert bushing.wear_surface(np.zeros((4, L.N_JP)), 0, 1e-6, 1e-4, (1.0, 0.0, 0.0)) == (0.0,) * 5
    ident = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)
    geo = bushing.gap.py_func(np.zeros((4, L.N_JP)), 0, None, None, 0, (1e-6, 0.0, 0.0),
                              (0.0, 0.0, 0.0), ident)
    assert geo[0] == pytest.approx(1e-6) and geo[-1] == 0.0 and geo[-2] == 0.0


def test_the_rate_of_one_direction_is_the_oscillator_s():
    """bushing.rate on a mobility of one free direction is the root of m s^2 + c s + k."""
    jp = np.zeros((4, L.N_JP))
    jp[0, L.J_K_RADIAL], jp[0, L.J_C_RADIAL] = 4e6, 0.0
    jp[0, L.J_K_AXIAL], jp[0, L.J_C_AXIAL] = 1e9, 1e4
    wp = (0.0, 0.0, 0.0, 1.0 / 0.25, 0.0, 0.0)      # only y moves, 0.25 kg
    r = bushing.rate.py_func(jp, 0, wp, (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
    assert r == pytest.approx(np.sqrt(4e6 / 0.25), rel=1e-12)


def test_the_rate_reads_the_axis_of_the_socket_s_body():
    """The protocol's force_rate of a bushing at A: its axis is the socket body's (the
    rod's) local x axis at the state. On a mobility of the global y direction alone, the
    rod unrotated rates the radial spring, the rod turned a quarter turn (alpha3 = pi/2:
    its x axis along global y) the axial one: the oscillators' sqrt(k / m)."""
    from clearsweep.core.kinematics import rotation, trig
    from clearsweep.core.work import Model

    jp = np.zeros((4, L.N_JP))
    jp[0, L.J_K_RADIAL], jp[0, L.J_K_AXIAL] = 4e6, 1e9
    model = Model(np.zeros(L.N_P), jp, np.zeros((4, L.N_S)), np.zeros((4, 1, 1)))
    wp = (0.0, 0.0, 0.0, 1.0 / 0.25, 0.0, 0.0)      # only y moves, 0.25 kg
    dg = np.zeros(L.N_D)
    y = np.zeros(L.N_Y)
    assert bushing.rate_point(0, model, dg) == (True, True, (0.0,) * 3, (0.0,) * 3)
    assert bushing.force_rate(0, model, dg, wp, y, 0.0) == pytest.approx(
        np.sqrt(4e6 / 0.25), rel=1e-12)
    y[L.Y_PHI3] = 0.5 * np.pi
    assert np.allclose(rotation(trig(*y[L.Y_PHI3:L.Y_PHI3 + 3]))[0::3], (0.0, 1.0, 0.0))
    assert bushing.force_rate(0, model, dg, wp, y, 0.0) == pytest.approx(
        np.sqrt(1e9 / 0.25), rel=1e-12)


def test_the_build_holds_the_case_s_bushings():
    cfg = load_config({}, ["joints.A.clearance=0", "joints.B.clearance=2.5e-4",
                           "joints.O.type=bushing"])
    build = kernel_build(cfg)
    assert build >> (L.N_JOINTS + joints.INDEX["O"]) & 1
    assert "O(bushing)" in jointset.label(build).split(",")
    jointset.check(jointset.named("O(bushing)"), build)
    with pytest.raises(ValueError, match="O\\(bushing\\)"):
        jointset.check(jointset.named("O(bushing)"), jointset.ALL)


def test_the_dense_reference_agrees_with_the_kernel_on_bushings():
    """tests/reference.py's KKT solve with the bushing's force written from its formula,
    at a state where each bushing is deflected and moving, against the kernel's evaluate
    (tolerances of tests/test_reference.py)."""
    import reference as ref_mod
    from test_reference import RTOL, perturb

    from clearsweep.config import resolve_materials
    from clearsweep.core.dynamics import NZ, VZ_ROWS, evaluate
    from clearsweep.core.work import Model, Solve
    from clearsweep.params import pack

    cfg = load_config({}, ["joints.A.clearance=0", "joints.B.clearance=0"] + [
        item for n in "ABO" for item in (f"joints.{n}.type=bushing",
                                         f"joints.{n}.bushing_stiffness=[2e6,5e5]",
                                         f"joints.{n}.bushing_damping=[400,100]")])
    packed = pack(cfg, resolve_materials(cfg))
    p, jp = packed.p, packed.jp
    rng = np.random.default_rng(7)
    # deflections of some micrometres and their rates at every joint
    y = perturb(packed.y0, rng, pos=5e-6, ang=2e-5, vel=1e-3, rate=1e-2)
    dg = np.zeros(L.N_D)
    dy = np.zeros(L.N_Y)
    st = evaluate(0.013, y, Model(p, jp, np.zeros((L.N_JOINTS, L.N_S)), np.zeros((L.N_JOINTS, 1, 1))),
                  dy, dg, True, Solve(np.zeros((NZ, NZ)), np.zeros((NZ, NZ)), np.zeros((NZ, NZ)),
                                      np.zeros((VZ_ROWS, NZ))), jointset.Build(BUILD))
    assert st == L.ST_OK
    ref = ref_mod.evaluate(0.013, y, p, jp)
    qdd = dy[L.Y_QD:L.Y_QD + L.N_Q]
    for b in range(3):
        for part in (slice(6 * b, 6 * b + 3), slice(6 * b + 3, 6 * b + 6)):
            scale = max(1.0, np.max(np.abs(ref.qdd[part])))
            assert np.max(np.abs(qdd[part] - ref.qdd[part])) <= RTOL * scale, (b, part)
    weight = 9.81 * (p[L.P_M2] + p[L.P_M3] + p[L.P_M4])
    force_scale = max(weight, np.max(np.abs(ref.joint_force)))
    kernel_force = dg[L.D_JOINT_FORCE:L.D_JOINT_FORCE + 3 * L.N_JOINTS].reshape(L.N_JOINTS, 3)
    for j in range(3):
        assert np.max(np.abs(kernel_force[j] - ref.joint_force[j])) <= RTOL * force_scale, j
        assert np.linalg.norm(ref.contacts[j].force) > 1e-2   # each bushing is loaded
    assert dg[L.D_TORQUE] == pytest.approx(ref.torque, abs=RTOL * force_scale)
    assert dg[L.D_PDISS] == pytest.approx(ref.dissipation, rel=1e-7)


def test_run_reports_o_as_a_bushing(tmp_path):
    """``clearsweep run configs/two_clearances.yaml --set joints.O.type=bushing``: the run's
    dataset says O is a bushing with its stiffness and damping, and the run's report says
    so."""
    import xarray as xr

    from clearsweep.cli import main

    out = tmp_path / "o.nc"
    result = CliRunner().invoke(main, ["run", "configs/two_clearances.yaml", "--set",
                                       "joints.O.type=bushing", "--set", "solver.duration=0.01",
                                       "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert "joint O: bushing" in result.output
    with xr.open_dataset(out) as ds:
        assert ds.attrs["joint_O_type"] == "bushing"
        assert ds.attrs["joint_O_bushing_radial_stiffness_N_per_m"] == 1e6
        assert ds.attrs["joint_O_bushing_axial_stiffness_N_per_m"] == 0.0
        assert ds.attrs["joint_O_bushing_radial_damping_N_s_per_m"] == 300.0
        assert ds.attrs["joint_O_bushing_axial_damping_N_s_per_m"] == 0.0
        assert ds.attrs["joint_A_type"] == "spherical"
        assert np.isnan(ds.attrs["joint_A_bushing_radial_stiffness_N_per_m"])
        assert str(ds["status"].values) == "ok"
        # the bushing's deflection is kept as the journal's offset, and drawn as its orbit
        ecc = ds["eccentricity"].sel(joint="O").values
        assert np.nanmax(ecc) > 0.0
        from clearsweep.plotting import figure

        fig = figure(ds.load(), "orbit")
        titles = [ax.get_title() for ax in fig.axes]
        assert any("O (bushing)" in t for t in titles), titles
    report = CliRunner().invoke(main, ["report", str(out)])
    assert report.exit_code == 0, report.output
    assert "joint O: bushing, stiffness 1e+06 / 0 N m-1" in report.output


def test_the_attributes_of_a_bushing():
    cfg = load_config({}, ["joints.B.clearance=0", "joints.B.type=bushing",
                           "joints.B.bushing_stiffness=[3e6,1e6]"])
    from clearsweep.config import resolve_materials
    from clearsweep.params import pack

    attrs = joint_attributes(cfg, pack(cfg, resolve_materials(cfg), seat=False))
    assert attrs["joint_B_type"] == "bushing"
    assert (attrs["joint_B_bushing_radial_stiffness_N_per_m"],
            attrs["joint_B_bushing_axial_stiffness_N_per_m"]) == (3e6, 1e6)
    assert (attrs["joint_B_bushing_radial_damping_N_s_per_m"],
            attrs["joint_B_bushing_axial_damping_N_s_per_m"]) == (300.0, 150.0)
    assert attrs["joint_O_type"] == "revolute"


def test_a_sweep_file_sweeps_the_type_and_the_stiffness(tmp_path):
    """joints.O.type and joints.O.bushing_stiffness are sweep dimensions like any key; the
    bushing's attributes, which vary from case to case, become variables of the sweep."""
    import xarray as xr

    from clearsweep.cli import main

    path = tmp_path / "s.yaml"
    path.write_text("name: bush\nstore: summary\nbase: {joints: {A: {clearance: 2.5e-4}, "
                    "B: {clearance: 2.5e-4}}, solver: {duration: 0.002}, wear: {map: [6, 12]}}\n"
                    "sweep: {grid: {joints.O.type: [revolute, bushing], "
                    "joints.O.bushing_stiffness: [[1.0e6, 5.0e5], [4.0e6, 5.0e5]]}}\n")
    result = CliRunner().invoke(main, ["sweep", str(path), "--dry-run"])
    assert result.exit_code == 0, result.output
    assert "dimension O_type (2): 'revolute', 'bushing'" in result.output
    assert "dimension O_bushing_stiffness (2)" in result.output
    out = tmp_path / "s.nc"
    result = CliRunner().invoke(main, ["sweep", str(path), "-o", str(out), "--workers", "1",
                                       "--no-progress", "-q"])
    assert result.exit_code == 0, result.output
    with xr.open_dataset(out) as ds:
        assert [str(s) for s in ds["status"].values.ravel()] == ["ok"] * 4
        k = ds["joint_O_bushing_radial_stiffness_N_per_m"]
        assert np.isnan(k.sel(O_type="revolute").values).all()
        assert list(k.sel(O_type="bushing").values) == [1e6, 4e6]
