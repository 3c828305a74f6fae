"""Synthetic results datasets with numbers that can be checked by hand.

The datasets go through ``clearsweep.dataset.build_dataset`` (no simulation)
and have the shapes of real ones: 0.2 s sampled every 1 ms, a 36 x 72 wear
map and 360 one-degree projection bins (centres -179.5 ... 179.5 degree).

What the tests may rely on (all set by the constants below):

- ``slider_acceleration`` is a square wave of +-``acc_level`` (switching
  every ``ACC_HALF_PERIOD_S``) with a single spike of ``ACC_SPIKE`` at
  ``ACC_SPIKE_TIME_S`` (inside the first 0.05 s): peak = ``ACC_SPIKE``,
  settled peak = settled RMS = ``acc_level``.
- ``normal_force`` is zero but for one sample of ``NORMAL_FORCE_PEAK[joint]``.
- The every-step statistics (``variables.STATISTICS``) are stored as a kernel would store
  them, from these rows (right-end rule over each row interval, settled window
  t >= ``SETTLE_TIME_S``): settled peak = settled RMS = ``acc_level``.
- ``wear_map`` holds a blob whose largest bin is exactly ``WEAR_MAP_PEAK[joint]``.
- ``wear_projection`` follows ``WEAR_PROFILES``: on every bin centre in
  [lo, hi] the depth falls linearly from ``peak`` at ``peak_angle`` to half
  of it at the farther end, all other bins hold ``SUB_THRESHOLD_DEPTH``
  (below 1e-3 of the peak, so not counted as worn), and the z axis of joint
  A has no wear at all.
- Joint O (the crank's revolute joint) is ideal: no contact, no wear, its statistics NaN
  (counts 0) as the kernel stores an ideal joint's, its joint force the bearing's reaction.
"""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
import yaml

from clearsweep.dataset import bin_centres_deg, build_dataset, write_netcdf_atomic
from clearsweep.variables import AXES, JOINTS

DURATION_S = 0.2
SAMPLE_DT_S = 1.0e-3
OMEGA_RAD_S = 2.0 * np.pi            # 60 r/min
CRANK_M, ROD_M, SLIDER_Z_M = 0.14, 0.38, -0.12   # docs/physics.md section 1
CLEARANCE_M = 2.5e-4
ORBIT_FRACTION = 0.8                 # ball-centre orbit radius / clearance

ACC_LEVEL = 3.0                      # [m s-2]
ACC_HALF_PERIOD_S = 0.02
ACC_SPIKE = 50.0                     # [m s-2]
ACC_SPIKE_TIME_S = 0.01
SETTLE_TIME_S = 0.05
NORMAL_FORCE_PEAK = {"A": 40.0, "B": 120.0, "O": 0.0, "P": 0.0}   # [N]
#: The ideal joints of the synthetic case.
IDEAL = ("O", "P")
NORMAL_FORCE_PEAK_TIME_S = 0.1
WEAR_MAP_SHAPE = (36, 72)
WEAR_MAP_PEAK = {"A": 3.0e-11, "B": 9.0e-11, "O": 0.0, "P": 0.0}   # [m]
WEAR_MAP_PEAK_BIN = {"A": (10, 20), "B": (25, 50), "O": (0, 0), "P": (0, 0)}
N_ANGLE = 360
SUB_THRESHOLD_DEPTH = 1.0e-15        # [m], < 1e-3 of every peak below

#: (joint, axis) -> (lo, hi, peak_angle [degree], peak depth [m]); missing = no wear.
WEAR_PROFILES = {
    ("A", "x"): (-179.5, 179.5, -150.5, 7.5e-11),
    ("A", "y"): (-4.5, 44.5, 44.5, 7.0e-12),
    ("B", "x"): (-10.5, 40.5, 20.5, 8.0e-11),
    ("B", "y"): (-5.5, 46.5, 10.5, 2.7e-11),
    ("B", "z"): (-22.5, 27.5, 27.5, 1.2e-10),
}

#: The sweep: B_coating x B_clearance; per case the B x profile (lo, hi, peak) and the
#: acceleration level. PTFE quarters the depth and widens the worn range by 10 degree.
SWEEP_COATINGS = ("none", "PTFE")
SWEEP_CLEARANCES = (1.0e-4, 2.5e-4)
SWEEP_B_X = {
    ("none", 1.0e-4): (-10.5, 40.5, 4.0e-11),
    ("none", 2.5e-4): (-10.5, 40.5, 8.0e-11),
    ("PTFE", 1.0e-4): (-20.5, 40.5, 1.0e-11),
    ("PTFE", 2.5e-4): (-20.5, 40.5, 2.0e-11),
}
SWEEP_ACC_LEVEL = {"none": 3.0, "PTFE": 1.5}


