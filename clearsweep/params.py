"""Presets, equivalent contact moduli and packing of a resolved config into kernel vectors.

Geometry, masses and inertias: Jing & Liu 2023 (Lubricants 11, 310), Table 2, and
docs/physics.md section 1.1 (the `realistic` preset replaces the rod's printed inertia by a slender rod's).
"""

from __future__ import annotations

import math
import types
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any, cast

import numpy as np

from .choices import DAMPING_LAWS
from .config import (
    SLIDER_CRANK_PINS,
    Config,
    ConfigError,
    EnsembleConfig,
    JointConfig,
    PrismaticJointConfig,
    RevoluteJointConfig,
    resolve_materials,
)
from .core import jointset
from .core import layout as L
from .core.bushing import JOINT_TYPE as BUSHING
from .core.contact import hysteresis_fraction
from .core.joints import BODIES, JOINTS, row_types
from .jointtypes import kind as joint_kind
from .materials import FIELDS
from .version import IDENTITY_VERSION

#: A joint section of the config: a spherical joint (A, B) or the revolute joint O.
AnyJoint = JointConfig | RevoluteJointConfig | PrismaticJointConfig


@dataclass(frozen=True)
class Preset:
    """Mechanism data in SI units."""

    crank_length_m: float
    rod_length_m: float
    slider_height_m: float
    crank_mass_kg: float
    rod_mass_kg: float
    slider_mass_kg: float
    crank_inertia_kgm2: tuple[float, float, float]
    rod_inertia_kgm2: tuple[float, float, float]
    slider_inertia_kgm2: tuple[float, float, float]
    source: str
    #: the mechanism (``mechanism.kind``): the RSSP, whose slider's guide runs along x at
    #: (y, z) = (0, z_s); or the planar slider-crank, the crank's plane y-z, its guide along y
    #: at (x, z) = (0, z_s) (docs/mechanisms.md)
    kind: str = "rssp"
    #: the slider-crank's pins' bearing length [m] (A and B, revolute there): the length of
    #: their wear strip where ``joints.X.length`` is null; None for the RSSP, whose A and B
    #: are balls
    pin_length_m: float | None = None

    @property
    def guide_axis(self) -> int:
        """The global axis of the slider's guide: 0 (x, the RSSP) or 1 (y, the slider-crank)
        (``p[P_GUIDE]``, ``core.jointset.guide_axis``)."""
        return 1 if self.kind == "slider_crank" else 0


_COMMON: dict[str, Any] = dict(crank_length_m=0.14, rod_length_m=0.38, slider_height_m=-0.12,
               crank_mass_kg=1.3, rod_mass_kg=1.2, slider_mass_kg=2.2,
               crank_inertia_kgm2=(1e-4, 1e-4, 1e-4), slider_inertia_kgm2=(1e-3, 1e-3, 1e-3))

PRESETS: dict[str, Preset] = {
    # Slender rod: m l^2 / 12 = 1.2 * 0.38^2 / 12 = 1.444e-2 kg m^2 about the transverse axes.
    "realistic": Preset(**_COMMON, rod_inertia_kgm2=(1e-4, 1.444e-2, 1.444e-2),
                        source="Jing & Liu 2023 Table 2; rod inertia m l^2/12 (docs/physics.md section 1.1)"),
    "paper": Preset(**_COMMON, rod_inertia_kgm2=(1e-5, 1e-5, 1e-5),
                    source="Jing & Liu 2023 Table 2 as published"),
    # The planar slider-crank of Flores, Ambrosio, Claro and Lankarani (docs/mechanisms.md,
    # each value's source): the in-plane inertias as published, the same value about the
    # body's other axes (the planar motion does not excite them); the slider in line with the
    # crank's pivot (no offset).
    "flores_benchmark": Preset(crank_length_m=0.05, rod_length_m=0.12, slider_height_m=0.0,
                               crank_mass_kg=0.30, rod_mass_kg=0.21, slider_mass_kg=0.14,
                               crank_inertia_kgm2=(1e-4, 1e-4, 1e-4),
                               rod_inertia_kgm2=(2.5e-4, 2.5e-4, 2.5e-4),
                               slider_inertia_kgm2=(1e-4, 1e-4, 1e-4),
                               source="Flores, Ambrosio, Claro & Lankarani 2008, the slider-crank "
                                      "benchmark (docs/mechanisms.md)",
                               kind="slider_crank", pin_length_m=0.02),
}

BASE_MATERIAL = "steel"  # socket base and ball (docs/physics.md section 6)


def as_python(func):
    """The kernel function ``func`` run as plain Python, and so every kernel function it
    calls: what planning evaluates of the kernel (the step bound's contact stiffness,
    :func:`clearsweep.simulation.check_step`) compiles nothing. The same arithmetic in the
    same order as the compiled function, to the bit (tests/test_planning_bounds.py)."""
    py = getattr(func, "py_func", func)
    calls = {name: as_python(value) for name, value in py.__globals__.items()
             if name in py.__code__.co_names and hasattr(value, "py_func")}
    if not calls:
        return py
    return types.FunctionType(py.__code__, {**py.__globals__, **calls}, py.__name__,
                              py.__defaults__, py.__closure__)


def oedometric_modulus(youngs_modulus_Pa: float, poisson_ratio: float) -> float:
    """E* = E (1 - nu) / ((1 + nu)(1 - 2 nu)) [Pa] (docs/physics.md section 3.2)."""
    nu = poisson_ratio
    return youngs_modulus_Pa * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu))


def layer_modulus(surface, base, coating_thickness_m: float, base_thickness_m: float,
                  coated: bool, rule: str = "series") -> tuple[float, float]:
    """Modulus E_x [Pa] and Poisson ratio of one side of the double elastic layer (docs/physics.md section 3.2).

    ``series``: thickness fractions f = l / (l_c + l_s); ``paper_mm``: the paper's literal
    thicknesses in millimetres (an uncoated side then has f_c = 0, f_s = l_s [mm]).
    """
    es = oedometric_modulus(base.youngs_modulus_Pa, base.poisson_ratio)
    ec = oedometric_modulus(surface.youngs_modulus_Pa, surface.poisson_ratio) if coated else es
    lc = coating_thickness_m if coated else 0.0
    if rule == "series":
        fc = lc / (lc + base_thickness_m)
        fs = base_thickness_m / (lc + base_thickness_m)
    elif rule == "paper_mm":
        fc = lc * 1e3
        fs = base_thickness_m * 1e3
    else:
        raise ValueError(f"unknown layer rule {rule!r}")
    ex = ec * es / (es * fc + ec * fs)
    return ex, (surface.poisson_ratio if coated else base.poisson_ratio)


def equivalent_modulus(joint: AnyJoint, materials: dict, rule: str) -> float:
    """E_w [Pa]: 1/E_w = (1 - nu_i^2)/E_i + (1 - nu_j^2)/E_j, socket i (maybe coated), ball j."""
    base = materials[BASE_MATERIAL]
    coated = joint.coating != "none"
    surface = materials[joint.coating] if coated else base
    ei, nui = layer_modulus(surface, base, joint.coating_thickness, joint.base_thickness,
                            coated, rule)
    ej, nuj = layer_modulus(base, base, joint.coating_thickness, joint.base_thickness,
                            False, rule)
    return 1.0 / ((1.0 - nui ** 2) / ei + (1.0 - nuj ** 2) / ej)


def plane_strain_modulus(youngs_modulus_Pa: float, poisson_ratio: float) -> float:
    """E / (1 - nu^2) [Pa]: one body's share of Hertz's contact modulus (docs/physics.md 3.2)."""
    return youngs_modulus_Pa / (1.0 - poisson_ratio ** 2)


def hertz_modulus(joint: AnyJoint, materials: dict) -> float:
    """Hertz's contact modulus E* [Pa] of joint's pair, socket i (maybe coated) on ball j
    (docs/physics.md 3.2, "Hertz's modulus"):

        1/E* = w_i + (1 - nu_s^2)/E_s,   w_i = f_c (1 - nu_c^2)/E_c + f_s (1 - nu_s^2)/E_s

    f_c = l_c / (l_c + l_s), f_s = 1 - f_c: the coated side's compliance is the thickness
    average of its coating's and its base's (the layers in series, as in the paper's
    double elastic layer, with Hertz's plane-strain moduli in place of the oedometric
    ones). Uncoated (or l_c -> 0) it is Hertz's E* = [(1 - nu_1^2)/E_1 + (1 - nu_2^2)/E_2]^-1
    of the two base bodies; l_c >> l_s gives the coating's own against the ball."""
    base = materials[BASE_MATERIAL]
    ws = 1.0 / plane_strain_modulus(base.youngs_modulus_Pa, base.poisson_ratio)
    wi = ws
    if joint.coating != "none":
        coat = materials[joint.coating]
        lc = joint.coating_thickness
        fc = lc / (lc + joint.base_thickness)
        wi = fc / plane_strain_modulus(coat.youngs_modulus_Pa, coat.poisson_ratio) + (1.0 - fc) * ws
    return 1.0 / (wi + ws)


def power_law_joint(joint_type: str, exponent: float) -> bool:
    """Whether a joint of ``joint_type`` takes the power law (Hertz's, docs/physics.md 3.2)
    in a case whose ``P_EXPONENT`` is ``exponent``: the journal of O and P's corners always
    (``revolute.journal_law``; P's faces, ``prismatic.line_stiffness``), the spherical joints under
    ``contact.elastic: hertz`` (``exponent`` != 0); else the paper's layered law."""
    return joint_kind(joint_type).power_law or exponent != 0.0


def contact_modulus(joint: AnyJoint, joint_type: str, materials: dict, rule: str,
                    exponent: float) -> float:
    """The modulus [Pa] of joint's elastic law, packed as jp[J_EW]: Hertz's E*
    (:func:`hertz_modulus`) where the joint takes the power law (:func:`power_law_joint`),
    the paper's layered E_w (:func:`equivalent_modulus`, layer rule ``rule``) under the
    paper's law."""
    if power_law_joint(joint_type, exponent):
        return hertz_modulus(joint, materials)
    return equivalent_modulus(joint, materials, rule)


