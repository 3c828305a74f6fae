"""Registry of output variables: one place for dims, units and long names.

Every dataset builder (one case, sweep summaries) reads this table and never
repeats a unit or a long name (docs/physics.md section 8).
"""

from __future__ import annotations

from dataclasses import dataclass

from .core.joints import JOINTS as JOINT_TABLE


@dataclass(frozen=True)
class VariableSpec:
    dims: tuple[str, ...]
    units: str
    long_name: str
    description: str = ""
    cell_methods: str = ""


#: The mechanism's joints, in the joint table's order (the ``joint`` dimension).
JOINTS = tuple(joint.name for joint in JOINT_TABLE)
#: Each joint's type by name in the joint table (the RSSP's; the slider-crank's A and B are
#: revolute, ``core.joints.SLIDER_CRANK_TYPES``): ``spherical`` (a ball in a socket: its map covers the socket's
#: sphere) or ``revolute`` (a journal in a bearing: one row of its map, around the bearing).
JOINT_TYPES = {joint.name: joint.type for joint in JOINT_TABLE}
AXES = ("x", "y", "z")
#: Each mechanism's name in titles and labels (``mechanism.kind``: config.MECHANISM_KINDS).
MECHANISM_NAMES = {"rssp": "RSSP", "slider_crank": "slider-crank"}
#: The mechanisms whose joints move in one plane, the crank's (y-z):
#: each joint's centre moves in one plane of its socket frame, the other axis holds nothing
#: but round-off.
PLANAR_MECHANISMS = ("slider_crank",)


def mechanism_title(kind: str) -> str:
    """The mechanism ``kind`` (``mechanism.kind``) as titles name it: "RSSP mechanism",
    "slider-crank mechanism"."""
    return f"{MECHANISM_NAMES.get(kind, kind)} mechanism"

#: Per-case variables (docs/physics.md section 8), plus the diagnostics the kernel keeps.
CASE_VARIABLES: dict[str, VariableSpec] = {
    "crank_angle": VariableSpec(("time",), "rad", "crank angle theta",
                                "driven crank angle theta0 + omega t"),
    "slider_position": VariableSpec(("time",), "m", "slider position along its guide",
                                   "the slider's centre along the guide's global axis: x "
                                   "for the RSSP, y for the slider-crank"),
    "slider_velocity": VariableSpec(("time",), "m s-1", "slider velocity"),
    "slider_acceleration": VariableSpec(("time",), "m s-2", "slider acceleration"),
    "crank_torque": VariableSpec(("time",), "N m", "driving torque on the crank about X"),
    "reaction_O": VariableSpec(("time", "axis"), "N", "reaction of the ground on the crank at O",
                               "global frame"),
    "joint_force": VariableSpec(("time", "joint", "axis"), "N",
                                "force on the ball of the joint (O: on the crank's journal; P: the "
                                "guide's on the slider)",
                                "global frame; constraint reaction (ideal joint) or contact force "
                                "(clearance joint) acting on the ball"),
    "normal_force": VariableSpec(("time", "joint"), "N", "normal contact force F_N",
                                 "zero for ideal joints and while out of contact; P: its most "
                                 "deeply penetrating corner's"),
    "friction_force": VariableSpec(("time", "joint"), "N", "magnitude of the friction force F_t"),
    "penetration": VariableSpec(("time", "joint"), "m", "penetration depth delta",
                                "e - c_eff(n); negative while free flight"),
    "eccentricity": VariableSpec(("time", "joint"), "m", "ball-centre offset e = |d|"),
    "ball_offset": VariableSpec(("time", "joint", "axis"), "m", "ball-centre offset d in the socket frame",
                                "d = ball centre - socket centre, socket body frame (a bearing's: "
                                "x its axis; the slider-crank's A: y along the rod)"),
    "wear_depth_max": VariableSpec(("time", "joint"), "m", "maximum wear depth on the wear map",
                                   "largest bin of the socket wear map so far"),
    "energy_kinetic": VariableSpec(("time",), "J", "kinetic energy"),
    "energy_potential": VariableSpec(("time",), "J", "potential energy (gravity + contact elastic)"),
    "work_drive": VariableSpec(("time",), "J", "work done by the crank drive since t = 0"),
    "energy_dissipated": VariableSpec(("time",), "J", "energy dissipated by contact damping and friction"),
    "energy_residual": VariableSpec(("time",), "J", "energy balance residual",
                                    "E_kin + E_pot - W_drive + E_diss - (E_kin + E_pot)(t=0)"),
    "constraint_violation": VariableSpec(("time",), "m", "largest position-constraint violation"),
    "wear_map": VariableSpec(("joint", "polar", "azimuth"), "m", "socket wear depth map",
                             "bin-averaged Archard wear depth over the socket inner sphere, socket "
                             "frame; O (and the slider-crank's A, B): row 0 around the bearing; "
                             "P: the guide's walls +y, -y, +z, "
                             "-z as four bands of polar // 4 rows across the wall by azimuth bins "
                             "along the guide, each bin the depth of the corners' track over "
                             "it (volume over track width x bin length)"),
    "wear_projection": VariableSpec(("joint", "axis", "angle"), "m", "wear depth projected per axis",
                                    "paper Eq. 15-17: k |F_N,axis| dS / A binned by the contact "
                                    "direction's angle about the axis, socket frame"),
    "wear_volume": VariableSpec(("joint",), "m3", "worn volume sum of k F_N dS"),
    "substeps_used": VariableSpec((), "1", "largest number of RK4 sub-steps in one output step",
                                  "2**k of the deepest sub-step level used (1 = never split)"),
    "rk4_steps": VariableSpec((), "1", "RK4 steps taken, sub-steps included",
                              "solver.method dopri5: accepted Dormand-Prince steps"),
    "first_impact_time": VariableSpec(("joint",), "s", "time of the first impact",
                                      "end of the accepted step in which the joint's first contact "
                                      "episode began; NaN when there was none"),
    "energy_residual_max": VariableSpec((), "J", "largest absolute energy residual", "",
                                        "time: maximum"),
    "energy_residual_relative": VariableSpec((), "1", "largest energy residual / peak kinetic energy"),
    "wall_time": VariableSpec((), "s", "wall-clock time of the simulation"),
}

