"""One case: resolved config -> packed vectors -> Numba kernel -> labelled dataset."""

from __future__ import annotations

import math
import os
import time
from contextlib import nullcontext
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    import xarray as xr

from .budget import check_budget
from .config import Config, ConfigError, dump_config, load_config, resolve_materials
from .core import jointset
from .core import layout as L
from .core.compiled import compile_lock
from .core.work import Case, Out
from .params import HOST_HOOKS, PRESETS, Packed, as_python, build_of, joint_attributes, kernel_build, pack, row_type
from .variables import mechanism_title

#: Largest crank rotation per output-grid step [rad]: the drive must be resolved even
#: where no contact demands sub-steps.
MAX_ROTATION_PER_STEP_RAD = 0.05


def check_step(cfg: Config, packed: Packed) -> None:
    """Reject a step that no permitted sub-step level can make stable (docs/physics.md section 4).

    Two bounds: the crank may turn at most MAX_ROTATION_PER_STEP_RAD per step, and the
    deepest sub-step h / 2^k_max must resolve the elastic contact rate at the largest
    penetration the run accepts (its stop, jp[J_PEN_STOP]: docs/physics.md 4.3), with the lightest
    mass a contact can meet (rod, slider, or the rod's end-point rotational mass; where O has
    clearance the crank is free in its bearing's plane, and that mass in series with the
    crank's; at P, the block's mass at a corner, its rotation included), each joint with its
    own elastic law (the journal's at O, the corners' at P); a bushing's spring and damper
    (its stiffer and more damped direction) on that mass.
    """
    from .core.joints import INDEX

    solver = cfg.solver
    dt = solver.dt
    omega = packed.p[L.P_OMEGA]
    bounds = [MAX_ROTATION_PER_STEP_RAD / omega]
    preset = PRESETS[cfg.mechanism.preset]
    half = 0.5 * preset.rod_length_m
    m_ref = min(preset.rod_mass_kg, preset.slider_mass_kg,
                min(preset.rod_inertia_kgm2[1:]) / half ** 2)
    if jointset.frees(packed.jp, INDEX["O"]):
        m_ref = 1.0 / (1.0 / m_ref + 1.0 / preset.crank_mass_kg)
    for j in range(L.N_JOINTS):
        if not jointset.frees(packed.jp, j):
            continue
        rate = HOST_HOOKS[row_type(packed.jp, j, packed.p)].rate(packed.jp, j, packed.p, preset, m_ref)
        bounds.append(solver.stability_limit * 2 ** solver.max_substep_level / rate)
    limit = min(bounds)
    if dt > limit:
        raise ConfigError("solver.dt", dt,
                          f"a step <= {limit:.3g} s (larger steps cannot be made stable: crank "
                          f"rotation per step and contact rate with {2 ** solver.max_substep_level}"
                          f" sub-steps at most, solver.max_substep_level)")


def preflight(cfg: Config, *, allow_large: bool = False, seat: bool = True) -> Packed:
    """Everything that can be checked before a run: work and memory, materials, packing and
    the step bound.

    ``cfg`` is a resolved config; raises ConfigError. Sweeps call it on every case before
    anything runs. ``allow_large`` lifts the bounds of :func:`clearsweep.budget.check_budget`.
    ``seat=False`` (planning: ``validate``, ``--dry-run``, a sweep's checks) compiles and
    runs nothing: the seated start is left to the run (:func:`clearsweep.params.pack`), and
    the packed inputs are for the checks only.
    """
    check_budget(cfg, allow_large=allow_large)
    packed = pack(cfg, resolve_materials(cfg), seat=seat)
    check_step(cfg, packed)
    return packed


def _kernel(method: str = "rk4"):
    """The compiled integrator of ``solver.method`` (each compiles on first use only)."""
    if method == "dopri5":
        from .core.dopri5 import integrate_dopri5

        return integrate_dopri5
    from .core.rk4 import integrate

    return integrate


def _compiled_for(kernel, build: int) -> bool:
    """Whether this process holds ``kernel`` compiled for the joint set ``build``."""
    signatures = getattr(kernel, "signatures", None)
    if signatures is None:      # plain Python (NUMBA_DISABLE_JIT)
        return True
    return any(getattr(sig[-1], "literal_value", None) == build for sig in signatures)