def surface_material(joint: AnyJoint, materials: dict):
    """The socket surface's material: the coating where coated, else the base."""
    return materials[BASE_MATERIAL if joint.coating == "none" else joint.coating]


def run_identity(cfg: Config) -> dict[str, Any]:
    """Everything that decides the results of ``cfg``'s run, as plain JSON-ready data.

    ``config``: the resolved config without ``materials_file`` (the file's path does not
    change a result; its values do); ``materials``: the values of every material the run
    reads (the base and the joints' coatings, as :func:`pack` reads them, sources left
    out); ``version``: the clearsweep version and the results' revision
    (:data:`clearsweep.version.IDENTITY_VERSION`). Finished work (a sweep's part, a life
    checkpoint) belongs to a run exactly when their identities are equal.
    """
    config = cfg.to_dict()
    config.pop("materials_file", None)
    if config["mechanism"]["kind"] == "rssp":
        # the default mechanism, as every run before mechanism.kind: its finished work stays
        # this run's
        del config["mechanism"]["kind"]
    for joint in SLIDER_CRANK_PINS:
        # a pin's length (the slider-crank's) left at the preset's: as every run before it
        if config["joints"][joint].get("length", 0.0) is None:
            del config["joints"][joint]["length"]
    table = resolve_materials(cfg)
    used = sorted({BASE_MATERIAL, *(j.coating for _, j in cfg.joints.items() if j.coating != "none")})
    return {"config": config,
            "materials": {m: {f: getattr(table[m], f) for f in FIELDS} for m in used},
            "version": IDENTITY_VERSION}


def _flat(tree: Any, prefix: str = "") -> dict[str, Any]:
    if not isinstance(tree, dict):
        return {prefix: tree}
    out: dict[str, Any] = {}
    for key, value in tree.items():
        out.update(_flat(value, f"{prefix}.{key}" if prefix else str(key)))
    return out


def identity_differences(theirs: dict[str, Any], ours: dict[str, Any]) -> list[str]:
    """The dotted keys at which two :func:`run_identity` values differ: config keys first,
    then materials values, then the version."""
    a, b = _flat(theirs), _flat(ours)
    return sorted((k for k in a.keys() | b.keys() if a.get(k) != b.get(k)),
                  key=lambda k: ({"config": 0, "materials": 1}.get(k.split(".")[0], 2), k))


def identity_changes(theirs: dict[str, Any], ours: dict[str, Any], limit: int = 3) -> str:
    """What differs between two :func:`run_identity` values, in words: ``KEY: VALUE there,
    VALUE here`` for the first ``limit`` differences, config keys as dotted paths, materials
    values as ``materials MATERIAL.FIELD``, and ``clearsweep version``."""
    a, b = _flat(theirs), _flat(ours)
    keys = identity_differences(theirs, ours)

    def name(key: str) -> str:
        section, _, rest = key.partition(".")
        return {"config": rest, "materials": f"materials {rest}",
                "store": "store"}.get(section, "clearsweep version")

    def shown(key: str, values: dict[str, Any]) -> str:
        return repr(values[key]) if key in values else "absent"

    text = "; ".join(f"{name(k)}: {shown(k, a)} there, {shown(k, b)} here" for k in keys[:limit])
    return text + (f"; and {len(keys) - limit} more" if len(keys) > limit else "")


def ideal_slider_x(theta, l2: float, l3: float, zs: float):
    """Closed-form slider position x_B(theta) [m] of docs/physics.md section 1 (ideal joints)."""
    return np.sqrt(l3 ** 2 - (l2 * np.sin(theta)) ** 2 - (zs + l2 * np.cos(theta)) ** 2)


def slider_crank_kinematics(theta, omega: float, l2: float, l3: float, zs: float):
    """The ideal slider-crank's slider along its guide (docs/mechanisms.md): position s [m],
    velocity [m/s] and acceleration [m/s^2] at crank angle theta [rad] turning at omega
    [rad/s], the crank pin at (0, l2 sin theta, -l2 cos theta) and the guide along y at
    height z_s: s = l2 sin theta + w, w = sqrt(l3^2 - u^2), u = z_s + l2 cos theta."""
    theta = np.asarray(theta, float)
    u = zs + l2 * np.cos(theta)
    ud = -l2 * omega * np.sin(theta)
    udd = -l2 * omega ** 2 * np.cos(theta)
    w = np.sqrt(l3 ** 2 - u ** 2)
    wd = -u * ud / w
    wdd = -(ud ** 2 + u * udd + wd ** 2) / w
    return (l2 * np.sin(theta) + w, l2 * omega * np.cos(theta) + wd,
            -l2 * omega ** 2 * np.sin(theta) + wdd)


def ideal_slider_position(preset: Preset, theta):
    """The ideal mechanism's slider position along its guide [m] at crank angle theta [rad]:
    :func:`ideal_slider_x` for the RSSP, :func:`slider_crank_kinematics` for the
    slider-crank."""
    l2, l3, zs = preset.crank_length_m, preset.rod_length_m, preset.slider_height_m
    if preset.kind == "slider_crank":
        return slider_crank_kinematics(theta, 0.0, l2, l3, zs)[0]
    return ideal_slider_x(theta, l2, l3, zs)


def rod_endpoints(preset: Preset, theta: float, offset_A=(0.0, 0.0, 0.0),
                  offset_B=(0.0, 0.0, 0.0), offset_O=(0.0, 0.0, 0.0)
                  ) -> tuple[np.ndarray, np.ndarray, float]:
    """Rod end points a, b [m] and slider position x4 [m] at crank angle theta [rad], with
    ball-centre offsets d = ball centre - socket centre (global frame [m]) held at A (ball:
    crank pin, socket: rod end), B (ball: rod end, socket: slider centre) and O (ball: the
    crank's journal, socket: the bearing at the origin; in its y-z plane)."""
    l2, l3, zs = preset.crank_length_m, preset.rod_length_m, preset.slider_height_m
    d_a = np.asarray(offset_A, float)
    d_b = np.asarray(offset_B, float)
    a = np.array([0.0, l2 * math.sin(theta), -l2 * math.cos(theta)]) + np.asarray(offset_O, float) - d_a
    # b = (x4, 0, z_s) + d_b (the slider-crank's (0, y4, z_s) + d_b) with |b - a| = l3, the
    # root with the slider beyond the crank
    g = preset.guide_axis
    h = 1 - g
    dh = d_b[h] - a[h]
    dz = zs + d_b[2] - a[2]
    x4 = a[g] - d_b[g] + math.sqrt(l3 ** 2 - dh ** 2 - dz ** 2)
    b = np.array([0.0, 0.0, zs]) + d_b
    b[g] += x4
    return a, b, x4


def initial_state(preset: Preset, theta0: float, omega: float, offset_A=(0.0, 0.0, 0.0),
                  offset_B=(0.0, 0.0, 0.0), offset_O=(0.0, 0.0, 0.0),
                  offset_P=(0.0, 0.0, 0.0)) -> np.ndarray:
    """State at crank angle theta0 moving at omega [rad/s], the ball-centre offsets (global
    frame [m], zero = centred ball) held fixed; velocities from the kinematics with the
    offsets held, so that no ball moves relative to its socket at the start. ``offset_P``:
    the slider block's offset across its guide in the guide's frame (0, side, up): the
    RSSP's (0, y, z); the slider-crank's (0, -x, z) (``prismatic.PLANAR_GUIDE``,
    :func:`guide_to_global`)."""
    l2, l3 = preset.crank_length_m, preset.rod_length_m
    st, ct = math.sin(theta0), math.cos(theta0)
    y = np.zeros(L.N_Y)
    # crank: centroid at -R2 (0, 0, l2/2), gamma2 = theta0
    r2, g2, r3, ph3, r4 = L.Y_R2, L.Y_CRANK_ANGLE, L.Y_R3, L.Y_PHI3, L.Y_R4
    qd = L.Y_QD
    y[r2:r2 + 3] = (0.0, 0.5 * l2 * st, -0.5 * l2 * ct)
    y[r2:r2 + 3] += np.asarray(offset_O, float)
    y[g2] = theta0
    y[qd + r2:qd + r2 + 3] = (0.0, 0.5 * l2 * ct * omega, 0.5 * l2 * st * omega)
    y[qd + g2] = omega
    g = preset.guide_axis
    d_p = guide_to_global(np.array([0.0, offset_P[1], offset_P[2]]), g)
    a, b, x4 = rod_endpoints(preset, theta0, offset_A, np.asarray(offset_B, float) + d_p, offset_O)
    va = np.array([0.0, l2 * ct, l2 * st]) * omega
    # |b - a| = l3 with b moving along its guide (axis g) only: (b - a) . (vb - va) = 0
    vb = np.zeros(3)
    vb[g] = (b - a) @ va / (b - a)[g]
    d = (b - a) / l3
    dd = (vb - va) / l3
    y[r3:r3 + 3] = 0.5 * (a + b)
    y[qd + r3:qd + r3 + 3] = 0.5 * (va + vb)
    y[ph3] = math.atan2(d[1], d[0])                          # alpha3
    y[ph3 + 1] = -math.asin(d[2])                            # beta3
    y[qd + ph3] = (d[0] * dd[1] - d[1] * dd[0]) / (d[0] ** 2 + d[1] ** 2)
    y[qd + ph3 + 1] = -dd[2] / math.cos(y[ph3 + 1])
    y[r4 + g] = x4
    y[r4 + 1 - g] = d_p[1 - g]
    y[r4 + 2] = preset.slider_height_m + d_p[2]
    y[qd + r4 + g] = vb[g]
    return y


def guide_to_global(v: np.ndarray, guide_axis: int) -> np.ndarray:
    """A vector of the guide's frame (along, side, up) in global axes: as is for the RSSP
    (``guide_axis`` 0); Q^T v for the slider-crank's guide along y
    (``prismatic.PLANAR_GUIDE``: along = y, side = -x, up = z)."""
    v = np.asarray(v, dtype=float)
    return v.copy() if guide_axis == 0 else np.array([-v[1], v[0], v[2]])