#: Running statistics accumulated by the kernel at every accepted RK4 (sub-)step
#: (``core.layout.M_*``), never from the saved rows: identical whatever ``save_every``.
#: Each has a ``_settled`` twin over time >= the ``settle_time_s`` attribute.
_EVERY_STEP = ("within every accepted RK4 (sub-)step (a cubic in time through its ends' values "
               "and rates), not the saved rows")
_IDEAL = "; NaN for an ideal joint (no contact law)"
STATISTICS: dict[str, VariableSpec] = {
    "slider_acceleration_peak": VariableSpec(
        (), "m s-2", "peak absolute slider acceleration", "max |a| " + _EVERY_STEP,
        "time: maximum"),
    "slider_acceleration_rms": VariableSpec(
        (), "m s-2", "RMS slider acceleration",
        "sqrt(integral a^2 dt / duration), right-end value over each (sub-)step", "time: root_mean_square"),
    "crank_torque_peak": VariableSpec(
        (), "N m", "peak absolute crank torque", "max |torque| " + _EVERY_STEP, "time: maximum"),
    "normal_force_peak": VariableSpec(
        ("joint",), "N", "peak normal contact force", "max F_N " + _EVERY_STEP + _IDEAL,
        "time: maximum"),
    "penetration_peak": VariableSpec(
        ("joint",), "m", "peak penetration depth",
        "max(0, max delta) " + _EVERY_STEP + _IDEAL, "time: maximum"),
    "impact_count": VariableSpec(
        ("joint",), "1", "number of impacts",
        "contact episodes begun (a ball resting on its socket at the start is not one); "
        "0 for an ideal joint", "time: sum"),
    "impact_velocity_max": VariableSpec(
        ("joint",), "m s-1", "largest impact velocity",
        "largest normal approach velocity at the onset of a contact episode, taken from the "
        "(sub-)step ends on either side of the onset; 0 without impacts" + _IDEAL, "time: maximum"),
    "contact_fraction": VariableSpec(
        ("joint",), "1", "fraction of time in contact",
        "time with delta > 0 / duration, right-end value over each (sub-)step" + _IDEAL,
        "time: mean"),
}
for _name, _spec in list(STATISTICS.items()):
    STATISTICS[_name + "_settled"] = VariableSpec(
        _spec.dims, _spec.units, _spec.long_name + " after start-up",
        _spec.description + "; over time >= the settle_time_s attribute [s] "
        "(NaN, or 0 for a count, for a run that ends before it)", _spec.cell_methods)