def kernel_needs_compiling(method: str = "rk4", build: int | None = None) -> bool:
    """True when neither this process nor the on-disk cache holds the kernel of ``method``
    compiled for the joint set ``build`` (``params.kernel_build``; None: A and B's)."""
    if build is None:
        build = build_of(jointset.named("A", "B"))
    kernel = _kernel(method)
    if _compiled_for(kernel, build):
        return False
    cache_file = getattr(getattr(kernel, "_cache", None), "_cache_file", None)
    index = getattr(cache_file, "_index_path", None)
    if cache_file is None or not (index and os.path.exists(index)):
        return True
    try:
        cached = cache_file._load_index()
    except Exception:  # noqa: BLE001 - an unreadable index: Numba compiles again
        return True
    return not any(getattr(key[0][-1], "literal_value", None) == build for key in cached)


def prepare_kernel(method: str = "rk4", build: int | None = None) -> float:
    """Compile (or load from the cache) the kernel of ``method`` for the joint set
    ``build`` (``params.kernel_build``; None: the two-clearance case's, A and B) with a
    run of no steps, under ``core.compiled.compile_lock`` where the on-disk cache does not
    hold it (one compile per machine: the other processes that ask wait, then load it);
    seconds taken.

    Run before a timed run so that its ``wall_time`` and steps/s count stepping only.
    """
    start = time.perf_counter()
    if build is None:
        build = build_of(jointset.named("A", "B"))
    if _compiled_for(_kernel(method), build):
        return 0.0
    # ideal: any build of its mechanism runs it
    mechanism = ({"kind": "slider_crank", "preset": "flores_benchmark"}
                 if build & jointset.SLIDER_CRANK else {})
    cfg = load_config({"mechanism": mechanism, "solver": {"method": method}})
    packed = pack(cfg, resolve_materials(cfg))
    packed.n_steps = 0
    packed.map_shape = (1, 1)
    # a build in the on-disk cache loads without the lock (many workers load at once)
    cold = kernel_needs_compiling(method, build)
    with compile_lock(_kernel(method), int(build)) if cold else nullcontext():
        _integrate(packed, build=build)
    return time.perf_counter() - start


@dataclass(frozen=True)
class KernelRun:
    """What one integration of the kernel gives: the saved rows, the wear, the running
    statistics and the counters (:func:`run_kernel` on the CPU; one case of a CUDA batch,
    ``clearsweep.gpu``, with one NaN row since the device keeps no series)."""

    t: np.ndarray               #: output times [s] (n_save)
    y: np.ndarray               #: state rows (n_save x layout.N_Y); NaN after a stop
    d: np.ndarray               #: diagnostics rows (n_save x layout.N_D)
    wmax: np.ndarray            #: deepest map bin per joint at each row [m] (n_save x 2)
    wmap: np.ndarray            #: wear map [m] (2 x npolar x nazim)
    proj: np.ndarray            #: per-axis projections [m] (2 x 3 x 360)
    wvol: np.ndarray            #: worn volume per joint [m^3]
    stats: np.ndarray           #: running statistics (2 x layout.N_M)
    sec: np.ndarray             #: Poincare sections (revolutions x layout.N_SEC), NaN: not taken
    status: str                 #: layout.STATUS_NAMES
    n_saved: int                #: rows written
    deepest: int                #: deepest sub-step level k (2^k sub-steps)
    t_end: float                #: time reached [s] (the stopping step included)
    rk4_steps: int              #: RK4 (sub-)steps taken (dopri5: accepted steps)
    residual_max: float         #: largest ``|energy residual|`` [J]
    ke_peak: float              #: peak kinetic energy [J]
    first_impact: np.ndarray    #: first impact time per joint [s], NaN: none
    wall_time: float            #: seconds the integration took

    @classmethod
    def from_counters(cls, packed: Packed, info: np.ndarray, residual_max: float, ke_peak: float,
                      first_impact: np.ndarray, wall_time: float, **arrays: np.ndarray) -> KernelRun:
        """From an integrator's ``info`` (status, saved rows, deepest level, sub-steps, grid
        steps done), its energy figures and first impact times (negative or NaN: none),
        and the arrays (t, y, d, wmax, wmap, proj, wvol, stats, sec)."""
        first = np.asarray(first_impact, dtype=float)
        return cls(status=L.STATUS_NAMES[int(info[L.I_STATUS])], n_saved=int(info[L.I_SAVED]),
                   deepest=int(info[L.I_DEEPEST]), rk4_steps=int(info[L.I_SUBSTEPS]),
                   t_end=float(info[L.I_STEPS]) * float(packed.p[L.P_DT]),
                   residual_max=float(residual_max), ke_peak=float(ke_peak),
                   first_impact=np.where(first >= 0.0, first, np.nan), wall_time=wall_time,
                   **arrays)