def global_to_guide(v: np.ndarray, guide_axis: int) -> np.ndarray:
    """A global vector in the guide's frame (along, side, up): the inverse of
    :func:`guide_to_global`."""
    v = np.asarray(v, dtype=float)
    return v.copy() if guide_axis == 0 else np.array([v[1], -v[0], v[2]])


def check_guide_reach(joint: PrismaticJointConfig, preset: Preset) -> None:
    """Raise ConfigError where joint P's clearances let the block sit where the rod cannot
    reach it: at some crank angle theta and some offset (y, z) within the clearances,
    (y - l2 sin theta)^2 + (z_s + z + l2 cos theta)^2 >= l3^2 (docs/physics.md section 1; the
    start would have no slider position). Names the larger clearance."""
    theta = np.linspace(0.0, 2.0 * math.pi, 7201)
    l2, l3 = preset.crank_length_m, preset.rod_length_m
    # the RSSP's block moves across its guide in y; the slider-crank's is held in its plane
    # (x = 0), its guide along y
    side = l2 * np.abs(np.sin(theta)) + joint.clearance_y if preset.guide_axis == 0 else 0.0
    worst = float(np.max(side ** 2 + (np.abs(preset.slider_height_m + l2 * np.cos(theta))
                                      + joint.clearance_z) ** 2))
    if worst < l3 ** 2:
        return
    key = "clearance_y" if joint.clearance_y >= joint.clearance_z else "clearance_z"
    raise ConfigError(f"joints.P.{key}", getattr(joint, key),
                      f"clearances of joint P that keep the block within the rod's reach "
                      f"({l3:g} m) anywhere in its guide at every crank angle (these let it lie "
                      f"{math.sqrt(worst):.3g} m from the crank pin across the guide)")


def guide_row(row: np.ndarray, joint: PrismaticJointConfig, preset: Preset) -> None:
    """Joint P's own columns of its jp row: the block, the two clearances (J_C, the joint's
    clearance, the smaller), the corners' edge radius, and the walls' wear maps along the
    guide: from the ideal slider's travel (docs/physics.md section 1) widened by the block's
    half length and 5 % of the travel each way. A guide has no socket or ball radius: its
    J_RI and J_RJ are 0."""
    length, width, height = joint.block
    row[L.J_BLOCK_LENGTH] = length
    row[L.J_WIDTH] = width
    row[L.J_HEIGHT] = height
    row[L.J_CY] = joint.clearance_y
    row[L.J_CZ] = joint.clearance_z
    row[L.J_C] = joint.clearance
    row[L.J_RI] = 0.0
    row[L.J_RJ] = 0.0
    row[L.J_CORNER_RADIUS] = joint.corner_radius
    theta = np.linspace(0.0, 2.0 * math.pi, 721)
    check_guide_reach(joint, preset)
    x = ideal_slider_position(preset, theta)
    margin = 0.5 * length + 0.05 * float(x.max() - x.min())
    row[L.J_X0] = float(x.min()) - margin
    row[L.J_XSPAN] = float(x.max() - x.min()) + 2.0 * margin


def static_penetration(force_N: float, c: float, ew: float, ri: float, rj: float = 0.0,
                       exponent: float = 0.0, *, plain: bool = False) -> float:
    """Penetration delta [m] at which the contact's elastic force equals force_N [N].

    ``exponent`` 0, the paper's law: Newton on F_el(delta) = force_N from the small-penetration
    estimate F_el ~ (2 K / c) delta^2, K = 4 pi E_w R_i / 5; F_el is convex and increasing, so
    the iteration converges monotonically from above. The power law F_el = A c (delta/c)^n
    (ball radius ``rj``, n = ``exponent``) is inverted in closed form. ``plain``: the contact
    functions' Python forms (:func:`as_python`), so that planning compiles nothing.
    """
    from .core import contact

    elastic_force, power_coefficient, stiffness_factor = (
        (as_python(f) if plain else f)
        for f in (contact.elastic_force, contact.power_coefficient, contact.stiffness_factor))

    if force_N <= 0.0:
        return 0.0
    if exponent != 0.0:
        return c * (force_N / (power_coefficient(ew, ri, rj) * c)) ** (1.0 / exponent)
    delta = math.sqrt(force_N * c / (2.0 * stiffness_factor(ew, ri)))
    delta *= 1.5  # start above the root
    for _ in range(60):
        f, df = elastic_force(delta, c, ew, ri, rj, exponent)
        step = (f - force_N) / df
        delta -= step
        if abs(step) <= 1e-15 * delta:
            break
    return delta


def hertz_sink_warnings(cfg: Config, materials: dict) -> list[str]:
    """One text per clearance joint whose clearance is below its Hertz sink: the static
    penetration under the joint's static load, here the ideal mechanism's joint reaction at
    the start (weights and inertia at cfg.mechanism.theta0 and speed), through the joint's
    own contact law and modulus (:func:`static_penetration`, :func:`equivalent_modulus`).
    Such a joint sits deeper in its socket than its clearance: its contact law is used
    beyond the small contact it describes (docs/physics.md 4.3). The text says
    whether the run will stop: where the sink also passes the joint's penetration stop
    (:func:`penetration_stop`; with ``contact.max_penetration_fraction`` that fraction of c,
    and then the warning comes at that fraction).

    At the guide P the reaction's component across each pair of walls (y, z) is carried by
    the face of the block that meets the wall, lying flat on it (:func:`face_sink`): the
    least sink a case can have (a tilted block carries the load on one edge, deeper).
    """
    from .core.dynamics import ideal_joint_forces

    packed = pack(cfg, materials, seat=False)
    p, jp = packed.p, packed.jp
    preset = PRESETS[cfg.mechanism.preset]
    forces = ideal_joint_forces(0.0, initial_state(preset, cfg.mechanism.theta0,
                                                   cfg.mechanism.omega_rad_s), p, jp)
    fraction = cfg.contact.max_penetration_fraction
    out = []

    def outcome(sink: float, stop: float) -> str:
        if sink > stop:
            if fraction is not None:
                return (f"beyond contact.max_penetration_fraction ({fraction:g}) of the "
                        "clearance; the run will stop on penetration_exceeded")
            return (f"beyond its penetration stop ({stop:.3g} m); the run will stop on "
                    "penetration_exceeded")
        return ("deeper than its clearance: its contact law is used beyond the small contact "
                "it describes (docs/physics.md 4.3); the run goes on")

    for j, joint in enumerate(JOINTS):
        if jp[j, L.J_CLEARANCE] == 0.0:
            continue
        stop = jp[j, L.J_PEN_STOP]
        found = HOST_HOOKS[table_type(j, p)].sink(joint.name, j, forces[j], p, jp,
                                            min(jp[j, L.J_C], stop))
        if found is not None:
            sink, text = found
            out.append(f"{text}, {outcome(sink, stop)}")
    return out


def point_sink(name: str, j: int, force: np.ndarray, p: np.ndarray, jp: np.ndarray,
               limit: float) -> tuple[float, str] | None:
    """A point contact's Hertz sink (:func:`hertz_sink_warnings`): the static penetration of
    its law (``HOST_HOOKS[type].law``) under the static load ``force`` [N] (its axial part
    left out where the joint's axial play is ideal, ``jointtypes.JointKind.axial_ideal``),
    and the warning's text, where it reaches ``limit`` [m]; else None."""
    described = joint_kind(table_type(j, p))
    f = force.copy()
    if described.axial_ideal:
        f[0] = 0.0
    c = jp[j, L.J_C]
    size = float(np.linalg.norm(f))
    if not (math.isfinite(size) and size > 0.0):
        return None
    sink = static_penetration(size, c, jp[j, L.J_EW], jp[j, L.J_RI], jp[j, L.J_RJ],
                              HOST_HOOKS[described.name].law(p))
    if sink < limit:
        return None
    return sink, (f"joints.{name}.clearance ({c:g} m) is below joint {name}'s Hertz sink: "
                  f"{sink:.3g} m under its static load of {size:.3g} N")


def guide_sink(name: str, j: int, force: np.ndarray, p: np.ndarray, jp: np.ndarray,
               limit: float) -> tuple[float, str] | None:
    """The guide's contact sink (:func:`hertz_sink_warnings`): the reaction across the y
    walls and across the z walls, a face each (:func:`face_sink`), against ``limit`` (the
    stop compares the deepest corner with the smaller clearance, jp[J_C])."""
    c = jp[j, L.J_C]
    key = "clearance_y" if jp[j, L.J_CY] <= jp[j, L.J_CZ] else "clearance_z"
    force = global_to_guide(force, int(p[L.P_GUIDE]))
    for axis in (1, 2):
        load = abs(float(force[axis]))
        if not (math.isfinite(load) and load > 0.0):
            continue
        sink = face_sink(load, jp[j], axis)
        if sink >= limit:
            return sink, (f"joints.{name}.{key} ({c:g} m) is below joint {name}'s contact "
                          f"sink: {sink:.3g} m of the block's face on its {'yz'[axis - 1]} "
                          f"walls under a static load of {load:.3g} N")
    return None


def film_coefficient(viscosity: float, radius: float, length: float, clearance: float) -> float:
    """The bearing film's viscous coefficient [N s/m]: Petroff's shear of a film of thickness
    c over the bearing's surface 2 pi R L, F = eta (2 pi R L / c) v (Petroff 1883; Hamrock,
    Schmid & Jacobson, *Fundamentals of Fluid Film Lubrication*, 2nd ed. 2004, ch. 8), along
    the journal's slip (docs/physics.md 3.6)."""
    return viscosity * 2.0 * math.pi * radius * length / clearance


#: The deepest a corner of the guide's block may go, a fraction of its edges' radius r_c:
#: there a rounded edge's contact half-width, about sqrt(r_c delta), is 0.32 r_c
#: (:func:`penetration_stop`).
CORNER_DEPTH_FRACTION = 0.1