CASE_VARIABLES.update(STATISTICS)

#: Poincare sections, one per crank revolution at the crank angle
#: ``outputs.poincare_phase_deg`` (docs/physics.md 8.4): read by the kernel at the section's
#: time within the (sub-)step that holds it, whatever ``save_every``; small, so every store
#: keeps them. A run shorter than its first section has none of them.
_SECTION = " at each revolution's Poincare section (crank angle outputs.poincare_phase_deg)"
POINCARE: dict[str, VariableSpec] = {
    "poincare_offset": VariableSpec(
        ("revolution", "joint", "axis"), "1", "ball-centre offset over the clearance",
        "ball-centre offset d in the socket frame / radial clearance c" + _SECTION
        + "; NaN for an ideal joint"),
    "poincare_velocity": VariableSpec(
        ("revolution", "joint", "axis"), "s-1", "ball-centre offset rate over the clearance",
        "rate of the ball-centre offset d in the socket frame / radial clearance c" + _SECTION
        + "; NaN for an ideal joint"),
    "poincare_slider_acc": VariableSpec(
        ("revolution",), "m s-2", "slider acceleration at the Poincare section",
        "slider acceleration" + _SECTION),
    "poincare_time": VariableSpec(
        ("revolution",), "s", "time of the Poincare section",
        "t_k = t at which the driven crank angle theta0 + omega t reaches the section angle"
        " + 360 degrees k; NaN where the run stopped before it"),
}
CASE_VARIABLES.update(POINCARE)

#: Coordinates and their attributes.
COORDINATES: dict[str, VariableSpec] = {
    "time": VariableSpec(("time",), "s", "time"),
    "joint": VariableSpec(("joint",), "", "joint (A: crank-rod, B: rod-slider, spherical, revolute "
                                          "in the slider-crank; O: crank bearing, revolute; P: slider "
                                          "guide, prismatic)"),
    "axis": VariableSpec(("axis",), "", "Cartesian axis"),
    "polar": VariableSpec(("polar",), "degree", "polar angle of the wear-map bin centre",
                          "measured from the socket frame's +z axis"),
    "azimuth": VariableSpec(("azimuth",), "degree", "azimuth of the wear-map bin centre",
                            "atan2(y, x) in the socket frame"),
    "angle": VariableSpec(("angle",), "degree", "projection angle bin centre",
                          "about x: atan2(n_z, n_y); about y: atan2(n_x, n_z); about z: atan2(n_y, n_x)"),
    "revolution": VariableSpec(("revolution",), "1", "crank revolution of the Poincare section",
                               "1-based: the k-th time the crank angle reaches the section angle "
                               "after the start"),
}


def attrs_for(name: str) -> dict[str, str]:
    """CF attributes (units, long_name, description) of a registered variable.

    Looks ``name`` up in ``CASE_VARIABLES``, then ``SUMMARY_VARIABLES``, then
    ``COORDINATES``; an unregistered name raises ``KeyError``.
    """
    spec = CASE_VARIABLES.get(name) or SUMMARY_VARIABLES.get(name) or COORDINATES[name]
    out = {"long_name": spec.long_name}
    if spec.units:
        out["units"] = spec.units
    if spec.description:
        out["description"] = spec.description
    if spec.cell_methods:
        out["cell_methods"] = spec.cell_methods
    return out


