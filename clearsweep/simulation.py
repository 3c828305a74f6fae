"""One case: resolved config -> packed vectors -> Numba kernel -> labelled dataset."""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from .config import ConfigError, dump_config, load_config, resolve_materials
from .core import layout as L
from .core.contact import elastic_force
from .params import PRESETS, Packed, pack

#: Largest crank rotation per output-grid step [rad]: the drive must be resolved even
#: where no contact demands sub-steps.
MAX_ROTATION_PER_STEP_RAD = 0.05


def check_step(cfg: dict, packed: Packed) -> None:
    """Reject a step that no permitted sub-step level can make stable (DESIGN 4).

    Two bounds: the crank may turn at most MAX_ROTATION_PER_STEP_RAD per step, and the
    deepest sub-step h / 2^k_max must resolve the elastic contact rate at the largest
    penetration the run accepts (contact.max_penetration_fraction * c), with the lightest
    mass a contact can meet (rod, slider, or the rod's end-point rotational mass).
    """
    solver = cfg["solver"]
    dt = solver["dt"]
    omega = packed.p[L.P_OMEGA]
    bounds = [MAX_ROTATION_PER_STEP_RAD / omega]
    preset = PRESETS[cfg["mechanism"]["preset"]]
    half = 0.5 * preset.rod_length_m
    m_ref = min(preset.rod_mass_kg, preset.slider_mass_kg,
                min(preset.rod_inertia_kgm2[1:]) / half ** 2)
    for j in range(2):
        jp = packed.jp[j]
        if jp[L.J_CLEARANCE] == 0.0:
            continue
        delta = packed.p[L.P_PEN_FRAC] * jp[L.J_C]
        _, stiffness = elastic_force(delta, jp[L.J_C], jp[L.J_EW], jp[L.J_RI])
        rate = math.sqrt(stiffness / m_ref)
        bounds.append(solver["stability_limit"] * 2 ** solver["max_substep_level"] / rate)
    limit = min(bounds)
    if dt > limit:
        raise ConfigError("solver.dt", dt,
                          f"a step <= {limit:.3g} s (larger steps cannot be made stable: crank "
                          f"rotation per step and contact rate with {2 ** solver['max_substep_level']}"
                          f" sub-steps at most, solver.max_substep_level)")


def preflight(cfg: dict) -> Packed:
    """Everything that can be checked before a run: materials, packing and the step bound.

    ``cfg`` is a resolved config; raises ConfigError. Sweeps call it on every case before
    anything runs.
    """
    packed = pack(cfg, resolve_materials(cfg))
    check_step(cfg, packed)
    return packed


def run_kernel(packed: Packed) -> dict[str, Any]:
    """Run the Numba kernel on packed inputs; raw arrays and counters."""
    from .core.rk4 import integrate

    n_save = packed.n_steps // packed.save_every + 1
    wmap = np.zeros((2,) + packed.map_shape)
    proj = np.zeros((2, 3, L.N_ANGLE_BINS))
    wvol = np.zeros(2)
    out_t = np.full(n_save, np.nan)
    out_y = np.full((n_save, L.N_Y), np.nan)
    out_d = np.full((n_save, L.N_D), np.nan)
    out_wmax = np.zeros((n_save, 2))
    info = np.zeros(5, dtype=np.int64)
    t0 = time.perf_counter()
    res = integrate(packed.p, packed.jp, packed.y0, 0.0, packed.n_steps, packed.save_every,
                    wmap, proj, wvol, out_t, out_y, out_d, out_wmax, info)
    wall = time.perf_counter() - t0
    n_ok = int(info[1])
    out_wmax[n_ok:] = np.nan
    h = packed.p[L.P_DT]
    out_t = np.arange(n_save) * h * packed.save_every
    return dict(t=out_t, y=out_y, d=out_d, wmax=out_wmax, wmap=wmap, proj=proj, wvol=wvol,
                status=L.STATUS_NAMES[int(info[0])], n_saved=n_ok, deepest=int(info[2]),
                t_end=float(info[4]) * h,
                rk4_steps=int(info[3]), residual_max=float(res[0]), ke_peak=float(res[1]),
                wall_time=wall)