def penetration_stop(row: np.ndarray, kind: str, p: np.ndarray, fraction: float | None,
                     load_bound: float) -> float:
    """The penetration [m] beyond which joint ``row`` (its packed jp row, of joint type
    ``kind``) stops its run on penetration_exceeded (docs/physics.md 4.3).

    ``fraction`` given (``contact.max_penetration_fraction``): that fraction of the clearance
    (at P, of the smaller of its two), the earlier rule. Otherwise the depth at which the
    contact law leaves its validity: where the joint's own law, with its modulus, carries
    ``load_bound`` [N] (``contact.load_bound``; at P on one edge line touching at its end
    corner only, the deepest a corner can be sent for a load); at P no deeper than
    :data:`CORNER_DEPTH_FRACTION` of the edges' radius. A coating's thickness does not cap
    it: the penetration is the two bodies' approach, which under a thin layer the base
    carries (a 1 um MoS2 layer in a 0.25 mm steel socket reaches 3.1 um at 300 r/min). The
    unworn clearance is used: wear softens the law, so a worn joint's stop is, if anything,
    early."""
    if fraction is not None:
        return fraction * float(row[L.J_C])
    return HOST_HOOKS[kind].stop(row, p, load_bound)


def point_stop(row: np.ndarray, p: np.ndarray, load_bound: float, law: float) -> float:
    """A point contact's penetration stop (:func:`penetration_stop`): the depth at which its
    law ``law`` carries ``load_bound`` [N]."""
    return static_penetration(load_bound, float(row[L.J_C]), row[L.J_EW], row[L.J_RI],
                              row[L.J_RJ], law, plain=True)


def guide_stop(row: np.ndarray, p: np.ndarray, load_bound: float) -> float:
    """The guide's penetration stop (:func:`penetration_stop`): the edge lines' law (section
    3.7): an edge tilted until only its end corner touches carries k_l L delta / 2 at the
    corner's depth delta, the least load for a depth that a line in contact along its
    length can have, on the softer wall's lines; no deeper than
    :data:`CORNER_DEPTH_FRACTION` of the edges' radius r_c (jp[J_CORNER_RADIUS]), where the rounded
    edge's line contact wants its width well inside r_c."""
    from .core.prismatic import line_stiffness

    one = np.ascontiguousarray(row[None, :], dtype=np.float64)
    kl = min(as_python(line_stiffness)(one, 0, wall, row[L.J_EW]) for wall in (0, 2))
    depth = load_bound / (0.5 * kl * float(row[L.J_BLOCK_LENGTH]))
    return min(depth, CORNER_DEPTH_FRACTION * float(row[L.J_CORNER_RADIUS]))


def worn_contact(jp: np.ndarray, j: int, wmap: np.ndarray, normal_socket: np.ndarray,
                 p: np.ndarray) -> tuple[float, float]:
    """Local clearance c_eff [m] and modulus [Pa] (jp[J_EW]) that the kernel's contact law uses in
    socket-frame direction ``normal_socket`` of joint j's worn socket (docs/physics.md 3.1).

    The kernel's own functions: ``wear.worn_surface`` reads the map as the run will (bin or
    bilinear, ``wear.interpolate``; feedback on or off) and ``contact.surface`` switches to
    the base material where the coating is worn through.
    """
    from .core.contact import surface

    n = tuple(float(v) for v in normal_socket)
    wmap = np.ascontiguousarray(wmap, dtype=np.float64)
    h, worn = HOST_HOOKS[table_type(j, p)].worn(wmap, j, n, jp, p)
    ew, _, _ = surface(jp, j, worn)
    return float(jp[j, L.J_C] + h), float(ew)


def seated_offsets(preset: Preset, p: np.ndarray, jp: np.ndarray, theta0: float,
                   omega: float, wmap: np.ndarray | None = None) -> np.ndarray:
    """Ball-centre offsets [m] (N_JOINTS x 3, global frame, in the table's order) of a
    seated start.

    Each clearance joint's ball rests on the socket wall along the ideal mechanism's joint
    reaction at t = 0: the force F on the ball is carried by a contact whose normal n points
    along -F, at the eccentricity c + delta_s where the elastic force equals ``|F|``. With a
    wear map (a socket worn by an earlier run), c is the local worn clearance c_eff(n) and
    the modulus the one the contact law uses there. The journal of O leans along the
    reaction's part in the bearing's plane (y, z), with the journal's law, turned by the
    friction angle where friction is on (:func:`journal_seat`), so that its contact force,
    normal and friction together, is the ideal reaction; the balls of the spherical joints
    likewise, against the friction of their slip at the start (:func:`ball_seats`).
    """
    from .core.dynamics import ideal_joint_forces

    y_ideal = initial_state(preset, theta0, omega)
    forces = ideal_joint_forces(0.0, y_ideal, p, jp)
    offsets = np.zeros((L.N_JOINTS, 3))
    for j, joint in enumerate(JOINTS):
        if jp[j, L.J_CLEARANCE] == 0.0:
            continue
        offsets[j] = HOST_HOOKS[table_type(j, p)].seat(j, forces[j].copy(), p, jp, y_ideal, omega,
                                                 wmap)
    return ball_seats(preset, p, jp, theta0, omega, forces, offsets, y_ideal, wmap)


def point_seat(j: int, f: np.ndarray, p: np.ndarray, jp: np.ndarray, y_ideal: np.ndarray,
               omega: float, wmap: np.ndarray | None) -> np.ndarray:
    """A point contact's seated offset (:func:`seated_offsets`): leaning along the ideal
    reaction f (its axial part left out where the joint's axial play is ideal: a revolute's,
    and the slider-crank's pins, whose axis is x), at its own law's static penetration
    (:func:`leaning_offset`); the journal turned by the friction angle
    (:func:`journal_seat`); centred where there is no load to lean on."""
    described = joint_kind(table_type(j, p))
    hooks = HOST_HOOKS[described.name]
    if described.axial_ideal or p[L.P_GUIDE] == 1.0:
        f[0] = 0.0          # axial: ideal
    law = hooks.law(p)
    size = float(np.linalg.norm(f))
    if not (math.isfinite(size) and size > 0.0):
        return np.zeros(3)  # no load to lean on: the ball stays centred
    u = f / size            # the contact's force on the ball leans along u
    if hooks.spins and grounded(j):
        # a journal spinning with the crank in the ground's bearing (O); the slider-crank's
        # pins, whose bearings turn with the rod or ride the slider, turn in ball_seats
        u, size = journal_seat(u, size, p, jp, j, omega, wmap)
    return leaning_offset(j, u, size, law, p, jp, y_ideal, wmap)


def guide_seat(j: int, f: np.ndarray, p: np.ndarray, jp: np.ndarray, y_ideal: np.ndarray,
               omega: float, wmap: np.ndarray | None) -> np.ndarray:
    """The block's seated offset in its guide's frame (:func:`seated_offsets`,
    :func:`seated_block`; the ideal guide's force f global), on the worn walls where wear
    feeds back (:func:`worn_walls`)."""
    g = int(p[L.P_GUIDE])
    f = global_to_guide(f, g)
    offset = seated_block(f, jp[j], p)
    if wmap is not None and p[L.P_FEEDBACK] != 0.0:
        r4 = global_to_guide(y_ideal[L.Y_R4:L.Y_R4 + 3], g) + offset
        offset = seated_block(f, jp[j], p, worn_walls(jp, j, wmap, p, r4))
    return offset


def leaning_offset(j: int, u: np.ndarray, size: float, law: float, p: np.ndarray,
                   jp: np.ndarray, y_ideal: np.ndarray, wmap: np.ndarray | None) -> np.ndarray:
    """The offset [m] of joint j's ball (global) whose contact force, normal along -n = u,
    carries the normal load ``size`` [N]: -(c + delta_s) u, delta_s the static penetration
    of the joint's law ``law`` (c and the modulus those of the worn socket in that
    direction where ``wmap`` is given)."""
    from .core.kinematics import rotation, trig

    joint = JOINTS[j]
    c, ew = jp[j, L.J_C], jp[j, L.J_EW]
    if wmap is not None:
        # the socket body's angles (the table's; the ground, with no state, unrotated)
        socket = next(body for body in BODIES if body.name == joint.socket.body)
        phi = np.zeros(3) if socket.y_phi is None else y_ideal[socket.y_phi:socket.y_phi + 3]
        rot = np.array(rotation(trig(*phi))).reshape(3, 3)
        c, ew = worn_contact(jp, j, wmap, rot.T @ (-u), p)
    delta = static_penetration(size, c, ew, jp[j, L.J_RI], jp[j, L.J_RJ], law)
    return -(c + delta) * u


#: Fixed-point iterations of :func:`ball_seats` at most; each turns the seat by at most the
#: friction angle's sine times the last turn (mu' = 0.167: 1e-16 in 20).
BALL_SEAT_ITERATIONS = 60