#: Per-case summaries derived from the variables above (``analysis.case_summary``,
#: ``analysis.wear_table``, ``analysis.reduction_table``); docs/physics.md sections 5, 7 and 9.
SUMMARY_VARIABLES: dict[str, VariableSpec] = {
    "wear_depth_max_final": VariableSpec(("joint",), "m", "maximum wear depth at the end of the run",
                                         "largest bin of the final socket wear map",
                                         "polar: azimuth: maximum"),
    "wear_depth_axis_max": VariableSpec(("joint", "axis"), "m", "maximum projected wear depth",
                                        "max of wear_projection over angle (paper Tables 4-5)",
                                        "angle: maximum"),
    "wear_angle_of_max": VariableSpec(("joint", "axis"), "degree", "angle of the maximum projected wear",
                                      "centre of the first bin holding the maximum"),
    "wear_angle_min": VariableSpec(("joint", "axis"), "degree", "minimum wear angle",
                                   "centre of the first bin, going up in angle, of the smallest "
                                   "arc holding every bin whose depth exceeds "
                                   "wear_threshold_fraction of the axis maximum (paper Tables 4-5, "
                                   "docs/physics.md section 5); above wear_angle_max where the arc "
                                   "crosses +-180 degree"),
    "wear_angle_max": VariableSpec(("joint", "axis"), "degree", "maximum wear angle",
                                   "centre of the last bin, going up in angle, of that arc"),
    "wear_range": VariableSpec(("joint", "axis"), "degree", "wear range",
                               "wear_angle_max - wear_angle_min on the circle: the smallest arc "
                               "holding every worn bin (paper Tables 4-5)"),
    "wear_depth_reduction": VariableSpec(("joint", "axis"), "m", "reduction of the maximum wear depth",
                                         "reference minus case (paper Table 6)"),
    "wear_depth_reduction_percent": VariableSpec(
        ("joint", "axis"), "%", "reduction of the maximum wear depth in percent",
        "100 (reference - case) / reference (paper Table 6)"),
    "wear_range_reduction": VariableSpec(("joint", "axis"), "degree", "reduction of the wear range",
                                         "reference minus case; negative where the range grew "
                                         "(paper Table 6)"),
    "wear_range_reduction_percent": VariableSpec(
        ("joint", "axis"), "%", "reduction of the wear range in percent",
        "100 (reference - case) / reference (paper Table 6)"),
    "members_ok": VariableSpec((), "1", "ensemble members with status ok",
                               "members counted in the ensemble statistics; the others stopped "
                               "with another status and are left out"),
    "is_reference": VariableSpec((), "", "reference case of the comparison",
                                 "true for the cases the reduction table compares against"),
    # docs/physics.md section 11 (clearsweep.motion)
    "slider_acceleration_dominant_order": VariableSpec(
        (), "1", "dominant crank order of the slider acceleration",
        "order (frequency / crank frequency) of the largest bin of the Welch spectrum of "
        "slider_acceleration over the settled window, the mean removed; NaN where the window "
        "holds fewer than 2 crank revolutions"),
    "slider_acceleration_high_order_share": VariableSpec(
        (), "1", "share of the slider acceleration's power above the high_order attribute",
        "power of the Welch spectrum's bins above crank order high_order over that of every "
        "bin above order 0, settled window; NaN where it holds fewer than 2 crank revolutions"),
    "slider_acceleration_rms_settled_drift": VariableSpec(
        (), "m s-2", "change of the settled RMS slider acceleration between the window's halves",
        "RMS of slider_acceleration's saved rows over the last n whole crank revolutions of "
        "the settled window minus that over its first n, n half the window's revolutions "
        "rounded down: how far the settled RMS still moves with the run's length; NaN where "
        "a half holds fewer than 2 rows"),
    "peak_force_source": VariableSpec(
        (), "", "what sets the case's peak contact force",
        "impacts (J...): clearance joints J began contact episodes; else in-contact "
        "oscillation (J...): joints J stayed in contact and the slider acceleration's peak / "
        "RMS exceeds the oscillation_crest_factor attribute; else quasi-static; settled "
        "window's statistics where the case has them, else the whole run's"),
    "period": VariableSpec(
        (), "1", "period of the motion in crank revolutions",
        "smallest n with every settled Poincare sample (slider acceleration, clearance joints' "
        "offsets) within period_rtol of the one n revolutions before; 0: none up to "
        "max_period (non-periodic); -1: fewer than 2 settled revolutions"),
    "chaos_k": VariableSpec(
        (), "1", "0-1 test for chaos K",
        "Gottwald and Melbourne (2004, 2009), correlation method, median over random c, on the "
        "settled Poincare samples of the slider acceleration: near 0 regular, near 1 chaotic; "
        "NaN for fewer than zero_one_min_samples revolutions"),
    "lyapunov_exponent": VariableSpec(
        (), "1", "largest Lyapunov exponent per crank revolution",
        "twin runs from the settled window's start, the twin lyapunov_perturbation away in the "
        "state (positions / crank length, angles in rad, rates / omega), renormalised once per "
        "revolution (Benettin et al. 1980) over lyapunov_revolutions: > 0 chaotic, about 0 "
        "quasi-periodic, < 0 periodic; NaN where the run is too short or a twin run stops"),
    "motion_class": VariableSpec(
        (), "", "motion class from the period, the 0-1 test and the Lyapunov exponent",
        "periodic, quasi-periodic, chaotic, transient (a negative exponent without a period "
        "in the window) or undetermined (docs/physics.md section 11.6)"),
}