def angle_centres() -> np.ndarray:
    """Projection bin centres [degree]."""
    return bin_centres_deg(N_ANGLE, -180.0, 180.0)


def projection_profile(lo: float, hi: float, peak_angle: float, peak: float) -> np.ndarray:
    """Depth per angle bin [m]: linear from ``peak`` down to ``peak / 2`` over [lo, hi]."""
    centres = angle_centres()
    inside = (centres >= lo) & (centres <= hi)
    reach = max(peak_angle - lo, hi - peak_angle, 1.0)
    depth = np.full(N_ANGLE, SUB_THRESHOLD_DEPTH)
    depth[inside] = peak * (1.0 - 0.5 * np.abs(centres[inside] - peak_angle) / reach)
    return depth


def ideal_slider_position(theta: np.ndarray) -> np.ndarray:
    """x_B(theta) of the ideal mechanism [m] (docs/physics.md section 1)."""
    return np.sqrt(ROD_M ** 2 - (CRANK_M * np.sin(theta)) ** 2
                   - (SLIDER_Z_M + CRANK_M * np.cos(theta)) ** 2)


def config_text(clearance_b: float = CLEARANCE_M, coating_b: str = "none") -> str:
    """A resolved-config excerpt with the keys the plots read."""
    joint = {"clearance": CLEARANCE_M, "socket_radius": 0.015, "coating": "none"}
    return yaml.safe_dump({
        "name": "synthetic",
        "joints": {"A": dict(joint), "B": {**joint, "clearance": clearance_b, "coating": coating_b}},
        "solver": {"dt": 1.0e-5, "duration": DURATION_S, "save_every": 100},
    }, sort_keys=False)


def statistics(t: np.ndarray, acceleration: np.ndarray, torque: np.ndarray,
               normal: np.ndarray, penetration: np.ndarray) -> dict[str, np.ndarray]:
    """The kernel's statistics of these rows, treated as every step (right-end rule)."""
    out = {}
    dt = np.diff(t, prepend=t[0])
    for suffix, keep in (("", t >= 0.0), ("_settled", t >= SETTLE_TIME_S)):
        w = dt[keep]
        a = acceleration[keep]
        out["slider_acceleration_peak" + suffix] = np.abs(a).max()
        out["slider_acceleration_rms" + suffix] = np.sqrt((a ** 2 * w).sum() / w.sum())
        out["crank_torque_peak" + suffix] = np.abs(torque[keep]).max()
        out["normal_force_peak" + suffix] = normal[keep].max(axis=0)
        out["penetration_peak" + suffix] = np.maximum(penetration[keep].max(axis=0), 0.0)
        touching = normal[keep] > 0
        out["impact_count" + suffix] = touching.sum(axis=0).astype(np.int32)
        out["impact_velocity_max" + suffix] = np.where(touching.any(axis=0), 0.01, 0.0)
        out["contact_fraction" + suffix] = (touching * w[:, None]).sum(axis=0) / w.sum()
    ideal = np.array([j in IDEAL for j in JOINTS])
    for name, value in out.items():
        if np.ndim(value) == 1 and value.dtype.kind == "f":
            value[ideal] = np.nan
    return out