def ball_seats(preset: Preset, p: np.ndarray, jp: np.ndarray, theta0: float, omega: float,
               forces: np.ndarray, offsets: np.ndarray, y_ideal: np.ndarray,
               wmap: np.ndarray | None = None) -> np.ndarray:
    """The seated offsets with each loaded spherical clearance joint's ball turned so that
    its contact force, normal and friction together, is the ideal reaction ``forces[j]``
    (docs/physics.md 1.2). Friction off: ``offsets`` unchanged.

    At the start the ball turns with its body and the socket with its own (the rod's rate
    against the crank's at A, the slider's at B), so the contact point slips and friction
    mu' F_N acts along the slip's tangent direction f (``mu' = mu c_d(|v_t|)``, section 3.3).
    With tan(phi) = mu', ``F_N (-n) + mu' F_N f = |F| F^`` holds when
    ``-n = cos(phi) F^ - sin(phi) g``, g the unit part of f across F^, and
    ``F_N = |F| cos(phi)``.
    The slip's direction depends on n (and the start's velocities on every offset), so the
    seat is a fixed point: the kernel's own contact (``dynamics.start_contacts``) at the
    state the offsets give reads f and mu', the seat is turned, and again, until the
    offsets stop moving (a contraction by about sin(phi) per turn)."""
    from .core.dynamics import start_contacts

    # the slider-crank's pins turn in its plane only (their axial play is ideal: x)
    planar = p[L.P_GUIDE] == 1.0
    seats = []
    for j, joint in enumerate(JOINTS):
        load = forces[j].copy()
        if planar:
            load[0] = 0.0
        size = float(np.linalg.norm(load))
        hooks = HOST_HOOKS[table_type(j, p)]
        turns = hooks.turns_at_start or (hooks.spins and not grounded(j))
        if (turns and jp[j, L.J_CLEARANCE] != 0.0
                and math.isfinite(size) and size > 0.0):
            seats.append((j, load / size, size, hooks.law(p)))
    if p[L.P_FRICTION] == 0.0 or not seats:
        return offsets
    grid = np.zeros((L.N_JOINTS, 1, 1)) if wmap is None else wmap
    offsets = offsets.copy()
    for _ in range(BALL_SEAT_ITERATIONS):
        by_name = {row.name: offsets[k] for k, row in enumerate(JOINTS)}
        y0 = initial_state(preset, theta0, omega, by_name["A"], by_name["B"], by_name["O"],
                           by_name["P"])
        force, fn, normal = start_contacts(y0, p, jp, grid)
        moved = 0.0
        for j, f_hat, size, law in seats:
            friction = force[j] + fn[j] * normal[j]     # the contact force less its normal part
            ft = float(np.linalg.norm(friction))
            if not (fn[j] > 0.0 and math.isfinite(ft) and ft > 0.0):
                continue                                # no slip, no friction to balance
            mu = ft / fn[j]
            cos, sin = 1.0 / math.sqrt(1.0 + mu * mu), mu / math.sqrt(1.0 + mu * mu)
            across = friction / ft - (friction / ft @ f_hat) * f_hat
            if planar:
                across[0] = 0.0
            if not np.linalg.norm(across) > 0.0:
                continue                                # friction along the load: no turn helps
            g = across / np.linalg.norm(across)
            u = cos * f_hat - sin * g
            new = leaning_offset(j, u / np.linalg.norm(u), size * cos, law, p, jp, y_ideal, wmap)
            moved = max(moved, float(np.linalg.norm(new - offsets[j]) / np.linalg.norm(new)))
            offsets[j] = new
        if moved <= 1e-15:
            break
    return offsets


def journal_seat(u: np.ndarray, size: float, p: np.ndarray, jp: np.ndarray, j: int,
                 omega: float, wmap: np.ndarray | None = None) -> tuple[np.ndarray, float]:
    """The seated journal's normal and load under friction (docs/physics.md 3.6): the
    direction -n [-] (unit, in the bearing's plane) and the normal force F_N [N] at which
    the contact's force, F_N (-n) plus the friction of the journal spinning in its bearing,
    equals the ideal reaction ``|F| u`` on the crank.

    The journal turns with the crank at omega about x while its centre stays put, so its
    contact point slips at ``R_j |omega|`` along sign(omega) x x n, and friction adds
    mu' F_N sign(omega) x x (-n), ``mu' = mu c_d(R_j |omega|)`` (section 3.3). The sum is
    F_N sqrt(1 + mu'^2) times -n turned by sign(omega) atan(mu') about x: -n is u turned
    back by the friction angle, and ``F_N = |F| / sqrt(1 + mu'^2)``. Friction off, or no
    slip: u and ``|F|`` unchanged. ``wmap``: a worn bearing, whose friction coefficient is the
    base's where its coating is worn through at u's direction."""
    from .core import revolute
    from .core.contact import friction_factor

    if p[L.P_FRICTION] == 0.0 or omega == 0.0:
        return u, size
    mu = jp[j, L.J_MU]
    film = jp[j, L.J_FILM]
    if wmap is not None and revolute.worn_through(np.ascontiguousarray(wmap, dtype=np.float64), j,
                                                  tuple(float(v) for v in -u), float(jp[j, L.J_COAT])):
        mu = jp[j, L.J_MU_BASE]
    slip = jp[j, L.J_RJ] * abs(omega)
    mu_eff = mu * as_python(friction_factor)(slip, p[L.P_V0], p[L.P_V1])
    drag = film * slip                  # the film's viscous shear [N] (section 3.6)
    if drag == 0.0 or not drag < size:
        # no film (or one whose drag alone exceeds the load: no seat balances it)
        angle = -math.copysign(math.atan(mu_eff), omega)
        normal = size / math.sqrt(1.0 + mu_eff * mu_eff)
    else:
        # |F|^2 = F_N^2 + (mu' F_N + drag)^2, the tangential force mu' F_N + drag
        a = 1.0 + mu_eff * mu_eff
        normal = (-mu_eff * drag + math.sqrt(mu_eff * mu_eff * drag * drag
                                             - a * (drag * drag - size * size))) / a
        angle = -math.copysign(math.atan2(mu_eff * normal + drag, normal), omega)
    cs, sn = math.cos(angle), math.sin(angle)
    turned = np.array([0.0, cs * u[1] - sn * u[2], sn * u[1] + cs * u[2]])
    return turned, normal


def face_sink(load_N: float, row: np.ndarray, axis: int) -> float:
    """Penetration [m] of the block's face lying flat on a wall across ``axis`` (1: a y wall,
    2: a z wall) of the guide P (its jp ``row``) under the load ``load_N`` [N]: both edge
    lines of the face in contact along their length, 2 k_l L delta = load
    (``prismatic.line_stiffness``, docs/physics.md 3.7)."""
    from .core.prismatic import line_stiffness

    stiffness = as_python(line_stiffness)(np.ascontiguousarray(row[None, :]), 0, 2 * axis - 2,
                                          row[L.J_EW])
    return load_N / (2.0 * stiffness * row[L.J_BLOCK_LENGTH])


def worn_walls(jp: np.ndarray, j: int, wmap: np.ndarray, p: np.ndarray,
               r4: np.ndarray) -> tuple[float, float, float, float]:
    """The least wear depth [m] under the four corners that face each wall of prismatic
    joint j (+y, -y, +z, -z), the block unrotated with its centroid at ``r4``: read as the
    kernel reads it (``prismatic.gap``: the bin, or bilinearly with ``wear.interpolate``)."""
    from .core.prismatic import IDENTITY, gap, guide_point, slot_corner, slot_wall

    depth = [math.inf] * 4
    wmap = np.ascontiguousarray(wmap, dtype=np.float64)
    for k in range(L.P_SLOTS):
        q = tuple(float(a + b) for a, b in zip(r4, slot_corner(jp, j, k)))
        wall = slot_wall(k)[0]
        depth[wall] = min(depth[wall], float(gap(jp, j, wmap, p, k, q, guide_point(p, q),
                                                      IDENTITY)[4]))
    return depth[0], depth[1], depth[2], depth[3]


def seated_block(force: np.ndarray, row: np.ndarray, p: np.ndarray,
                 depth: tuple[float, ...] = (0.0, 0.0, 0.0, 0.0)) -> np.ndarray:
    """The offset [m] (0, y, z) of a block seated in its guide (joint P's jp ``row``) under
    the ideal guide's force ``force`` [N] on it: against the y wall the force's y part
    pushes from, and likewise in z, each wall's four corners sharing that part of the load
    (its face lying flat on the wall, :func:`face_sink`, with the coated modulus); a part
    that is 0 or not finite leaves the block centred in that direction. ``depth``: each
    wall's wear under its least worn corner (+y, -y, +z, -z; :func:`worn_walls`), which moves
    the wall's surface out by that much: the least worn corner rests on it, the others start
    clear of their deeper wear."""
    out = np.zeros(3)
    for axis, c in ((1, row[L.J_CY]), (2, row[L.J_CZ])):
        part = float(force[axis])
        if not (math.isfinite(part) and part != 0.0):
            continue
        # the block rests on the wall opposite the force's direction: -y (-z) for a part > 0
        c = c + depth[2 * axis - 2 + (1 if part > 0.0 else 0)]
        delta = face_sink(abs(part), row, axis)
        out[axis] = -math.copysign(c + delta, part)
    return out


def perturbed_block(nominal: np.ndarray, shift: np.ndarray, row: np.ndarray) -> np.ndarray:
    """A block's nominal offset across its guide [m] (0, y, z) moved by ``shift`` times each
    direction's clearance (joint P's jp ``row``: c_y, c_z) and kept, direction by direction,
    within ``max(|nominal|, c)``: the guide is a box, so no corner starts deeper in a wall
    than the seated start's (a limit on the offset's length let one direction grow while
    the other shrank: corners 37 um into a wall)."""
    d = np.array(nominal, dtype=float)
    for axis, c in ((1, float(row[L.J_CY])), (2, float(row[L.J_CZ]))):
        limit = max(abs(float(nominal[axis])), c)
        d[axis] = min(max(float(nominal[axis]) + c * float(shift[axis]), -limit), limit)
    return d


@dataclass(frozen=True)
class MemberPerturbation:
    """What makes one ensemble member differ from the nominal case (docs/physics.md section 10).

    Attributes
    ----------
    crank_phase_rad : float
        Added to theta0 [rad].
    ball_offset : np.ndarray
        (N_JOINTS, 3) per joint (A, B, O): ball-centre displacement from the nominal start,
        as a fraction of that joint's clearance (global frame), inside the ball of radius
        ``perturb.ball_offset`` (O's axial part is dropped where it is applied).
    wear_factor : np.ndarray
        (N_JOINTS,) per joint: multiplies the wear coefficient k (lognormal, mean 1).
    """

    crank_phase_rad: float
    ball_offset: np.ndarray
    wear_factor: np.ndarray