#: Variables of a service-life dataset (``clearsweep life``, docs/service_life.md).
LIFE_VARIABLES: dict[str, VariableSpec] = {
    "cycle": VariableSpec(("cycle",), "1", "crank revolutions at the end of the block",
                          "cumulative revolutions, simulated and jumped"),
    "joint": VariableSpec(("joint",), "", "joint (A, B: spherical; O: revolute; P: prismatic)"),
    "polar": VariableSpec(("polar",), "degree", "polar angle of the wear-map bin centre"),
    "azimuth": VariableSpec(("azimuth",), "degree", "azimuth of the wear-map bin centre"),
    "block_revolutions": VariableSpec(("cycle",), "1", "revolutions simulated in the block"),
    "jump_revolutions": VariableSpec(("cycle",), "1", "revolutions jumped after the block",
                                     "the block's wear per revolution times this is added to the map"),
    "block_status": VariableSpec(("cycle",), "", "simulation status of the block"),
    "energy_residual_relative": VariableSpec(
        ("cycle",), "1", "largest energy residual of the block over its peak kinetic energy",
        "the block's energy balance (docs/physics.md 8.3); the run stops a block whose residual "
        "passes solver.energy_tolerance of the energy throughput"),
    "wear_depth_max": VariableSpec(("cycle", "joint"), "m", "maximum wear depth",
                                   "largest bin of the joint's wear map after the block (joint P: "
                                   "the deepest track on its walls)"),
    "wear_depth_mean": VariableSpec(("cycle", "joint"), "m", "mean wear depth over the worn area",
                                    "area-weighted mean of the bins deeper than 1e-2 of the maximum "
                                    "(joint P: the plain mean of its track bins)"),
    "wear_volume": VariableSpec(("cycle", "joint"), "m3", "worn volume sum of k F_N dS",
                                "blocks simulated plus jumps extrapolated"),
    "clearance_effective": VariableSpec(("cycle", "joint"), "m",
                                        "effective clearance in the most-worn direction",
                                        "c + largest bin depth"),
    "coating_remaining": VariableSpec(("cycle", "joint"), "m", "coating remaining at the most-worn bin",
                                      "max(0, coating thickness - largest bin depth); NaN uncoated"),
    "normal_force_peak_settled": VariableSpec(("cycle", "joint"), "N", "settled peak normal force",
                                              "over the block's settled window", "time: maximum"),
    "slider_acceleration_rms_settled": VariableSpec(("cycle",), "m s-2", "settled RMS slider acceleration",
                                                    "over the block's settled window"),
    "slider_acceleration_peak_settled": VariableSpec(("cycle",), "m s-2", "settled peak slider acceleration",
                                                     "over the block's settled window", "time: maximum"),
    "slider_motion_error_settled": VariableSpec(
        ("cycle",), "m", "settled slider motion error",
        "largest |s - s_ideal(theta)| over the block's saved rows in the settled window, s the "
        "slider's position along its guide, s_ideal the ideal mechanism's (docs/physics.md "
        "section 1)", "time: maximum"),
    "impacts_per_revolution": VariableSpec(("cycle", "joint"), "1", "impacts per revolution",
                                           "settled impact count / settled revolutions of the block"),
    "wear_map_snapshot": VariableSpec(("snapshot", "joint", "polar", "azimuth"), "m",
                                      "socket wear depth map at thinned blocks",
                                      "log-spaced in cycle; the last block's map is the last one"),
    "snapshot_cycle": VariableSpec(("snapshot",), "1", "crank revolutions of the wear-map snapshot"),
    "wear_map": VariableSpec(("joint", "polar", "azimuth"), "m", "socket wear depth map at the end"),
    "wear_through_cycle": VariableSpec(("joint",), "1", "revolutions at which the coating first wore through",
                                       "first bin whose depth reached the coating thickness; NaN if none"),
    "wear_through_polar": VariableSpec(("joint",), "degree", "polar angle where the coating first wore through"),
    "wear_through_azimuth": VariableSpec(("joint",), "degree", "azimuth where the coating first wore through"),
    "cycles_to_clearance_growth": VariableSpec((), "1", "revolutions to life.max_clearance_growth",
                                               "largest wear depth, interpolated between blocks; NaN "
                                               "if not reached or not set"),
    "cycles_to_normal_force": VariableSpec((), "1", "revolutions to life.max_normal_force",
                                           "settled peak normal force of either joint, interpolated "
                                           "between blocks; NaN if not reached or not set"),
    "cycles_to_rms_acceleration": VariableSpec((), "1", "revolutions to life.max_rms_acceleration",
                                               "settled RMS slider acceleration, interpolated between "
                                               "blocks; NaN if not reached or not set"),
    "cycles_to_motion_error": VariableSpec((), "1", "revolutions to life.max_motion_error",
                                           "settled slider motion error, interpolated between "
                                           "blocks; NaN if not reached or not set"),
    "cycles_to_wear_through": VariableSpec((), "1", "revolutions to the first coating wear-through",
                                           "earliest joint; NaN if none"),
    **{f"first_joint_to_{name}": VariableSpec((), "", f"the joint that reached {what} first",
                                              "each joint against the limit; empty if none did")
       for name, what in (("clearance_growth", "life.max_clearance_growth"),
                          ("normal_force", "life.max_normal_force"),
                          ("wear_through", "coating wear-through"))},
    "first_joint_to_rms_acceleration": VariableSpec((), "", "the joint that reached "
                                                    "life.max_rms_acceleration first",
                                                    "empty: the slider's, no joint's"),
    "first_joint_to_motion_error": VariableSpec((), "", "the joint that reached "
                                                "life.max_motion_error first",
                                                "empty: the slider's, no joint's"),
    "wall_time": VariableSpec((), "s", "wall-clock time of the life run"),
}