def one_case(*, profiles: dict | None = None, acc_level: float = ACC_LEVEL,
             clearance_b: float = CLEARANCE_M, coating_b: str = "none",
             status: str = "ok") -> xr.Dataset:
    """A one-case dataset (see the module docstring for its known numbers)."""
    profiles = WEAR_PROFILES if profiles is None else profiles
    n = int(round(DURATION_S / SAMPLE_DT_S)) + 1
    t = np.arange(n) * SAMPLE_DT_S
    theta = OMEGA_RAD_S * t
    position = ideal_slider_position(theta)
    acceleration = acc_level * (-1.0) ** np.floor(t / ACC_HALF_PERIOD_S)
    acceleration[int(round(ACC_SPIKE_TIME_S / SAMPLE_DT_S))] = ACC_SPIKE

    normal = np.zeros((n, len(JOINTS)))
    spike = int(round(NORMAL_FORCE_PEAK_TIME_S / SAMPLE_DT_S))
    for j, joint in enumerate(JOINTS):
        normal[spike, j] = NORMAL_FORCE_PEAK[joint]
    swing = np.stack([np.cos(theta), np.sin(theta), 0.2 * np.cos(2 * theta)], axis=-1)
    # (time, joint, axis), scaled with the acceleration level so that sweep cases differ
    force = np.stack([50.0 * swing, 80.0 * swing, 100.0 * swing, 30.0 * swing], axis=1) * acc_level / ACC_LEVEL
    clearances = np.array([CLEARANCE_M, clearance_b, 0.0, 0.0])
    radius = ORBIT_FRACTION * clearances
    offset = np.stack([np.cos(3 * theta), np.sin(3 * theta), 0.3 * np.sin(5 * theta)], axis=-1)
    offset = offset / np.linalg.norm(offset, axis=-1, keepdims=True)
    offset = offset[:, None, :] * radius[None, :, None]
    eccentricity = np.linalg.norm(offset, axis=-1)

    polar = bin_centres_deg(WEAR_MAP_SHAPE[0], 0.0, 180.0)
    azimuth = bin_centres_deg(WEAR_MAP_SHAPE[1], -180.0, 180.0)
    wear_map = np.zeros((len(JOINTS), *WEAR_MAP_SHAPE))
    for j, joint in enumerate(JOINTS):
        ip, ia = WEAR_MAP_PEAK_BIN[joint]
        blob = np.exp(-((polar[:, None] - polar[ip]) ** 2 + (azimuth[None, :] - azimuth[ia]) ** 2)
                      / (2 * 20.0 ** 2))
        wear_map[j] = WEAR_MAP_PEAK[joint] * blob
    projection = np.zeros((len(JOINTS), len(AXES), N_ANGLE))
    for (joint, axis), profile in profiles.items():
        projection[JOINTS.index(joint), AXES.index(axis)] = projection_profile(*profile)

    growth = np.clip(t / DURATION_S, 0.0, 1.0)[:, None]
    arrays = {
        "crank_angle": theta,
        "slider_position": position,
        "slider_velocity": np.gradient(position, t),
        "slider_acceleration": acceleration,
        "crank_torque": 2.0 * np.sin(theta),
        "reaction_O": 100.0 * swing,
        "joint_force": force,
        "normal_force": normal,
        "friction_force": 0.1 * normal,
        "penetration": np.where(clearances > 0.0, eccentricity - clearances, 0.0),
        "eccentricity": eccentricity,
        "ball_offset": offset,
        "wear_depth_max": growth * np.array([WEAR_MAP_PEAK[j] for j in JOINTS]),
        "energy_kinetic": 0.3 + 0.01 * np.sin(theta),
        "energy_potential": np.zeros(n),
        "work_drive": 0.01 * np.sin(theta),
        "energy_dissipated": np.zeros(n),
        "energy_residual": np.zeros(n),
        "constraint_violation": np.full(n, 1e-9),
        "wear_map": wear_map,
        "wear_projection": projection,
        "wear_volume": np.array([1e-15, 2e-15, 0.0, 0.0]),
        "substeps_used": np.int64(4),
        "rk4_steps": np.int64(80_000),
        "energy_residual_max": 1e-7,
        "energy_residual_relative": 2.5e-6,
        "wall_time": 2.0,
        "status": status,
    }
    arrays.update(statistics(t, acceleration, arrays["crank_torque"], normal,
                             arrays["penetration"]))
    arrays.update(sections(acc_level))
    return build_dataset(arrays, t, config_text=config_text(clearance_b, coating_b),
                         attrs={"settle_time_s": SETTLE_TIME_S})


#: Poincare sections of the synthetic case (not of its time series: a figure's input alone).
N_SECTIONS = 8