def member_perturbation(ensemble: EnsembleConfig) -> MemberPerturbation:
    """The perturbation of member ``ensemble.member``, from ``(seed, member)`` only.

    The generator is ``np.random.SeedSequence(seed, spawn_key=(member,))`` (the member-th
    child of ``SeedSequence(seed)``), so a member's draw does not depend on the other members,
    the workers or the order cases finish. Every draw is made whatever the amplitudes, in a
    fixed order (phase, then per joint A, B, O: direction, radius, wear), so switching one
    perturbation on or off leaves the others' values unchanged (and A's and B's as they were
    before joint O existed).
    """
    rng = np.random.default_rng(np.random.SeedSequence(ensemble.seed, spawn_key=(ensemble.member,)))
    pert = ensemble.perturb
    phase = rng.uniform(-1.0, 1.0)
    offsets = np.zeros((L.N_JOINTS, 3))
    factors = np.ones(L.N_JOINTS)
    sigma = math.sqrt(math.log1p(pert.wear_coefficient_cv ** 2))
    for j in range(L.N_JOINTS):
        direction = rng.standard_normal(3)
        radius = rng.random() ** (1.0 / 3.0)        # uniform in the unit ball
        z = rng.standard_normal()
        norm = float(np.linalg.norm(direction))
        if norm > 0.0:
            offsets[j] = pert.ball_offset * radius * direction / norm
        factors[j] = math.exp(sigma * z - 0.5 * sigma ** 2)
    return MemberPerturbation(math.radians(pert.crank_phase_deg) * phase, offsets, factors)


def perturbed_offset(nominal: np.ndarray, shift: np.ndarray, clearance: float) -> np.ndarray:
    """Nominal ball-centre offset [m] moved by ``shift * clearance`` and kept within
    ``max(|nominal|, clearance)`` of the socket centre: never deeper in the wall than the seated
    start (docs/physics.md section 10)."""
    d = nominal + clearance * shift
    limit = max(float(np.linalg.norm(nominal)), clearance)
    size = float(np.linalg.norm(d))
    return d * (limit / size) if size > limit else d


def socket_fill(row: np.ndarray, joint: AnyJoint, preset: Preset) -> None:
    """A spherical joint's own columns of its jp row: none beyond the common ones."""


def bearing_fill(row: np.ndarray, joint: AnyJoint, preset: Preset) -> None:
    """The bearing's own columns of its jp row: its length, and with a clearance its
    lubricant film's coefficient (:func:`film_coefficient`). The slider-crank's pins (A and
    B, a ``JointConfig`` section): their ``length``, else the preset's
    (``Preset.pin_length_m``); dry (no film)."""
    if not isinstance(joint, RevoluteJointConfig):
        length = getattr(joint, "length", None)
        row[L.J_LENGTH] = preset.pin_length_m if length is None else length
        return
    bearing = joint
    row[L.J_LENGTH] = bearing.length
    c = bearing.clearance
    if c > 0.0:
        row[L.J_FILM] = film_coefficient(bearing.lubricant_viscosity, bearing.bearing_radius,
                                         bearing.length, c)


def guide_fill(row: np.ndarray, joint: AnyJoint, preset: Preset) -> None:
    """The guide's own columns of its jp row (:func:`guide_row`)."""
    guide_row(row, cast(PrismaticJointConfig, joint), preset)


def socket_law(p: np.ndarray) -> float:
    """A spherical joint's elastic law: the case's (``P_EXPONENT``; 0: the paper's)."""
    return p[L.P_EXPONENT]


def journal_law(p: np.ndarray) -> float:
    """The journal's elastic law (``revolute.journal_law``)."""
    from .core.revolute import journal_law as law

    return as_python(law)(p)


def no_law(p: np.ndarray) -> float:
    """A type whose contact is no point contact's law (the guide's edge lines; the
    bushing, which has no contact)."""
    raise ValueError("this joint type's contact has no point contact law")


def table_type(j: int, p: np.ndarray) -> str:
    """Joint j's type in the mechanism of a packed case's ``p`` (``core.joints.row_types``:
    the slider-crank's A and B revolute, ``p[P_GUIDE]`` 1; else the joint table's)."""
    return row_types(bool(p[L.P_GUIDE] == 1.0))[j]


def grounded(j: int) -> bool:
    """Whether joint j's socket sits in the ground (O's bearing, P's guide)."""
    return JOINTS[j].socket.body == "ground"


def row_type(jp: np.ndarray, j: int, p: np.ndarray | None = None) -> str:
    """The joint type that joint j of a packed case runs as (its ``HOST_HOOKS`` key): the
    bushing where its row says so (``J_BUSHING``), else its type in the case's mechanism
    (:func:`table_type` of ``p``; without ``p`` the joint table's)."""
    if jp[j, L.J_BUSHING] != 0.0:
        return BUSHING
    return JOINTS[j].type if p is None else table_type(j, p)


def socket_worn(wmap: np.ndarray, j: int, n: tuple, jp: np.ndarray,
                p: np.ndarray) -> tuple[float, bool]:
    """(h, worn) of a socket's map over its sphere at the socket-frame direction n
    (``wear.worn_surface``), as :func:`worn_contact` reads it."""
    from .core.wear import worn_surface

    h, _, worn = worn_surface(wmap, j, n, float(jp[j, L.J_COAT]),
                              bool(p[L.P_FEEDBACK] != 0.0), bool(p[L.P_INTERP] != 0.0))
    return h, worn


def bearing_worn(wmap: np.ndarray, j: int, n: tuple, jp: np.ndarray,
                 p: np.ndarray) -> tuple[float, bool]:
    """(h, worn) of the bearing's map, one row around the bearing, at the direction n
    (``revolute.map_read``, ``revolute.worn_through``)."""
    from .core import revolute

    # in the bearing's frame (the socket body's for A and B in the slider-crank's rod and
    # slider, revolute.to_bearing)
    n = tuple(float(v) for v in as_python(revolute.to_bearing)(j, n))
    h = (revolute.map_read(wmap, j, n, bool(p[L.P_INTERP] != 0.0))[0]
         if p[L.P_FEEDBACK] != 0.0 else 0.0)
    return h, revolute.worn_through(wmap, j, n, float(jp[j, L.J_COAT]))


def point_perturb(nominal: np.ndarray, shift: np.ndarray, row: np.ndarray) -> np.ndarray:
    """A point contact's perturbed start (:func:`perturbed_offset`, its clearance jp[J_C])."""
    return perturbed_offset(nominal, shift, float(row[L.J_C]))


def point_rate(jp: np.ndarray, j: int, p: np.ndarray, preset: Preset, m_ref: float) -> float:
    """A point contact's stiff rate [1/s] at its penetration stop (jp[J_PEN_STOP]) on the
    lightest mass ``m_ref`` [kg] it can meet (``simulation.check_step``), with its own law."""
    from .core.contact import elastic_force

    row = jp[j]
    _, stiffness = as_python(elastic_force)(row[L.J_PEN_STOP], row[L.J_C], row[L.J_EW],
                                            row[L.J_RI], row[L.J_RJ],
                                            HOST_HOOKS[table_type(j, p)].law(p))
    return math.sqrt(stiffness / m_ref)


def guide_rate(jp: np.ndarray, j: int, p: np.ndarray, preset: Preset, m_ref: float) -> float:
    """The guide's stiff rate [1/s] (``simulation.check_step``): a corner's bound on its
    edge line's stiffness, k_l L / 2 (``prismatic.slot_rate``), the stiffer of the two
    faces, on the free block's mass at the corner."""
    from .core.prismatic import line_stiffness

    row = jp[j]
    corner = 0.25 * (row[L.J_BLOCK_LENGTH] ** 2 + row[L.J_WIDTH] ** 2 + row[L.J_HEIGHT] ** 2)
    mass = 1.0 / (1.0 / preset.slider_mass_kg + corner / min(preset.slider_inertia_kgm2))
    stiffness = max(0.5 * as_python(line_stiffness)(jp, j, wall, row[L.J_EW])
                    * row[L.J_BLOCK_LENGTH] for wall in (0, 2))
    return math.sqrt(stiffness / mass)


@dataclass(frozen=True)
class TypeHooks:
    """A joint type's behaviour in packing and checking a case (one entry of
    :data:`HOST_HOOKS`, keyed by the type's name as ``jointtypes.KINDS``): what the packing,
    the seated start, the checks and the step bound call, so that none of them branches on
    the type's name."""

    #: fills the type's own columns of its jp row (row, its config section, the preset)
    fill: Callable[[np.ndarray, AnyJoint, Preset], None]
    #: its elastic law's exponent for the case's p (:func:`static_penetration`'s)
    law: Callable[[np.ndarray], float]
    #: its penetration stop [m] (row, p, contact.load_bound) without a fraction rule
    stop: Callable[[np.ndarray, np.ndarray, float], float]
    #: its sink under the start's static load against a limit: (sink, warning) or None
    sink: Callable[[str, int, np.ndarray, np.ndarray, np.ndarray, float],
                   tuple[float, str] | None]
    #: its seated offset [m] (j, ideal force, p, jp, ideal state, omega, wear map)
    seat: Callable[[int, np.ndarray, np.ndarray, np.ndarray, np.ndarray, float,
                    np.ndarray | None], np.ndarray]
    #: an ensemble member's start (nominal offset, shift in clearances, row)
    perturb: Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]
    #: (wear depth, coating worn through) of its map in a socket-frame direction
    worn: Callable[[np.ndarray, int, tuple, np.ndarray, np.ndarray], tuple[float, bool]]
    #: its stiff rate [1/s] for the step bound (jp, j, p, preset, lightest mass)
    rate: Callable[[np.ndarray, int, np.ndarray, Preset, float], float]
    #: whether its ball turns against the slip's friction at a seated start
    #: (:func:`ball_seats`)
    turns_at_start: bool = False
    #: whether its seat turns by the friction of the journal spinning in place
    #: (:func:`journal_seat`)
    spins: bool = False