#: Text variables of results files and the dims they carry besides the sweep's.
TEXT_VARIABLES: dict[str, tuple[str, ...]] = {
    "status": (), "message": (), "motion_class": (), "stop_reason": (), "block_status": ("cycle",),
    **{f"first_joint_to_{name}": () for name in ("clearance_growth", "normal_force",
                                                 "rms_acceleration", "motion_error",
                                                 "wear_through")},
    "first_joint": ("limit",),
}

#: Dims of a reliability sweep's estimates and member draws besides the design dims
#: (``reliability.add_reliability_estimate``, ``reliability.reliability_case``).
RELIABILITY_DIMS: dict[str, tuple[str, ...]] = {
    **{name: ("limit", "revolutions") for name in
       ("reliability", "reliability_ci_low", "reliability_ci_high")},
    **{name: ("limit",) for name in
       ("b10", "b10_ci_low", "b10_ci_high", "b50", "b50_ci_low", "b50_ci_high", "members_reached",
        "members_counted")},
    **{name: ("limit", "input") for name in
       ("rank_correlation", "rank_correlation_ci_low", "rank_correlation_ci_high", "variance_share")},
    "revolutions_to_limit": ("member", "limit"), "censored": ("member", "limit"),
}


def layout_problem(ds) -> str | None:
    """What makes the results file ``ds`` (an xarray Dataset) other than clearsweep writes it,
    in words, or None: an empty dimension, a registered variable whose dims do not end with
    its registered dims or hold a dimension that is neither those nor a sweep dimension, a
    number variable that is not numbers, a text variable that is not text. ``report``,
    ``plot`` and ``sensitivity`` check it before reading a file (an edited file, or one of
    another program): such files stopped with numpy's or matplotlib's traceback, or were
    drawn as nonsense."""
    for dim, size in ds.sizes.items():
        if size == 0:
            return f"its dimension {dim!r} is empty"
    life_run = "cycle" in ds.dims
    registry = LIFE_VARIABLES if life_run else {**CASE_VARIABLES, **SUMMARY_VARIABLES}
    # a leading dim is a sweep's: one that the file names as such, or where it names none
    # (a file made by hand or by the API), any dim that is not one of a case's
    case_dims = {d for spec in (*registry.values(), *COORDINATES.values()) for d in spec.dims}
    named = ds.attrs.get("sweep_dims")
    sweep_dims = (set(str(named).split()) | {"member", "case", "sample"} if named is not None
                  else {str(d) for d in ds.dims} - case_dims)
    for name, da in ds.data_vars.items():
        name = str(name)
        dims = tuple(str(d) for d in da.dims)
        text = name in TEXT_VARIABLES
        if text:
            expected = TEXT_VARIABLES[name]
        elif name in RELIABILITY_DIMS and ds.attrs.get("sweep_store") == "reliability":
            expected = RELIABILITY_DIMS[name]
        elif name in registry:
            expected = registry[name].dims
        else:
            continue
        if dims[len(dims) - len(expected):] != expected or len(dims) < len(expected) or any(
                d not in sweep_dims for d in dims[:len(dims) - len(expected)]):
            return (f"its variable {name!r} has dims {dims}; clearsweep writes it with the "
                    f"sweep's dims followed by {expected}")
        if text != (da.dtype.kind in "USO"):
            kind = "text" if text else "numbers"
            return f"its variable {name!r} holds {da.dtype} values, not {kind}"
    return None