def section_rows(packed: Packed) -> int:
    """Poincare sections a run of the packed case holds (``core.rk4.section_count``, run as
    plain Python: nothing compiled), one per crank revolution."""
    from .core.rk4 import section_count

    return int(as_python(section_count)(packed.p, 0.0, packed.n_steps))


def run_kernel(packed: Packed, wmap0: np.ndarray | None = None,
                wvol0: np.ndarray | None = None, t0: float = 0.0, *,
                build: int | None = None) -> KernelRun:
    """Run the Numba kernel on packed inputs: the saved rows, wear, statistics, counters.

    ``wmap0`` (float64[2, npolar, nazim], [m]) and ``wvol0`` (float64[2], [m^3]): the wear
    map and worn volume to start from (a worn socket, e.g. the previous block of a life
    run); copied, not changed. Default: unworn. ``t0`` [s]: the time of ``packed.y0`` (a
    block continued from a saved state: the drive angle and the sections run on from it;
    the contact episodes begin afresh, as at a run's start). ``wall_time`` times the integration call
    alone (the compile, where the build was not compiled yet, comes before it).

    ``build``: the joint set of the kernel build to run (``core.jointset``); default the
    case's own, ``params.build_of`` the joints it has with clearance. ValueError for a
    build without one of them (it would run the joint as ideal). A build that this process
    has not compiled yet is compiled (or loaded from the cache) first, by
    :func:`prepare_kernel`, once per machine where several processes ask at once.
    """
    case_set = jointset.of(packed.jp, packed.p)
    build = build_of(case_set) if build is None else int(build)
    jointset.check(case_set, build)
    prepare_kernel(packed.method, build)
    return _integrate(packed, wmap0, wvol0, t0, build=build)


def _integrate(packed: Packed, wmap0: np.ndarray | None = None,
               wvol0: np.ndarray | None = None, t0: float = 0.0, *, build: int) -> KernelRun:
    """:func:`run_kernel` on the build ``build``, checked there, compiling it in place
    where this process has not (:func:`prepare_kernel`'s run of no steps)."""
    integrate = _kernel(packed.method)
    n_save = packed.n_steps // packed.save_every + 1
    wmap = np.zeros((L.N_JOINTS,) + packed.map_shape) if wmap0 is None else np.array(wmap0, dtype=float)
    if wmap.shape != (L.N_JOINTS,) + tuple(packed.map_shape):
        raise ValueError(f"wmap0 has shape {wmap.shape}, the config's map needs "
                         f"{(L.N_JOINTS,) + tuple(packed.map_shape)}")
    proj = np.zeros((L.N_JOINTS, 3, L.N_ANGLE_BINS))
    wvol = np.zeros(L.N_JOINTS) if wvol0 is None else np.array(wvol0, dtype=float)
    out_t = np.full(n_save, np.nan)
    out_y = np.full((n_save, L.N_Y), np.nan)
    out_d = np.full((n_save, L.N_D), np.nan)
    out_wmax = np.zeros((n_save, L.N_JOINTS))
    info = np.zeros(L.N_INFO, dtype=np.int64)
    stats = np.zeros((L.N_WINDOWS, L.N_M))
    sec = np.full((section_rows(packed), L.N_SEC), np.nan)
    case = Case(packed.p, packed.jp, packed.y0, wmap, proj, wvol)
    out = Out(out_t, out_y, out_d, out_wmax, info, stats, np.zeros(L.N_TRACK),
              np.zeros(L.N_JOINTS), sec)
    start = time.perf_counter()
    res = integrate(case, t0, packed.n_steps, packed.save_every, out, jointset.Build(build))
    wall = time.perf_counter() - start
    out_wmax[int(info[L.I_SAVED]):] = np.nan
    out_t = t0 + np.arange(n_save) * packed.p[L.P_DT] * packed.save_every
    return KernelRun.from_counters(packed, info, res[L.R_RESIDUAL_MAX], res[L.R_KE_PEAK],
                                   res[L.R_FIRST_IMPACT:L.N_R], wall, t=out_t,
                                   y=out_y, d=out_d, wmax=out_wmax, wmap=wmap, proj=proj, wvol=wvol,
                                   stats=stats, sec=sec)