def bushing_fill(row: np.ndarray, joint: Any, preset: Preset) -> None:
    """A bushing's own columns (core/bushing.py): the flag, the stiffness and the damping,
    radial and axial (``joints.X.bushing_stiffness``, ``bushing_damping``)."""
    kr, ka = joint.bushing_stiffness
    cr, ca = joint.bushing_damping
    row[L.J_BUSHING] = 1.0
    row[L.J_K_RADIAL] = kr
    row[L.J_K_AXIAL] = ka
    row[L.J_C_RADIAL] = cr
    row[L.J_C_AXIAL] = ca


def bushing_rate(jp: np.ndarray, j: int, p: np.ndarray, preset: Preset, m_ref: float) -> float:
    """A bushing's stiff rate [1/s] for the step bound: its stiffer spring and damper on
    the lightest mass ``m_ref`` [kg] (``contact.stiff_rate``; the kernel's sub-step rule
    reads the joint's own mobility, ``bushing.rate``)."""
    from .core.contact import stiff_rate

    row = jp[j]
    return float(as_python(stiff_rate)(m_ref, max(row[L.J_K_RADIAL], row[L.J_K_AXIAL]),
                                       max(row[L.J_C_RADIAL], row[L.J_C_AXIAL])))


def no_sink(name: str, j: int, force: np.ndarray, p: np.ndarray, jp: np.ndarray,
            limit: float) -> None:
    """A joint without a gap sinks into no wall: no warning."""
    return None


def unseated(j: int, f: np.ndarray, p: np.ndarray, jp: np.ndarray, y_ideal: np.ndarray,
             omega: float, wmap: np.ndarray | None) -> np.ndarray:
    """A bushing starts undeflected (docs/physics.md 3.8): no seated offset."""
    return np.zeros(3)


def unperturbed(nominal: np.ndarray, shift: np.ndarray, row: np.ndarray) -> np.ndarray:
    """A joint without clearance has no play for an ensemble member's start to take."""
    return np.array(nominal, dtype=float)


def unworn(wmap: np.ndarray, j: int, n: tuple, jp: np.ndarray,
           p: np.ndarray) -> tuple[float, bool]:
    """A joint that does not wear: no depth, no coating worn through."""
    return 0.0, False


#: The registered joint types' host behaviour, by type name (``core.joints.JOINT_TYPES``;
#: tests/test_jointtypes.py fails for a registered type without an entry).
HOST_HOOKS: dict[str, TypeHooks] = {
    "spherical": TypeHooks(fill=socket_fill, law=socket_law,
                           stop=lambda row, p, bound: point_stop(row, p, bound, socket_law(p)),
                           sink=point_sink, seat=point_seat, perturb=point_perturb,
                           worn=socket_worn, rate=point_rate, turns_at_start=True),
    "revolute": TypeHooks(fill=bearing_fill, law=journal_law,
                          stop=lambda row, p, bound: point_stop(row, p, bound, journal_law(p)),
                          sink=point_sink, seat=point_seat, perturb=point_perturb,
                          worn=bearing_worn, rate=point_rate, spins=True),
    "prismatic": TypeHooks(fill=guide_fill, law=no_law, stop=guide_stop, sink=guide_sink,
                           seat=guide_seat, perturb=perturbed_block, worn=socket_worn,
                           rate=guide_rate),
    # a bushing has no gap: no contact law, no penetration to stop, nothing to wear
    "bushing": TypeHooks(fill=bushing_fill, law=no_law, stop=lambda row, p, bound: math.inf,
                         sink=no_sink, seat=unseated, perturb=unperturbed, worn=unworn,
                         rate=bushing_rate),
}


@dataclass
class Packed:
    """Kernel inputs of one case."""

    p: np.ndarray
    jp: np.ndarray
    y0: np.ndarray
    n_steps: int
    save_every: int
    map_shape: tuple[int, int]
    #: time integrator (solver.method)
    method: str = "rk4"


def joint_configs(cfg: Config) -> list[tuple[str, AnyJoint]]:
    """The config's joint sections in the joint table's order (``core.joints.JOINTS``, the
    order of the kernel's per-joint rows): ``[(name, its JointConfig), ...]``."""
    return [(joint.name, getattr(cfg.joints, joint.name)) for joint in JOINTS]


def joint_set(cfg: Config) -> int:
    """The case's joints with clearance and its bushings, as a ``core.jointset`` bitmask
    (bit j: row j of the joint table has clearance; bit N_JOINTS + j: it is a bushing): the
    flags :func:`pack` writes into ``jp[:, J_CLEARANCE]`` and ``jp[:, J_BUSHING]``, which
    ``jointset.of`` reads back; and ``jointset.SLIDER_CRANK`` for the slider-crank (its
    ``p[P_GUIDE]``); the kernel build that runs the case is
    :func:`kernel_build` of it."""
    mask = jointset.SLIDER_CRANK if cfg.mechanism.kind == "slider_crank" else 0
    for j, (_, joint) in enumerate(joint_configs(cfg)):
        if joint.clearance > 0.0:
            mask |= 1 << j
        if getattr(joint, "type", None) == BUSHING:
            mask |= 1 << (L.N_JOINTS + j)
    return mask


#: The joints on which the CPU's kernel builds are specialised (``core.jointset``: a build
#: per set of them, compiled and cached once each); a build always holds the others, tested
#: at run time. A cold cache's first build costs 70-85 CPU seconds (the functions the
#: builds share included), each later one 20-28: the mixed-clearance study's 16 sets
#: would compile 16 builds for a run of 40 s. Specialised on the spherical joints A and B,
#: four builds at most: against the tree before builds per joint set (c64b06a), side by
#: side, the ideal case runs 1.26x, one clearance 1.12x, two 1.03x (1.23x, 1.16x and 1.15x
#: since a ball's map bin comes from a hint, ``wear.map_bin_near``). Folding O and P away
#: together where both are ideal (eight builds) gave those three cases 1.30x, 1.14x and
#: 1.05x, but the default test run compiled seven more builds and took 603 s against 482 s,
#: past its budget (benchmarks/README.md, "Builds per joint set", "The CPU's grouping,
#: measured again", "O and P folded together").
SPECIALISED_JOINTS = jointset.named("A", "B")

#: The device's: every joint. Folding O and P away halves the CUDA kernel's spill stores
#: (``python -m clearsweep.ptx --joints``), and a device build is compiled in each process
#: that launches it, cached or not.
SPECIALISED_JOINTS_DEVICE = jointset.ALL


def build_of(case_set: int, device: bool = False) -> int:
    """The joint set of the kernel build that runs a case of joint set ``case_set``
    (``core.jointset.of`` of its packed flags) on the CPU, or with ``device`` on a CUDA
    device: the case's joints among :data:`SPECIALISED_JOINTS` (or
    :data:`SPECIALISED_JOINTS_DEVICE`), and every other joint; and the case's bushings
    (a build without bushings, every build before them, folds their code away); and the
    case's mechanism (``jointset.MECHANISMS``), the slider-crank's without P unless the
    case has P's clearance."""
    mask = SPECIALISED_JOINTS_DEVICE if device else SPECIALISED_JOINTS
    build = ((int(case_set) & mask) | (jointset.ALL & ~mask)
             | (int(case_set) & (jointset.BUSHINGS | jointset.MECHANISMS)))
    if build & jointset.SLIDER_CRANK and not int(case_set) & jointset.named("P"):
        # the slider-crank's guide ideal: its builds fold P away (the builds, and results,
        # of every slider-crank case before P's clearance in it)
        build &= ~jointset.named("P")
    return build


def kernel_build(cfg: Config) -> int:
    """The joint set of the kernel build that runs the case (:func:`build_of` its
    :func:`joint_set`): one compile, cached on disk, per set and method."""
    return build_of(joint_set(cfg))



#: The per-joint attributes of a run's results (:func:`joint_attributes`): the suffix of
#: ``joint_<J>_<suffix>`` and what it holds (docs/runs.md, "Joint attributes").
JOINT_ATTRIBUTES = {
    "type": "the joint's type (spherical, revolute, prismatic)",
    "contact": "'ideal' (no clearance, no contact law) or the elastic law its contact takes",
    "clearance_m": "the packed clearance jp[J_C] [m] (P: the smaller of its two)",
    "coating": "the socket's (bearing's, guide's) coating, 'none' if uncoated",
    "surface_material": "the material of the socket's surface (the coating where coated)",
    "base_material": "the socket's base and the ball's material",
    "modulus_Pa": "the modulus of the contact law, jp[J_EW] [Pa] (NaN: ideal)",
    "friction_coefficient": "jp[J_MU] (NaN: ideal)",
    "wear_coefficient_m2_per_N": "Archard's k, jp[J_K] [m^2/N] (NaN: ideal)",
    "bushing_radial_stiffness_N_per_m": "a bushing's stiffness across its axis [N/m] (NaN: not a bushing)",
    "bushing_axial_stiffness_N_per_m": "a bushing's stiffness along its axis [N/m] (NaN: not a bushing)",
    "bushing_radial_damping_N_s_per_m": "a bushing's damping across its axis [N s/m] (NaN: not a bushing)",
    "bushing_axial_damping_N_s_per_m": "a bushing's damping along its axis [N s/m] (NaN: not a bushing)",
}