def simulate(config, overrides=()) -> "xr.Dataset":  # noqa: F821
    """Simulate one case.

    Parameters
    ----------
    config
        Path to a YAML case file, or a (possibly partial) config dict; validated by
        ``config.load_config``.
    overrides
        ``"dotted.key=VALUE"`` strings.

    Returns
    -------
    xr.Dataset
        DESIGN 8 variables with CF attributes; ``status`` is ``"ok"`` or the reason the
        case stopped (rows after the stop are NaN).
    """
    from .dataset import build_dataset

    cfg = load_config(config, overrides)
    packed = preflight(cfg)
    raw = run_kernel(packed)
    arrays = arrays_from_raw(raw, packed)
    attrs = {
        "slip_rule": cfg["wear"]["slip"],
        "slip_description": ("dS = |v_t| dt (sliding distance)" if cfg["wear"]["slip"] == "sliding"
                             else "dS = R_i |d beta| (paper Eq. 14)"),
        "wear_map_rule": "bin-averaged depth: worn volume / bin area into the bin under the "
                         "contact point; read back by nearest bin",
        "wear_amplification": cfg["wear"]["amplification"],
        "rod_spin_constraint": "gamma3 = 0 (paper Eq. 24)",
        "preset": cfg["mechanism"]["preset"],
        "preset_source": PRESETS[cfg["mechanism"]["preset"]].source,
        "equivalent_modulus_A_Pa": float(packed.jp[0, L.J_EW]),
        "equivalent_modulus_B_Pa": float(packed.jp[1, L.J_EW]),
        "friction_coefficient_A": float(packed.jp[0, L.J_MU]),
        "friction_coefficient_B": float(packed.jp[1, L.J_MU]),
        "wear_coefficient_A_m2_per_N": float(packed.jp[0, L.J_K]),
        "wear_coefficient_B_m2_per_N": float(packed.jp[1, L.J_K]),
        # where the run ended (the stop, for a failed case: rows after the last saved
        # one are NaN, while wear_map, wear_projection and wear_volume hold the wear up
        # to this time)
        "status_time_s": raw["t_end"],
        "simulated_duration_s": float(packed.n_steps * packed.p[L.P_DT]),
    }
    return build_dataset(arrays, raw["t"], config_text=dump_config(cfg), attrs=attrs)


def arrays_from_raw(raw: dict, packed: Packed) -> dict[str, np.ndarray]:
    """Kernel rows -> registered output variables (variables.CASE_VARIABLES)."""
    y, d = raw["y"], raw["d"]
    qd = L.Y_QD
    clearance = packed.jp[:, L.J_CLEARANCE] != 0.0
    joint_force = d[:, L.D_JOINT_FORCE:L.D_JOINT_FORCE + 6].reshape(-1, 2, 3)
    offset = d[:, L.D_OFFSET:L.D_OFFSET + 6].reshape(-1, 2, 3)
    penetration = d[:, L.D_DELTA:L.D_DELTA + 2].copy()
    ecc = d[:, L.D_ECC:L.D_ECC + 2].copy()
    penetration[:, ~clearance] = 0.0
    offset[:, ~clearance, :] = 0.0
    ecc[:, ~clearance] = 0.0
    ke = d[:, L.D_KE]
    pe = d[:, L.D_PE_GRAV] + d[:, L.D_UEL] + d[:, L.D_UEL + 1]
    work = y[:, L.Y_WORK]
    diss = y[:, L.Y_DISS]
    residual = ke + pe - work + diss - (ke[0] + pe[0])
    ke_peak = raw["ke_peak"]
    return {
        "status": raw["status"],
        "crank_angle": y[:, 5],
        "slider_position": y[:, 12],
        "slider_velocity": y[:, qd + 12],
        "slider_acceleration": d[:, L.D_SLIDER_ACC],
        "crank_torque": d[:, L.D_TORQUE],
        "reaction_O": d[:, L.D_REACTION_O:L.D_REACTION_O + 3],
        "joint_force": joint_force,
        "normal_force": d[:, L.D_FN:L.D_FN + 2],
        "friction_force": d[:, L.D_FT:L.D_FT + 2],
        "penetration": penetration,
        "eccentricity": ecc,
        "ball_offset": offset,
        "wear_depth_max": raw["wmax"],
        "energy_kinetic": ke,
        "energy_potential": pe,
        "work_drive": work,
        "energy_dissipated": diss,
        "energy_residual": residual,
        "constraint_violation": d[:, L.D_CONS],
        "wear_map": raw["wmap"],
        "wear_projection": raw["proj"],
        "wear_volume": raw["wvol"],
        "substeps_used": np.int64(1 << raw["deepest"]),
        "rk4_steps": np.int64(raw["rk4_steps"]),
        "energy_residual_max": raw["residual_max"],
        "energy_residual_relative": raw["residual_max"] / ke_peak if ke_peak > 0 else np.nan,
        "wall_time": raw["wall_time"],
    }