def simulate(config, overrides=(), *, allow_large: bool = False) -> xr.Dataset:
    """Simulate one case.

    Parameters
    ----------
    config
        A :class:`clearsweep.config.Config` (used as it is), the path of a YAML case
        file, or a (possibly partial) config dict; the last two are validated by
        ``config.load_config``.
    overrides
        ``"dotted.key=VALUE"`` strings.
    allow_large
        Run a case beyond the work and memory bounds of ``budget.check_budget``.

    Returns
    -------
    xr.Dataset
        docs/physics.md section 8 variables with CF attributes; ``status`` is ``"ok"`` or the reason the
        case stopped (rows after the stop are NaN).
    """
    cfg = load_config(config, overrides)
    packed = preflight(cfg, allow_large=allow_large)
    prepare_kernel(cfg.solver.method, kernel_build(cfg))
    raw = run_kernel(packed)
    ds = case_dataset(cfg, packed, raw)
    if cfg.metrics.lyapunov_revolutions > 0:
        ds = with_lyapunov(ds, packed, raw, cfg.metrics.lyapunov_revolutions)
    return ds


def with_lyapunov(ds: xr.Dataset, packed: Packed, raw: KernelRun, revolutions: int) -> xr.Dataset:
    """``ds`` with ``lyapunov_exponent`` [1 / revolution] of its run (:func:`lyapunov_exponent`,
    the twin runs' kernel time added to ``wall_time``)."""
    import xarray as xr

    from .motion import LYAPUNOV_PERTURBATION
    from .variables import attrs_for

    start = time.perf_counter()
    value = lyapunov_exponent(packed, raw, revolutions)
    attrs = {**attrs_for("lyapunov_exponent"), "lyapunov_revolutions": int(revolutions),
             "lyapunov_perturbation": LYAPUNOV_PERTURBATION}
    out = ds.assign(lyapunov_exponent=xr.Variable((), np.float64(value), attrs))
    if "wall_time" in out:
        out["wall_time"] = out["wall_time"] + (time.perf_counter() - start)
        out["wall_time"].attrs = ds["wall_time"].attrs
    return out


def case_dataset(cfg: Config, packed: Packed, raw: KernelRun) -> xr.Dataset:
    """A case's dataset from its config, packed inputs and the kernel's raw output
    (:func:`run_kernel`, or one case of a CUDA batch: ``clearsweep.gpu``)."""
    from .dataset import build_dataset

    arrays = arrays_from_raw(raw, packed)
    attrs = {
        "title": f"clearsweep {mechanism_title(cfg.mechanism.kind)} simulation",
        "mechanism": cfg.mechanism.kind,
        "slip_rule": cfg.wear.slip,
        "slip_description": ("dS = |v_t| dt (sliding distance)" if cfg.wear.slip == "sliding"
                             else "dS = R_i |d beta| (paper Eq. 14)"),
        "wear_map_rule": "contact-area rule: each step's worn volume k F_N dS spread over the "
                         "bins the contact cap (area A) overlaps, in proportion to the overlap; "
                         "depth = volume / bin area; c_eff read from the bin holding the "
                         "contact direction",
        "wear_feedback": int(cfg.wear.feeds_back),
        "initial_joints": cfg.initial.joints,
        "settle_time_s": cfg.metrics.settle_time,
        "rod_inertia_kgm2": list(PRESETS[cfg.mechanism.preset].rod_inertia_kgm2),
        "wear_amplification": cfg.wear.amplification,
        "rod_spin_constraint": "gamma3 = 0 (paper Eq. 24)",
        "preset": cfg.mechanism.preset,
        "preset_source": PRESETS[cfg.mechanism.preset].source,
        # every joint: its type, materials and the contact values the kernel ran with
        **joint_attributes(cfg, packed),
        # where the run ended (the stop, for a failed case: rows after the last saved
        # one are NaN, while wear_map, wear_projection and wear_volume hold the wear up
        # to this time)
        "status_time_s": raw.t_end,
        # what was asked (solver.duration, or solver.revolutions at this speed), and what ran:
        # whole output samples, so up to save_every - 1 steps more
        "duration_s": cfg.solver.duration,
        "simulated_duration_s": float(packed.n_steps * packed.p[L.P_DT]),
    }
    # a length asked in crank revolutions: the revolutions (the seconds are above)
    for name, value in (("revolutions", cfg.solver.revolutions),
                        ("settle_revolutions", cfg.metrics.settle_revolutions)):
        if value is not None:
            attrs[name] = value
    if raw.status == L.STATUS_NAMES[L.ST_ENERGY]:
        attrs["status_hint"] = energy_residual_hint(arrays, raw.t, cfg)
    return build_dataset(arrays, raw.t, config_text=dump_config(cfg), attrs=attrs)