#: Length units a report scales metres to, largest first: (factor from metres, symbol).
LENGTH_UNITS = ((1e-3, "mm"), (1e-6, "um"), (1e-9, "nm"))

#: Units that a value is shown in, by its SI unit, smallest first: the one rule of reports
#: (:func:`length_unit`) and figures (``plotting.common.display_scale``).
DISPLAY_UNITS = {
    "m": ((1e-9, "nm"), (1e-6, "um"), (1e-3, "mm"), (1.0, "m")),
    "N": ((1.0, "N"), (1e3, "kN"), (1e6, "MN")),
}


def display_unit(values, units: str) -> tuple[float, str] | None:
    """(factor, symbol) that shows ``values`` [``units``] with one to three digits before
    the point (:data:`DISPLAY_UNITS`: the largest unit not above the largest finite
    magnitude, the smallest where all are below it); None where ``units`` has no ladder or
    no value is finite and non-zero."""
    steps = DISPLAY_UNITS.get(units)
    finite = [abs(float(v)) for v in values if v == v and abs(float(v)) != float("inf")]
    peak = max(finite, default=0.0)
    if not steps or not peak > 0:
        return None
    factor, symbol = steps[0]
    for f, t in steps:
        if peak >= f * (1.0 - 1e-9):
            factor, symbol = f, t
    return factor, symbol


def length_unit(values_m) -> tuple[float, str]:
    """The unit (factor from metres, symbol) that prints lengths ``values_m`` [m] with one
    to three digits before the point: mm, um or nm, from the largest finite magnitude;
    metres at 1 m and above (:func:`display_unit`); nm where none is non-zero."""
    return display_unit(list(values_m), "m") or LENGTH_UNITS[-1]


def format_length(value_m: float, digits: int = 4) -> str:
    """``value_m`` [m] in the unit that suits it (:func:`length_unit`): ``12.7 um``."""
    factor, symbol = length_unit([value_m])
    return f"{value_m / factor:.{digits}g} {symbol}"