def sections(acc_level: float) -> dict[str, np.ndarray]:
    """Period-2 Poincare sections: each joint's offset / c alternates between two points, the
    slider acceleration between +-acc_level, one revolution a second."""
    alt = np.where(np.arange(N_SECTIONS) % 2 == 0, 1.0, -1.0)
    offset = np.zeros((N_SECTIONS, len(JOINTS), 3))
    offset[:, 0] = np.stack([np.full(N_SECTIONS, 0.5), 0.3 * alt, np.full(N_SECTIONS, -0.6)], axis=-1)
    offset[:, 1] = np.stack([0.2 * alt * acc_level / ACC_LEVEL, np.full(N_SECTIONS, 0.7),
                             np.full(N_SECTIONS, -0.5)], axis=-1)
    return {"poincare_offset": offset, "poincare_velocity": 0.1 * offset,
            "poincare_slider_acc": acc_level * alt,
            "poincare_time": np.arange(1.0, N_SECTIONS + 1)}


def sweep_case_profiles(coating: str, clearance: float) -> dict:
    """``WEAR_PROFILES`` with the B x profile of that sweep case."""
    lo, hi, peak = SWEEP_B_X[(coating, clearance)]
    return {**WEAR_PROFILES, ("B", "x"): (lo, hi, 20.5, peak)}


def sweep() -> xr.Dataset:
    """A 2 x 2 sweep over ``B_coating`` (strings) and ``B_clearance`` [m] (floats)."""
    rows = []
    for coating in SWEEP_COATINGS:
        cases = [one_case(profiles=sweep_case_profiles(coating, clearance),
                          acc_level=SWEEP_ACC_LEVEL[coating], clearance_b=clearance,
                          coating_b=coating)
                 for clearance in SWEEP_CLEARANCES]
        rows.append(xr.concat(cases, dim="B_clearance", data_vars="all", coords="minimal",
                              compat="override", join="override", combine_attrs="override"))
    ds = xr.concat(rows, dim="B_coating", data_vars="all", coords="minimal", compat="override",
                   join="override", combine_attrs="override")
    ds = ds.assign_coords(B_coating=("B_coating", list(SWEEP_COATINGS), {"long_name": "coating of B"}),
                          B_clearance=("B_clearance", list(SWEEP_CLEARANCES),
                                       {"long_name": "radial clearance of B", "units": "m"}))
    ds.attrs["config"] = config_text()
    return ds


# Fixtures shared by the test modules (import them by name there).

def heat_map_sweep(grid: np.ndarray) -> xr.Dataset:
    """A summary sweep of 4 coatings x 6 clearances of B: one metric, its values ``grid``."""
    return xr.Dataset(
        {"slider_acceleration_peak_settled": (("B_coating", "B_clearance"), grid,
                                              {"units": "m s-2", "long_name": "settled peak"})},
        coords={"B_coating": ["none", "MoS2", "lead", "PTFE"], "B_clearance": np.arange(6) * 1e-4})


@pytest.fixture(scope="module")
def case() -> xr.Dataset:
    """``one_case()``."""
    return one_case()


@pytest.fixture(scope="module")
def sweep_ds() -> xr.Dataset:
    """``sweep()``."""
    return sweep()


@pytest.fixture(scope="module")
def sweep_file(tmp_path_factory, sweep_ds) -> str:
    """``sweep()`` written to a netCDF file."""
    return str(write_netcdf_atomic(sweep_ds, tmp_path_factory.mktemp("sweep") / "sweep.nc"))


# Poincaré samples (one point per crank revolution), as the kernel stores them: the
# contract of docs/physics.md section 11.

def logistic_orbit(r: float, n: int, x0: float = 0.3, skip: int = 1000) -> np.ndarray:
    """``n`` iterates of the logistic map x -> r x (1 - x) after ``skip`` (its attractor):
    period 2 at r = 3.2, 4 at 3.5, 3 at 3.83; chaotic at 3.9 and 4.0."""
    x, out = x0, np.empty(n)
    for i in range(skip + n):
        x = r * x * (1.0 - x)
        if i >= skip:
            out[i - skip] = x
    return out