def statistics_from_raw(stats: np.ndarray, clearance: np.ndarray) -> dict[str, np.ndarray]:
    """Kernel running statistics (layout.M_*, whole run and settled window) -> variables.

    Float statistics of an ideal joint, and every statistic of an empty window (a run that
    ends before the settle time), are NaN; counts are then 0.
    """
    out: dict[str, Any] = {}
    for w, suffix in ((L.W_WHOLE, ""), (L.W_SETTLED, "_settled")):
        m = stats[w]
        empty = not m[L.M_SAMPLES] > 0
        duration = m[L.M_TIME]

        def joint(i: int) -> np.ndarray:
            v = m[i:i + L.N_JOINTS].astype(float).copy()
            v[~clearance] = np.nan
            return np.full(L.N_JOINTS, np.nan) if empty else v

        def scalar(v: float) -> np.float64:
            return np.float64(np.nan if empty else v)

        rms = math.sqrt(m[L.M_ACC_SQ] / duration) if duration > 0 else np.nan
        out["slider_acceleration_peak" + suffix] = scalar(m[L.M_ACC_PEAK])
        out["slider_acceleration_rms" + suffix] = scalar(rms)
        out["crank_torque_peak" + suffix] = scalar(m[L.M_TORQUE_PEAK])
        out["normal_force_peak" + suffix] = joint(L.M_FN_PEAK)
        out["penetration_peak" + suffix] = joint(L.M_PEN_PEAK)
        out["impact_velocity_max" + suffix] = joint(L.M_VIMP_MAX)
        fraction = joint(L.M_CONTACT_T) / duration if duration > 0 else np.full(L.N_JOINTS, np.nan)
        out["contact_fraction" + suffix] = fraction
        out["impact_count" + suffix] = m[L.M_IMPACTS:L.M_IMPACTS + L.N_JOINTS].astype(np.int32)
    return out


#: Terms of the energy balance, as energy_residual_hint names them.
_ENERGY_TERMS = (("energy_kinetic", "kinetic energy"),
                 ("energy_potential", "potential energy (gravity + contact elastic)"),
                 ("work_drive", "drive work"), ("energy_dissipated", "dissipated energy"))


def energy_residual_hint(arrays: dict[str, np.ndarray], t: np.ndarray, cfg: Config) -> str:
    """A hint at what drove an ``energy_residual`` stop, from the saved rows (post-processing).

    Compares the change since t = 0 of each term of the balance (kinetic and potential
    energy, drive work, dissipated energy) at the last saved row before the stop and names
    the largest; with ``wear.feedback`` on, adds the worn depth against each joint's
    clearance (wear enlarges the clearance the contact sees). Only a hint: the kernel
    stops between saved rows, on the residual it integrates itself.
    """
    finite = np.flatnonzero(np.isfinite(arrays["energy_residual"]))
    if finite.size < 2:
        return "hint: no saved rows before the stop to compare"
    k = int(finite[-1])
    changes = {label: float(arrays[name][k] - arrays[name][0]) for name, label in _ENERGY_TERMS}
    largest = max(changes, key=lambda label: abs(changes[label]))
    others = ", ".join(f"{label.split(' (')[0]} {value:+.3g} J" for label, value in changes.items()
                       if label != largest)
    text = (f"hint (saved rows up to t = {float(t[k]):.4g} s): the largest change since t = 0 is "
            f"the {largest}, {changes[largest]:+.3g} J ({others}; residual "
            f"{float(arrays['energy_residual'][k]):+.3g} J)")
    if cfg.wear.feeds_back:
        worn = []
        for j, (name, joint) in enumerate(cfg.joints.items()):
            c = joint.clearance
            depth = float(arrays["wear_depth_max"][k, j])
            if c > 0 and np.isfinite(depth) and depth > 0:
                worn.append(f"{name} {depth:.3g} m = {100 * depth / c:.3g} % of its clearance")
        if worn:
            text += ("; with wear.feedback on, the worn depth enlarges the clearance the contact "
                     f"sees: {'; '.join(worn)}")
    return text