def joint_attributes(cfg: Config, packed: Packed) -> dict[str, Any]:
    """Each joint's type, materials and the contact values the kernel ran with, read from the
    packed ``jp`` rows: ``joint_<J>_<suffix>`` for every suffix of :data:`JOINT_ATTRIBUTES`.
    An ideal joint's ``contact`` is ``"ideal"`` and its contact values NaN: no contact law
    applies there."""
    exponent = float(packed.p[L.P_EXPONENT])
    out: dict[str, Any] = {}
    for j, (name, joint) in enumerate(joint_configs(cfg)):
        row, kind = packed.jp[j], table_type(j, packed.p)
        ideal = row[L.J_CLEARANCE] == 0.0
        elastic = row[L.J_BUSHING] != 0.0
        law = "Hertz power law, E*" if power_law_joint(kind, exponent) else \
            f"layered law, E_w ({cfg.contact.layer_rule})"
        own = joint_kind(kind).contact_law
        if own is not None:
            law = own
        if elastic:
            kind, law = BUSHING, "linear spring-damper (bushing), no contact"
        values = {
            "type": kind,
            "contact": "ideal" if ideal else law,
            "clearance_m": float(row[L.J_C]),
            "coating": joint.coating,
            "surface_material": BASE_MATERIAL if joint.coating == "none" else joint.coating,
            "base_material": BASE_MATERIAL,
            "modulus_Pa": math.nan if ideal else float(row[L.J_EW]),
            "friction_coefficient": math.nan if ideal else float(row[L.J_MU]),
            "wear_coefficient_m2_per_N": math.nan if ideal else float(row[L.J_K]),
            "bushing_radial_stiffness_N_per_m": float(row[L.J_K_RADIAL]) if elastic else math.nan,
            "bushing_axial_stiffness_N_per_m": float(row[L.J_K_AXIAL]) if elastic else math.nan,
            "bushing_radial_damping_N_s_per_m": float(row[L.J_C_RADIAL]) if elastic else math.nan,
            "bushing_axial_damping_N_s_per_m": float(row[L.J_C_AXIAL]) if elastic else math.nan,
        }
        out.update({f"joint_{name}_{key}": value for key, value in values.items()})
    return out


def bushing_row(row: np.ndarray, joint: Any, kind: str, preset: Preset) -> None:
    """A bushing's columns of its jp row (core/bushing.py) at a joint of the table's type
    ``kind``: its own (:func:`bushing_fill`), the axial pair 0 where that type's axial
    motion is ideal (a revolute's place, O). The slider-crank's A and B are pins whose
    axial motion (across the plane) the kernel holds: their bushing is radial in the plane
    whatever its socket body's x axis (the rod's, at A, lies in the plane), so the axial
    pair repeats the radial one."""
    HOST_HOOKS[BUSHING].fill(row, joint, preset)
    if joint_kind(kind).axial_ideal:
        row[L.J_K_AXIAL] = 0.0
        row[L.J_C_AXIAL] = 0.0
    elif preset.kind == "slider_crank":
        row[L.J_K_AXIAL] = row[L.J_K_RADIAL]
        row[L.J_C_AXIAL] = row[L.J_C_RADIAL]


def pack(cfg: Config, materials: dict, wmap: np.ndarray | None = None, *,
         seat: bool = True) -> Packed:
    """Resolved config (config.load_config) + materials -> kernel vectors (SI).

    ``wmap`` (float64[2, npolar, nazim], [m]): a worn socket to start from; the seated
    start then rests each ball on the worn wall. ``seat=False``: for the checks that plan
    a run (:func:`clearsweep.simulation.preflight`), which compile nothing: the seated
    start (``initial.joints: seated``) calls the kernel's compiled functions, so it is
    left to the run, and ``y0`` is then the centred start, not one to run."""
    preset = PRESETS[cfg.mechanism.preset]
    solver = cfg.solver
    p = np.zeros(L.N_P)
    p[L.P_L2] = preset.crank_length_m
    p[L.P_L3] = preset.rod_length_m
    p[L.P_ZS] = preset.slider_height_m
    p[L.P_M2] = preset.crank_mass_kg
    p[L.P_M3] = preset.rod_mass_kg
    p[L.P_M4] = preset.slider_mass_kg
    p[L.P_J2:L.P_J2 + 3] = preset.crank_inertia_kgm2
    p[L.P_J3:L.P_J3 + 3] = preset.rod_inertia_kgm2
    p[L.P_J4:L.P_J4 + 3] = preset.slider_inertia_kgm2
    p[L.P_G:L.P_G + 3] = cfg.mechanism.gravity
    omega = cfg.mechanism.omega_rad_s
    p[L.P_OMEGA] = omega
    p[L.P_THETA0] = cfg.mechanism.theta0
    p[L.P_BAUM_A], p[L.P_BAUM_B] = solver.baumgarte
    contact = cfg.contact
    p[L.P_CR] = contact.restitution
    p[L.P_DV0_MIN] = contact.min_impact_velocity
    fraction = contact.max_penetration_fraction
    p[L.P_PEN_FRAC] = 0.0 if fraction is None else fraction
    p[L.P_HYST_NUM], p[L.P_HYST_DEN] = as_python(hysteresis_fraction)(DAMPING_LAWS.index(contact.damping),
                                                           contact.restitution)
    p[L.P_ONSET] = 1.0 if contact.impact_velocity == "onset" else 0.0
    p[L.P_EXPONENT] = contact.hertz_exponent if contact.elastic == "hertz" else 0.0
    p[L.P_SECTION_PHASE] = math.radians(cfg.outputs.poincare_phase_deg)
    p[L.P_GUIDE] = float(preset.guide_axis)
    friction = cfg.friction
    p[L.P_FRICTION] = 1.0 if friction.enabled else 0.0
    p[L.P_V0] = friction.v0
    p[L.P_V1] = friction.v1
    wear = cfg.wear
    p[L.P_WEAR] = 1.0 if wear.enabled else 0.0
    p[L.P_SLIP] = 0.0 if wear.slip == "sliding" else 1.0
    p[L.P_AMPL] = wear.amplification
    p[L.P_CONS_TOL] = solver.constraint_tolerance
    p[L.P_ENERGY_TOL] = solver.energy_tolerance
    p[L.P_STAB] = solver.stability_limit
    p[L.P_DT] = solver.dt
    p[L.P_MAX_LEVEL] = solver.max_substep_level
    p[L.P_SETTLE] = cfg.metrics.settle_time
    p[L.P_FEEDBACK] = 1.0 if wear.feeds_back else 0.0
    p[L.P_RTOL] = solver.rtol
    p[L.P_ATOL_Q] = solver.atol_position
    p[L.P_ATOL_V] = solver.atol_velocity
    p[L.P_ATOL_E] = solver.atol_energy
    # not tied to save_every: the steps, and so every statistic, do not depend on the output
    p[L.P_HMAX] = 10.0 * solver.dt if solver.max_step is None else solver.max_step
    p[L.P_ONSET_TOL] = solver.onset_tolerance
    p[L.P_INTERP] = 1.0 if wear.interpolate else 0.0
    jp = np.zeros((L.N_JOINTS, L.N_JP))
    clear = joint_set(cfg)
    for j, (_, joint) in enumerate(joint_configs(cfg)):
        surface = surface_material(joint, materials)
        c = joint.clearance
        jp[j, L.J_CLEARANCE] = 1.0 if clear >> j & 1 else 0.0
        jp[j, L.J_C] = c
        jp[j, L.J_RI] = joint.socket_radius
        jp[j, L.J_RJ] = joint.socket_radius - c
        kind = table_type(j, p)
        jp[j, L.J_EW] = contact_modulus(joint, kind, materials, contact.layer_rule, p[L.P_EXPONENT])
        jp[j, L.J_MU] = surface.friction_coefficient
        k = joint.wear_coefficient
        jp[j, L.J_K] = surface.wear_coefficient_m2_per_N if k is None else k
        # where the coating is worn through: the uncoated pair (docs/service_life.md)
        coated = joint.coating != "none"
        base = materials[BASE_MATERIAL]
        jp[j, L.J_EW_BASE] = (contact_modulus(replace(joint, coating="none"), kind, materials,
                                              contact.layer_rule, p[L.P_EXPONENT])
                              if coated else jp[j, L.J_EW])
        jp[j, L.J_MU_BASE] = base.friction_coefficient if coated else jp[j, L.J_MU]
        jp[j, L.J_K_BASE] = base.wear_coefficient_m2_per_N if coated else jp[j, L.J_K]
        jp[j, L.J_COAT] = joint.coating_thickness if coated else math.inf
        HOST_HOOKS[kind].fill(jp[j], joint, preset)
        if clear >> (L.N_JOINTS + j) & 1:
            # the joint table's type: the slider-crank's pin bushings keep their axial pair
            bushing_row(jp[j], joint, JOINTS[j].type, preset)
        if c > 0.0:
            jp[j, L.J_PEN_STOP] = penetration_stop(jp[j], kind, p, contact.max_penetration_fraction,
                                                   contact.load_bound)
    perturb = cfg.ensemble.perturb
    member = member_perturbation(cfg.ensemble) if perturb.any else None
    if member is not None:      # unperturbed: the nominal case, bit for bit
        jp[:, L.J_K] *= member.wear_factor
        p[L.P_THETA0] += member.crank_phase_rad
    # whole output samples, rounded up: the run covers at least `duration`
    save_every = solver.save_every
    n_raw = int(math.ceil(solver.duration / solver.dt - 1e-9))
    n_steps = max(1, -(-n_raw // save_every)) * save_every
    theta0 = float(p[L.P_THETA0])
    if cfg.initial.joints == "seated" and seat:
        offsets = seated_offsets(preset, p, jp, theta0, omega, wmap)
    else:
        offsets = np.zeros((L.N_JOINTS, 3))
    if member is not None and perturb.ball_offset > 0.0:
        for j, row in enumerate(JOINTS):
            shift = member.ball_offset[j].copy()
            kind = table_type(j, p)
            if joint_kind(kind).axial_ideal or preset.kind == "slider_crank":
                shift[0] = 0.0      # the journal moves in the bearing's plane only, the block
                                    # across its guide, the slider-crank's pins in its plane
            if preset.kind == "slider_crank":
                # across its plane: the guide's block moves up (z) only, its side held
                shift[joint_kind(kind).off_plane_axis] = 0.0
            offsets[j] = HOST_HOOKS[kind].perturb(offsets[j], shift, jp[j])
    by_name = {row.name: offsets[j] for j, row in enumerate(JOINTS)}
    y0 = initial_state(preset, theta0, omega, by_name["A"], by_name["B"], by_name["O"],
                       by_name["P"])
    return Packed(p=p, jp=jp, y0=y0, n_steps=n_steps, save_every=save_every,
                  map_shape=(wear.map[0], wear.map[1]), method=solver.method)