def with_poincare(ds: xr.Dataset, slider: np.ndarray, offset: np.ndarray | None = None,
                  period_s: float = 1.0, first_s: float = 0.0) -> xr.Dataset:
    """``ds`` with Poincaré samples: ``slider`` (revolution,) [m s-2] as
    ``poincare_slider_acc``; ``offset`` (revolution, joint) -> the offset / clearance of
    each joint along x (y half of it, z 0; NaN for a joint whose column is NaN: an ideal
    one), over ``ds``'s joints; sample k at ``first_s + (k - 1) period_s``."""
    n = slider.size
    # these samples replace any the dataset has (one_case's own sections)
    ds = ds.drop_vars([v for v in ("poincare_time", "poincare_slider_acc", "poincare_offset",
                                   "poincare_velocity", "revolution") if v in ds.variables])
    joints = [str(j) for j in ds["joint"].values] if "joint" in ds.coords else list(JOINTS)
    if offset is None:
        offset = np.full((n, len(joints)), np.nan)
    d = np.stack([offset, 0.5 * offset, 0.0 * offset], axis=-1)
    revolution = np.arange(1, n + 1)
    return ds.assign(
        poincare_time=(("revolution",), first_s + (revolution - 1) * period_s,
                       {"units": "s", "long_name": "time of the Poincare section"}),
        poincare_slider_acc=(("revolution",), slider.astype(float),
                             {"units": "m s-2", "long_name": "slider acceleration at the section"}),
        poincare_offset=(("revolution", "joint", "axis"), d,
                         {"units": "1", "long_name": "ball-centre offset / clearance at the section"}),
        poincare_velocity=(("revolution", "joint", "axis"), np.zeros_like(d),
                           {"units": "s-1", "long_name": "ball-centre velocity / clearance at the section"}),
    ).assign_coords(revolution=("revolution", revolution), joint=("joint", joints),
                    axis=("axis", list(AXES)))


def bifurcation_sweep(values=(2.9, 3.2, 3.5, 3.83, 4.0), revolutions: int = 40,
                      dim: str = "speed_rpm", joints=("A", "B", "O", "P")) -> xr.Dataset:
    """A summary sweep over ``dim`` whose Poincaré samples are the logistic map's attractor
    at r = each value: slider acceleration 10 x (m s-2), joint B's offset x along x (y half),
    the other joints ideal (NaN); the first half of the revolutions before the settled
    window (``settle_time_s`` = revolutions / 2 s at 1 s a revolution), the first case
    NaN-padded after three quarters of its revolutions (a shorter case)."""
    cases = []
    for k, r in enumerate(values):
        x = logistic_orbit(r, revolutions)
        offset = np.full((revolutions, len(joints)), np.nan)
        offset[:, list(joints).index("B")] = x
        base = xr.Dataset({"status": ((), "ok")}, coords={"joint": ("joint", list(joints))})
        case = with_poincare(base, 10.0 * x, offset)
        if k == 0:
            case = case.where(case["revolution"] <= revolutions * 3 // 4)
            case["status"] = ((), "ok")
        cases.append(case)
    ds = xr.concat(cases, dim=dim, data_vars="all", coords="minimal", compat="override",
                   join="override", combine_attrs="override")
    ds = ds.assign_coords({dim: (dim, list(values), {"long_name": "crank speed", "units": "min-1"})})
    ds.attrs.update(settle_time_s=revolutions / 2.0, sweep_dims=dim, sweep_store="summary",
                    config=config_text())
    return ds


def ideal_acceleration_case(revolutions: float = 6.0, samples_per_revolution: int = 1000,
                            omega: float = OMEGA_RAD_S, settle_s: float = 0.0) -> xr.Dataset:
    """A run's slider acceleration where the mechanism is ideal: the closed form x_B(theta)
    (``params.ideal_slider_x``, the realistic preset) differentiated twice in time at
    constant ``omega`` by central differences (relative error (k omega h)^2 / 12 at order k:
    under 1e-5 up to order 10), sampled ``samples_per_revolution`` times a revolution over
    ``revolutions``; ``settle_time_s`` = ``settle_s``."""
    from clearsweep.params import PRESETS, ideal_slider_x

    preset = PRESETS["realistic"]
    geometry = (preset.crank_length_m, preset.rod_length_m, preset.slider_height_m)
    dt = 2.0 * np.pi / omega / samples_per_revolution
    t = np.arange(int(round(revolutions * samples_per_revolution)) + 1) * dt
    h = 1.0e-3 / omega
    x = [ideal_slider_x(omega * (t + s), *geometry) for s in (-h, 0.0, h)]
    acceleration = (x[0] - 2.0 * x[1] + x[2]) / h ** 2
    return xr.Dataset(
        {"crank_angle": (("time",), omega * t, {"units": "rad", "long_name": "crank angle theta"}),
         "slider_acceleration": (("time",), acceleration,
                                 {"units": "m s-2", "long_name": "slider acceleration"})},
        coords={"time": ("time", t, {"units": "s", "long_name": "time"})},
        attrs={"settle_time_s": settle_s, "config": config_text()})