def arrays_from_raw(raw: KernelRun, packed: Packed) -> dict[str, np.ndarray]:
    """Kernel rows -> registered output variables (variables.CASE_VARIABLES)."""
    y, d = raw.y, raw.d
    qd = L.Y_QD
    slider = L.Y_R4 + int(packed.p[L.P_GUIDE])     # along its guide: x, or the slider-crank's y
    clearance = packed.jp[:, L.J_CLEARANCE] != 0.0
    free = clearance | (packed.jp[:, L.J_BUSHING] != 0.0)     # a bushing's offset is read too
    nj = L.N_JOINTS
    joint_force = d[:, L.D_JOINT_FORCE:L.D_JOINT_FORCE + 3 * nj].reshape(-1, nj, 3)
    offset = d[:, L.D_OFFSET:L.D_OFFSET + 3 * nj].reshape(-1, nj, 3)
    penetration = d[:, L.D_DELTA:L.D_DELTA + L.N_JOINTS].copy()
    ecc = d[:, L.D_ECC:L.D_ECC + L.N_JOINTS].copy()
    penetration[:, ~clearance] = 0.0
    offset[:, ~free, :] = 0.0
    ecc[:, ~free] = 0.0
    ke = d[:, L.D_KE]
    pe = d[:, L.D_PE_GRAV].copy()
    for j in range(nj):
        pe += d[:, L.D_UEL + j]
    work = y[:, L.Y_WORK]
    diss = y[:, L.Y_DISS]
    residual = ke + pe - work + diss - (ke[0] + pe[0])
    ke_peak = raw.ke_peak
    return {
        "status": raw.status,
        "crank_angle": y[:, L.Y_CRANK_ANGLE],
        "slider_position": y[:, slider],
        "slider_velocity": y[:, qd + slider],
        "slider_acceleration": d[:, L.D_SLIDER_ACC],
        "crank_torque": d[:, L.D_TORQUE],
        "reaction_O": d[:, L.D_REACTION_O:L.D_REACTION_O + 3],
        "joint_force": joint_force,
        "normal_force": d[:, L.D_FN:L.D_FN + L.N_JOINTS],
        "friction_force": d[:, L.D_FT:L.D_FT + L.N_JOINTS],
        "penetration": penetration,
        "eccentricity": ecc,
        "ball_offset": offset,
        "wear_depth_max": raw.wmax,
        "energy_kinetic": ke,
        "energy_potential": pe,
        "work_drive": work,
        "energy_dissipated": diss,
        "energy_residual": residual,
        "constraint_violation": d[:, L.D_CONS],
        "wear_map": raw.wmap,
        "wear_projection": raw.proj,
        "wear_volume": raw.wvol,
        # counters: int32 where the value fits (2**16 sub-steps at most); rk4_steps can pass
        # 2**31 with --allow-large, so it stays int64
        "substeps_used": np.int32(1 << raw.deepest),
        "rk4_steps": np.int64(raw.rk4_steps),
        "energy_residual_max": raw.residual_max,
        "first_impact_time": raw.first_impact,
        "energy_residual_relative": raw.residual_max / ke_peak if ke_peak > 0 else np.nan,
        "wall_time": raw.wall_time,
        **statistics_from_raw(raw.stats, clearance),
        **sections_from_raw(raw.sec),
    }


def sections_from_raw(sec: np.ndarray) -> dict[str, np.ndarray]:
    """Kernel Poincare sections (layout.SEC_*) -> the ``poincare_*`` variables (dimension
    ``revolution``); none for a run that holds no section (shorter than its first)."""
    if sec.shape[0] == 0:
        return {}
    nj = L.N_JOINTS
    return {"poincare_time": sec[:, L.SEC_TIME],
            "poincare_slider_acc": sec[:, L.SEC_SLIDER_ACC],
            "poincare_offset": sec[:, L.SEC_OFFSET:L.SEC_OFFSET + 3 * nj].reshape(-1, nj, 3),
            "poincare_velocity": sec[:, L.SEC_RATE:L.SEC_RATE + 3 * nj].reshape(-1, nj, 3)}


#: The state components the twin runs perturb and measure (layout.Y_*): the positions,
#: angles and their rates; not the energy integrals (drive work, dissipation).
_LYAPUNOV_STATE = slice(0, L.Y_WORK)


#: The state components across a planar mechanism's plane (the slider-crank's, y-z: the
#: crank turns about x): each body's x, the crank's and the slider's Euler angles other
#: than the one about x (alpha, beta), the rod's yaw alpha3 out of the plane and its spin
#: gamma3; the rod's beta3 turns it in the plane.
OFF_PLANE_STATE = (L.Y_R2, L.Y_R3, L.Y_R4, L.Y_PHI2, L.Y_PHI2 + 1, L.Y_PHI3, L.Y_PHI3 + 2,
                   L.Y_PHI4, L.Y_PHI4 + 1)


def lyapunov_scale(packed: Packed) -> np.ndarray:
    """Each state component's scale in the twin runs' norm: the crank length l2 for a
    position, 1 rad for an angle, times omega for a rate (docs/physics.md section 11.5);
    the energy integrals ``inf`` (not perturbed, not measured), and for the planar
    slider-crank (its guide along y, ``p[P_GUIDE]``) the components across its plane
    (:data:`OFF_PLANE_STATE`): its exponent is its motion's in the plane."""
    length, omega = float(packed.p[L.P_L2]), float(packed.p[L.P_OMEGA])
    position = np.ones(L.Y_QD)
    for body in (L.Y_R2, L.Y_R3, L.Y_R4):
        position[body:body + 3] = length
    if packed.p[L.P_GUIDE] == 1.0:
        position[list(OFF_PLANE_STATE)] = np.inf
    scale = np.full(L.N_Y, np.inf)
    scale[:L.Y_QD] = position
    scale[L.Y_QD:L.Y_QD + L.Y_QD] = position * omega
    return scale


def lyapunov_exponent(packed: Packed, raw: KernelRun, revolutions: int,
                      logs: list | None = None) -> float:
    """The largest Lyapunov exponent [1 / revolution] of a run, from twin runs renormalised
    once per revolution over ``revolutions`` revolutions from the settled window's start
    (:func:`clearsweep.motion.largest_lyapunov`, docs/physics.md section 11.5).

    Block k starts at a saved row x_k of the run (``raw``), about one revolution after the
    previous one (a whole number of saved rows). The kernel runs the block twice from that
    row's time: from x_k and from x_k + d_k. Both begin their contact episodes afresh (the
    kernel keeps a contact's impact velocity outside the state), so both see the same
    restart and their difference is the perturbation's growth alone. NaN where the run
    holds fewer rows than one block after its settled window's start, or a block stops.
    ``logs``: a list that receives each block's ln growth.
    """
    from dataclasses import replace

    from .motion import largest_lyapunov

    p = packed.p
    dt = float(p[L.P_DT])
    row_dt = dt * packed.save_every
    period = 2.0 * math.pi / float(p[L.P_OMEGA])
    rows = max(1, int(round(period / row_dt)))             # rows a block spans
    first = int(math.ceil(float(p[L.P_SETTLE]) / row_dt - 1e-9))
    saved = raw.n_saved
    blocks = min(int(revolutions), (saved - 1 - first) // rows)
    if blocks < 1:
        return float("nan")
    steps = rows * packed.save_every
    block = replace(packed, n_steps=steps, save_every=steps)

    def advance(k: int, reference: np.ndarray, twin: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        t0 = (first + k * rows) * row_dt
        ends = []
        for y0 in (reference, twin):
            y0 = np.array(y0, dtype=float)
            y0[L.Y_WORK:] = 0.0          # the energy balance counts from the block's start
            run = run_kernel(replace(block, y0=y0), t0=t0)
            ends.append(run.y[-1] if run.status == L.STATUS_NAMES[L.ST_OK]
                        else np.full(L.N_Y, np.nan))
        return ends[0], ends[1]

    per_block = largest_lyapunov(advance, raw.y[first], blocks, lyapunov_scale(packed),
                                 base=lambda k: raw.y[first + k * rows], logs=logs)
    return per_block * period / (rows * row_dt)
