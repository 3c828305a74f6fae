"""Configuration: schema, defaults, validation, ``--set`` overrides.

The resolved configuration is the contract between modules
(docs/architecture.md): a frozen :class:`Config` of typed sections, every leaf
present, numbers normalised (``float`` or ``int`` as the schema says, vectors
as tuples), each leaf's units and long name in its dataclass metadata. It is
validated once, here, before any computation, and passed down as it is; a wrong
value raises :class:`ConfigError` with a message of the form::

    <file>: <dotted.key>: got <value>; expected <what is allowed>[; did you mean '<match>'?]

YAML reading, errors and :class:`Field` live in :mod:`clearsweep.schema`.
"""

from __future__ import annotations

import copy
import math
import operator
import os
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import MISSING, dataclass, field, fields
from typing import Any, ClassVar

from .choices import DAMPING_LAWS, MAX_BLOCKS, MAX_MEMBERS, MAX_SNAPSHOTS
from .schema import (  # noqa: F401
    MAX_YAML_ALIASES,
    MAX_YAML_BYTES,
    MAX_YAML_DEPTH,
    MAX_YAML_VALUES,
    ConfigError,
    Field,
    close_match,
    dump_yaml,
    oversized_number,
    oversized_text,
    parse_yaml,
    read_yaml,
    short_repr,
)

__all__ = [
    "ConfigError", "Field", "Config", "JointConfig", "RevoluteJointConfig", "PrismaticJointConfig",
    "section_clearance", "EnsembleConfig", "PerturbConfig",
    "ReliabilityConfig", "SCHEMA",
    "DEFAULTS", "load_config",
    "apply_override", "dump_config",
    "get_path", "set_path", "set_setting", "ALTERNATIVES", "alternative_of",
    "resolve_materials", "read_yaml", "parse_yaml", "close_match",
    "field_info", "FIELD_INFO", "SWEEP_FILE_KEYS", "file_kind",
]


def _setting(spec: Field, units: str | None, long_name: str) -> Any:
    """A dataclass field: its rule (:class:`Field`), default, units (UDUNITS) and long name."""
    default = tuple(spec.default) if isinstance(spec.default, list) else spec.default
    return field(default=default, metadata={"field": spec, "units": units, "long_name": long_name})


def _section(cls: type) -> Any:
    return field(default_factory=cls)


def _positive(default: float) -> Field:
    return Field(default, lo=0.0, lo_open=True)


class _Section:
    """Shared behaviour of the frozen configuration sections."""

    #: (seconds key, revolutions key) of the section's alternative pairs (:data:`ALTERNATIVES`)
    _alternatives: ClassVar[tuple[tuple[str, str], ...]] = ()

    def to_dict(self) -> dict[str, Any]:
        """Plain nested dict (lists for vectors): YAML, JSON and hashing use it. A length
        asked in revolutions leaves its seconds key null (what was asked: ``load_config``
        of the dict resolves it again, at the speed the dict then holds)."""
        out: dict[str, Any] = {}
        for f in fields(self):  # type: ignore[arg-type]
            value = getattr(self, f.name)
            out[f.name] = (value.to_dict() if isinstance(value, _Section)
                           else list(value) if isinstance(value, tuple) else value)
        for seconds, revolutions in self._alternatives:
            if out[revolutions] is not None:
                out[seconds] = None
        return out

    def get(self, key: str) -> Any:
        """Value at dotted ``key`` (``"joints.B.clearance"``); see :func:`get_path`."""
        return get_path(self, key)


#: A rubber bushing's default stiffness [N/m] (radial, axial): a suspension control arm's
#: bushing is about 1e6 N/m across its axis (0.8-1.5 kN/mm), the default of common linear
#: bushing elements (1e6 N/m); along its axis, where the rubber works in shear, about half
#: (docs/physics.md 3.8).
BUSHING_STIFFNESS = (1.0e6, 5.0e5)
#: Its default damping [N s/m] (radial, axial): a damping ratio of about 0.2 on the rod's
#: mass, within the 1e2-1e3 N s/m of a rubber bushing's viscous part.
BUSHING_DAMPING = (300.0, 150.0)


def _bushing_stiffness(joint: str) -> Any:
    return _setting(Field(list(BUSHING_STIFFNESS), size=2, lo=0.0, lo_open=True, hi=1.0e12),
                    "N m-1", f"bushing stiffness of joint {joint} (radial, axial)")


def _bushing_damping(joint: str) -> Any:
    return _setting(Field(list(BUSHING_DAMPING), size=2, lo=0.0, hi=1.0e9), "N s m-1",
                    f"bushing damping of joint {joint} (radial, axial)")


@dataclass(frozen=True)
class JointConfig(_Section):
    """One spherical joint; ``clearance == 0`` makes it ideal."""

    clearance: float = _setting(Field(0.0, lo=0.0), "m", "radial clearance of joint X")
    socket_radius: float = _setting(_positive(0.015), "m", "socket radius of joint X")
    coating: str = _setting(Field("none", str), None, "socket coating of joint X")
    coating_thickness: float = _setting(_positive(1.0e-4), "m", "coating thickness of joint X")
    base_thickness: float = _setting(_positive(4.9e-3), "m", "socket base thickness of joint X")
    #: None: the surface material's own coefficient
    wear_coefficient: float | None = _setting(Field(None, lo=0.0, nullable=True), "m2 N-1",
                                              "Archard wear coefficient of joint X's socket")
    #: bushing: an elastic bushing (core/bushing.py) in place of the joint: no clearance, no
    #: coating, its stiffness and damping below. The joint itself is the mechanism's: the
    #: RSSP's spherical, the slider-crank's revolute pin (validation resolves the default
    #: to the mechanism's, and refuses the other mechanism's type)
    type: str = _setting(Field("spherical", ("spherical", "revolute", "bushing")), None,
                         "joint type of joint X")
    bushing_stiffness: tuple[float, float] = _bushing_stiffness("X")
    bushing_damping: tuple[float, float] = _bushing_damping("X")
    #: the slider-crank's pins (A, B: revolute, docs/mechanisms.md): the bearing's length,
    #: over which its wear strip spreads; null: the preset's (``params.Preset.pin_length_m``).
    #: The RSSP's balls have none: refused there
    length: float | None = _setting(Field(None, lo=0.0, lo_open=True, nullable=True), "m",
                                    "bearing length of joint X (slider-crank)")

    @property
    def ball_radius_m(self) -> float:
        """R_j = socket_radius - clearance [m]."""
        return self.socket_radius - self.clearance

    def clearance_overrides(self, joint: str, clearance: float) -> dict[str, float]:
        """The overrides (``Config.replace`` keywords) that give joint ``joint`` the
        clearance ``clearance`` [m] (a reliability member's draw)."""
        return {f"joints__{joint}__clearance": clearance}

    # the joint type's checks of its section (a raw mapping), called by validation for the
    # joint ``joint`` in the table's order: its sizes, its fit, its reliability band

    @staticmethod
    def check_sizes(joint: str, spec: Mapping[str, Any], cfg: Mapping[str, Any],
                    source: str) -> None:
        """A socket's sizes: the common bounds only."""

    @staticmethod
    def check_fit(joint: str, spec: Mapping[str, Any], cfg: Mapping[str, Any],
                  source: str) -> None:
        """The ball's radius within the socket (:func:`_check_ball_fit`)."""
        _check_ball_fit(joint, spec, "ball", source)

    @staticmethod
    def check_band(joint: str, spec: Mapping[str, Any], tolerance: float, source: str) -> None:
        """The reliability band of its clearance (:func:`_check_point_band`)."""
        _check_point_band(joint, spec, tolerance, source)


@dataclass(frozen=True)
class RevoluteJointConfig(_Section):
    """The crank's revolute joint O: a journal in a bearing; ``clearance == 0`` (the default)
    makes it ideal. Radial clearance only: axial play and tilt stay ideal."""

    clearance: float = _setting(Field(0.0, lo=0.0), "m", "radial clearance of joint O")
    bearing_radius: float = _setting(_positive(0.01), "m", "bearing radius of joint O")
    length: float = _setting(_positive(0.02), "m", "bearing length of joint O")
    coating: str = _setting(Field("none", str), None, "bearing coating of joint O")
    coating_thickness: float = _setting(_positive(1.0e-4), "m", "coating thickness of joint O")
    base_thickness: float = _setting(_positive(4.9e-3), "m", "bearing base thickness of joint O")
    #: None: the surface material's own coefficient
    wear_coefficient: float | None = _setting(Field(None, lo=0.0, nullable=True), "m2 N-1",
                                              "Archard wear coefficient of joint O's bearing")
    #: the oil's dynamic viscosity in the bearing's film (Petroff's viscous shear, docs/physics.md
    #: 3.6); 0 (the default): the paper's dry contact. An ISO VG 68 oil (68 mm2/s at 40 C,
    #: ISO 3448, at 880 kg/m3) is 0.06 Pa s
    lubricant_viscosity: float = _setting(Field(0.0, lo=0.0, hi=10.0), "Pa s",
                                          "lubricant viscosity in joint O's bearing")
    #: bushing: an elastic bushing (core/bushing.py) in place of the revolute: radial only
    #: (its axial value unused: O's axial motion stays ideal)
    type: str = _setting(Field("revolute", ("revolute", "bushing")), None, "joint type of joint O")
    bushing_stiffness: tuple[float, float] = _bushing_stiffness("O")
    bushing_damping: tuple[float, float] = _bushing_damping("O")

    @property
    def socket_radius(self) -> float:
        """The outer surface's radius R_i [m]: the bearing's."""
        return self.bearing_radius

    @property
    def ball_radius_m(self) -> float:
        """Journal radius R_j = bearing_radius - clearance [m]."""
        return self.bearing_radius - self.clearance

    def clearance_overrides(self, joint: str, clearance: float) -> dict[str, float]:
        """The overrides that give the bearing the clearance ``clearance`` [m]."""
        return {f"joints__{joint}__clearance": clearance}

    @staticmethod
    def check_sizes(joint: str, spec: Mapping[str, Any], cfg: Mapping[str, Any],
                    source: str) -> None:
        """The bearing's radius and coating (:func:`_check_bearing`)."""
        _check_bearing(joint, spec, cfg, source)

    @staticmethod
    def check_fit(joint: str, spec: Mapping[str, Any], cfg: Mapping[str, Any],
                  source: str) -> None:
        """The journal's radius within the bearing (:func:`_check_ball_fit`)."""
        _check_ball_fit(joint, spec, "journal", source)

    @staticmethod
    def check_band(joint: str, spec: Mapping[str, Any], tolerance: float, source: str) -> None:
        """The reliability band of its clearance (:func:`_check_point_band`)."""
        _check_point_band(joint, spec, tolerance, source)


@dataclass(frozen=True)
class PrismaticJointConfig(_Section):
    """The slider's guide P: a block in a guide; both clearances 0 (the default) make it
    ideal. The block moves across the guide (y, z) and tilts within its clearances, and
    touches the walls at its corners. In the planar slider-crank (its guide along y) the
    block moves in the plane only: ``clearance_z`` above and below it, in the plane;
    ``clearance_y`` its sides' gap across the plane (x), which it never closes."""

    clearance_y: float = _setting(Field(0.0, lo=0.0), "m",
                                  "clearance of joint P between the block's sides and the guide")
    clearance_z: float = _setting(Field(0.0, lo=0.0), "m",
                                  "clearance of joint P above and below the block")
    block: tuple[float, float, float] = _setting(Field([0.08, 0.06, 0.06], size=3, lo=0.0, lo_open=True),
                                                 "m", "block length, width and height of joint P")
    corner_radius: float = _setting(_positive(1.0e-3), "m", "edge radius of joint P's block corners")
    coating: str = _setting(Field("none", str), None, "guide wall coating of joint P")
    coating_thickness: float = _setting(_positive(1.0e-4), "m", "coating thickness of joint P")
    base_thickness: float = _setting(_positive(4.9e-3), "m", "guide wall base thickness of joint P")
    #: None: the surface material's own coefficient
    wear_coefficient: float | None = _setting(Field(None, lo=0.0, nullable=True), "m2 N-1",
                                              "Archard wear coefficient of joint P's guide walls")

    @property
    def clearance(self) -> float:
        """The smaller of the two clearances [m]: 0 for an ideal guide."""
        return min(self.clearance_y, self.clearance_z)

    @property
    def socket_radius(self) -> float:
        """The corners' edge radius [m] (the contact law's radius)."""
        return self.corner_radius

    def clearance_overrides(self, joint: str, clearance: float) -> dict[str, float]:
        """The overrides that give the guide the clearance ``clearance`` [m], its smaller:
        both move by the same shift."""
        shift = clearance - self.clearance
        return {f"joints__{joint}__clearance_y": self.clearance_y + shift,
                f"joints__{joint}__clearance_z": self.clearance_z + shift}

    @staticmethod
    def check_sizes(joint: str, spec: Mapping[str, Any], cfg: Mapping[str, Any],
                    source: str) -> None:
        """The block (:func:`_check_block`), then the guide's clearances, corners and wall
        maps (:func:`_check_guide`)."""
        _check_block(joint, spec, cfg, source)
        _check_guide(spec, cfg["wear"]["map"], source, joint)

    @staticmethod
    def check_fit(joint: str, spec: Mapping[str, Any], cfg: Mapping[str, Any],
                  source: str) -> None:
        """Nothing beyond its sizes: a block has no ball to fit."""

    @staticmethod
    def check_band(joint: str, spec: Mapping[str, Any], tolerance: float, source: str) -> None:
        """The reliability band of its smaller clearance (:func:`_check_guide_band`)."""
        _check_guide_band(joint, spec, tolerance, source)


def section_clearance(spec: Mapping[str, Any]) -> float:
    """A joint section's clearance [m] as a mapping gives it: ``clearance``, or a guide's
    smaller of ``clearance_y`` and ``clearance_z``."""
    if "clearance" in spec:
        return float(spec["clearance"])
    return float(min(spec["clearance_y"], spec["clearance_z"]))


#: The key of each joint section's outer radius (socket or bearing).
RADIUS_KEYS = ("socket_radius", "bearing_radius")


def radius_key(spec: Mapping[str, Any]) -> str:
    """The key of a joint section's outer radius R_i: ``socket_radius`` or ``bearing_radius``."""
    return next(k for k in RADIUS_KEYS if k in spec)


@dataclass(frozen=True)
class JointsConfig(_Section):
    A: JointConfig = _section(JointConfig)
    B: JointConfig = _section(JointConfig)
    O: RevoluteJointConfig = _section(RevoluteJointConfig)
    P: PrismaticJointConfig = _section(PrismaticJointConfig)

    def items(self) -> tuple[tuple[str, "JointConfig | RevoluteJointConfig | PrismaticJointConfig"], ...]:
        """``(("A", joint A), ("B", joint B), ("O", joint O), ("P", joint P))``, in kernel
        order."""
        return (("A", self.A), ("B", self.B), ("O", self.O), ("P", self.P))


#: The mechanisms (``mechanism.kind``) and each one's presets, the first its default's
#: example; ``clearsweep.params.PRESETS`` holds the presets' data (tests/test_config.py
#: checks they agree).
MECHANISM_KINDS = {"rssp": ("realistic", "paper"), "slider_crank": ("flores_benchmark",)}
#: The mechanism of each preset.
PRESET_KINDS = {preset: kind for kind, presets in MECHANISM_KINDS.items() for preset in presets}


@dataclass(frozen=True)
class MechanismConfig(_Section):
    #: rssp: the spatial RSSP four-bar; slider_crank: the planar slider-crank
    #: (docs/mechanisms.md), whose data come from a slider-crank preset (flores_benchmark)
    kind: str = _setting(Field("rssp", tuple(MECHANISM_KINDS)), None, "mechanism")
    preset: str = _setting(Field("realistic", tuple(PRESET_KINDS)), None, "mechanism data preset")
    speed_rpm: float = _setting(_positive(60.0), "min-1", "crank speed in revolutions per minute")
    gravity: tuple[float, float, float] = _setting(Field([0.0, 0.0, -9.81], size=3), "m s-2",
                                                   "gravity vector")
    theta0: float = _setting(Field(0.0), "rad", "initial crank angle")

    @property
    def omega_rad_s(self) -> float:
        """Crank angular speed [rad/s]."""
        return self.speed_rpm * 2.0 * math.pi / 60.0


@dataclass(frozen=True)
class InitialConfig(_Section):
    #: seated: each clearance joint starts with its ball resting on the socket wall, along the
    #: ideal joint's reaction at t = 0; centred: ball in the socket centre
    joints: str = _setting(Field("seated", ("seated", "centred")), None,
                           "initial ball position in the clearance joints")


@dataclass(frozen=True)
class ContactConfig(_Section):
    restitution: float = _setting(Field(0.7, lo=0.0, lo_open=True, hi=1.0), "1",
                                  "coefficient of restitution")
    min_impact_velocity: float = _setting(_positive(1.0e-2), "m s-1", "floor of the impact velocity")
    layer_rule: str = _setting(Field("series", ("series", "paper_mm")), None,
                               "double elastic layer rule")
    #: null (the default): the physical stop, the depth at which the joint's own law carries
    #: load_bound (docs/physics.md 4.3); a number: the earlier
    #: stop, that fraction of the clearance
    max_penetration_fraction: float | None = _setting(
        Field(None, lo=0.0, lo_open=True, nullable=True), "1",
        "largest penetration accepted, fraction of the clearance (null: the physical stop)")
    #: the contact force beyond which the elastic law is not trusted: the penetration stop
    #: is the law's depth at it (docs/physics.md 4.3)
    load_bound: float = _setting(_positive(1.0e5), "N",
                                 "contact force at the penetration stop")
    #: hysteresis damping law (docs/physics.md section 3.2): the paper's or one of the literature's
    damping: str = _setting(Field("paper", DAMPING_LAWS), None, "contact damping law")
    #: max: the fastest approach of the contact episode; onset: its value at the episode's first step
    impact_velocity: str = _setting(Field("max", ("max", "onset")), None,
                                    "impact velocity of the damping law")
    #: paper: the coated law of Table 1; hertz: F = K delta^n with n = hertz_exponent
    elastic: str = _setting(Field("paper", ("paper", "hertz")), None, "elastic contact law")
    hertz_exponent: float = _setting(Field(1.5, lo=1.0, hi=3.0), "1",
                                     "exponent n of the power contact law (contact.elastic: hertz)")


@dataclass(frozen=True)
class FrictionConfig(_Section):
    enabled: bool = _setting(Field(True, bool), None, "friction on")
    v0: float = _setting(_positive(1.0e-4), "m s-1", "friction ramp start velocity")
    v1: float = _setting(_positive(1.0e-3), "m s-1", "friction ramp end velocity")


@dataclass(frozen=True)
class WearConfig(_Section):
    enabled: bool = _setting(Field(True, bool), None, "wear on")
    slip: str = _setting(Field("sliding", ("sliding", "paper")), None, "wear slip rule")
    map: tuple[int, int] = _setting(Field([144, 288], int, lo=1, size=2), "1",
                                    "wear map bins (polar, azimuth)")
    amplification: float = _setting(Field(1.0, lo=0.0), "1", "wear amplification")
    feedback: bool = _setting(Field(True, bool), None, "wear enlarges the clearance")
    #: false: c_eff reads the bin holding the contact direction; true: bilinear between bin
    #: centres (a worn socket without steps between bins; life runs, docs/service_life.md)
    interpolate: bool = _setting(Field(False, bool), None, "wear map read bilinearly")

    @property
    def feeds_back(self) -> bool:
        """Worn depth enlarges the clearance the contact sees (wear on and feedback on)."""
        return self.enabled and self.feedback


@dataclass(frozen=True)
class MetricsConfig(_Section):
    _alternatives = (("settle_time", "settle_revolutions"),)

    #: resolved: settle_revolutions * 60 / speed_rpm where settle_revolutions is given
    settle_time: float = _setting(Field(0.05, lo=0.0), "s", "start of the settled window")
    #: the alternative to settle_time (give one of them); null: not given
    settle_revolutions: float | None = _setting(
        Field(None, lo=0.0, nullable=True), "1",
        "crank revolutions before the settled window (alternative to settle_time)")
    #: twin runs from the settled window's start, renormalised once a revolution, for the
    #: largest Lyapunov exponent (docs/physics.md section 11.5); 0: not computed (each
    #: revolution costs two more revolutions of the kernel)
    lyapunov_revolutions: int = _setting(
        Field(0, int, lo=0), "1",
        "crank revolutions of the largest Lyapunov exponent's twin runs (0: none)")


@dataclass(frozen=True)
class OutputsConfig(_Section):
    #: the crank angle of each revolution's Poincare section (docs/physics.md 8.4)
    poincare_phase_deg: float = _setting(Field(0.0, lo=0.0, hi=360.0, hi_open=True), "degree",
                                         "crank angle of the Poincare sections")


@dataclass(frozen=True)
class SolverConfig(_Section):
    _alternatives = (("duration", "revolutions"),)

    dt: float = _setting(_positive(1.0e-5), "s", "output-grid time step")
    #: resolved: revolutions * 60 / speed_rpm where revolutions is given
    duration: float = _setting(_positive(1.0), "s", "simulated duration")
    #: the alternative to duration (give one of them); null: not given
    revolutions: float | None = _setting(Field(None, lo=0.0, lo_open=True, nullable=True), "1",
                                         "simulated crank revolutions (alternative to duration)")
    save_every: int = _setting(Field(10, int, lo=1), "1", "steps per output sample")
    baumgarte: tuple[float, float] = _setting(Field([5.0, 5.0], lo=0.0, size=2), "s-1",
                                              "Baumgarte coefficients (alpha, beta)")
    max_substep_level: int = _setting(Field(8, int, lo=0, hi=16), "1", "deepest sub-step level")
    stability_limit: float = _setting(Field(1.0, lo=0.0, lo_open=True, hi=2.8, hi_open=True), "1",
                                      "largest stiff rate times step")
    constraint_tolerance: float = _setting(_positive(1.0e-6), "m", "constraint violation stop")
    energy_tolerance: float = _setting(_positive(1.0e-3), "1",
                                       "energy residual stop, fraction of the throughput")
    #: rk4: fixed steps of dt with 2^k sub-steps (the reference); dopri5: adaptive
    #: Dormand-Prince 5(4) with error control (docs/physics.md section 4.4)
    method: str = _setting(Field("rk4", ("rk4", "dopri5")), None, "time integrator")
    rtol: float = _setting(Field(1.0e-6, lo=0.0, lo_open=True, hi=1.0), "1",
                           "relative tolerance (dopri5)")
    atol_position: float = _setting(_positive(1.0e-9), "m",
                                    "absolute tolerance of positions and angles (dopri5; rad for angles)")
    atol_velocity: float = _setting(_positive(1.0e-6), "m s-1",
                                    "absolute tolerance of velocities (dopri5; rad/s for angles)")
    atol_energy: float = _setting(_positive(1.0e-6), "J",
                                  "absolute tolerance of drive work and dissipated energy (dopri5)")
    max_step: float | None = _setting(Field(None, lo=0.0, lo_open=True, nullable=True), "s",
                                      "longest step (dopri5); null: 10 * dt")
    onset_tolerance: float = _setting(_positive(1.0e-6), "s",
                                      "longest step over which a contact begins (dopri5)")


def _fraction(default: float) -> Field:
    return Field(default, lo=0.0, lo_open=True, hi=1.0)


def _limit() -> Field:
    return Field(None, lo=0.0, lo_open=True, nullable=True)


@dataclass(frozen=True)
class LifeConfig(_Section):
    """Service life by cycle jumps (``clearsweep life``, docs/service_life.md); ignored by
    ``run`` and ``sweep``. A limit left null is not checked."""

    cycles: float = _setting(_positive(1.0e6), "1", "crank revolutions to reach")
    block_revolutions: int = _setting(Field(1, int, lo=1), "1",
                                      "crank revolutions simulated in each dynamic block")
    jump_clearance_fraction: float = _setting(
        _fraction(0.01), "1", "largest depth growth of a wear-map bin per jump, fraction of the clearance")
    jump_coating_fraction: float = _setting(
        _fraction(0.25), "1", "largest depth growth of a bin per jump, fraction of its remaining coating")
    max_clearance_growth: float | None = _setting(_limit(), "m",
                                                  "clearance growth limit (largest wear depth)")
    max_normal_force: float | None = _setting(_limit(), "N", "settled peak normal force limit")
    max_rms_acceleration: float | None = _setting(_limit(), "m s-2",
                                                  "settled RMS slider acceleration limit")
    #: the largest settled ``|s - s_ideal(theta)|`` of a block, s the slider along its guide
    #: (docs/physics.md section 1, docs/mechanisms.md)
    max_motion_error: float | None = _setting(_limit(), "m", "slider motion error limit")
    stop_at_wear_through: bool = _setting(Field(False, bool), None,
                                          "stop when a coating is first worn through")
    snapshots: int = _setting(Field(12, int, lo=2, hi=MAX_SNAPSHOTS), "1", "wear-map snapshots kept")
    max_blocks: int = _setting(Field(200, int, lo=1, hi=MAX_BLOCKS), "1",
                                  "most dynamic blocks")


@dataclass(frozen=True)
class PerturbConfig(_Section):
    """Scatter of one ensemble member (docs/physics.md section 10); 0 = none."""

    #: radius of the uniform ball the offset is drawn from, fraction of each clearance
    ball_offset: float = _setting(Field(0.0, lo=0.0, hi=1.0), "1",
                                  "initial ball offset scatter, fraction of the clearance")
    #: theta0 + U(-x, x)
    crank_phase_deg: float = _setting(Field(0.0, lo=0.0, hi=180.0), "degree",
                                      "half-width of the uniform initial crank angle scatter")
    #: k * lognormal factor of mean 1 and this coefficient of variation, per joint
    wear_coefficient_cv: float = _setting(Field(0.0, lo=0.0, hi=10.0), "1",
                                          "coefficient of variation of the wear coefficient")

    @property
    def any(self) -> bool:
        """Whether any perturbation is switched on."""
        return self.ball_offset > 0.0 or self.crank_phase_deg > 0.0 or self.wear_coefficient_cv > 0.0


@dataclass(frozen=True)
class EnsembleConfig(_Section):
    """An ensemble: ``members`` cases that differ only by a perturbation drawn from
    (``seed``, ``member``); a sweep runs every member, a resolved case is one member."""

    members: int = _setting(Field(1, int, lo=1, hi=MAX_MEMBERS), "1", "ensemble members")
    seed: int = _setting(Field(0, int, lo=0), "1", "ensemble random seed")
    #: set by the sweep for each member; 0 .. members - 1
    member: int = _setting(Field(0, int, lo=0), "1", "ensemble member index")
    perturb: PerturbConfig = _section(PerturbConfig)


@dataclass(frozen=True)
class ReliabilityConfig(_Section):
    """Reliability over service life (``store: reliability``, docs/reliability.md): each of
    ``members`` life runs draws the inputs a manufacturer cannot pin down from (``seed``,
    ``member``) only; ignored by ``run``, ``life`` and other sweeps. 0 = no scatter."""

    members: int = _setting(Field(16, int, lo=2, hi=MAX_MEMBERS), "1", "reliability members per design")
    seed: int = _setting(Field(0, int, lo=0), "1", "reliability random seed")
    #: set by the sweep for each member; 0 .. members - 1
    member: int = _setting(Field(0, int, lo=0), "1", "reliability member index")
    #: uniform: c + U(-t, t); normal: c + t z / 3 with z cut at -+3 (the band is -+3 sigma)
    clearance_tolerance: float = _setting(Field(0.0, lo=0.0), "m",
                                          "half-width of the initial radial clearance tolerance band")
    clearance_distribution: str = _setting(Field("uniform", ("uniform", "normal")), None,
                                           "distribution of the initial radial clearance in its band")
    #: lognormal factor of mean 1 on the socket surface's k of each clearance joint (the
    #: coating's where coated; the base's after wear-through keeps its value)
    wear_coefficient_cv: float = _setting(Field(0.0, lo=0.0, hi=10.0), "1",
                                          "coefficient of variation of the wear coefficient")
    coating_thickness_cv: float = _setting(Field(0.0, lo=0.0, hi=1.0), "1",
                                           "coefficient of variation of the coating thickness")
    speed_cv: float = _setting(Field(0.0, lo=0.0, hi=1.0), "1",
                               "coefficient of variation of the crank speed")

    @property
    def any(self) -> bool:
        """Whether any input is scattered."""
        return (self.clearance_tolerance > 0.0 or self.wear_coefficient_cv > 0.0
                or self.coating_thickness_cv > 0.0 or self.speed_cv > 0.0)


@dataclass(frozen=True)
class Config(_Section):
    """A resolved case configuration: validated once by :func:`load_config`, then passed
    down as it is. Frozen: change a value with :func:`load_config` and an override, or
    :meth:`replace`, which validates again. SI units throughout except ``speed_rpm``
    (r/min); each leaf's units are in its dataclass metadata (:func:`field_info`)."""

    name: str = _setting(Field("case", str), None, "case name")
    #: absolute path once resolved
    materials_file: str | None = _setting(Field(None, str, nullable=True), None,
                                          "user materials file")
    mechanism: MechanismConfig = _section(MechanismConfig)
    initial: InitialConfig = _section(InitialConfig)
    joints: JointsConfig = _section(JointsConfig)
    contact: ContactConfig = _section(ContactConfig)
    friction: FrictionConfig = _section(FrictionConfig)
    wear: WearConfig = _section(WearConfig)
    metrics: MetricsConfig = _section(MetricsConfig)
    outputs: OutputsConfig = _section(OutputsConfig)
    solver: SolverConfig = _section(SolverConfig)
    life: LifeConfig = _section(LifeConfig)
    ensemble: EnsembleConfig = _section(EnsembleConfig)
    reliability: ReliabilityConfig = _section(ReliabilityConfig)

    def replace(self, *overrides: str, **values: Any) -> Config:
        """A validated copy with ``"dotted.key=VALUE"`` overrides and/or ``dotted__key=value``
        keywords (``joints__B__clearance=1e-4``) applied."""
        raw = self.to_dict()
        for key, value in values.items():
            set_setting(raw, key.replace("__", "."), value)
        return load_config(raw, overrides, source_name="<config>")


def _schema_of(cls: type) -> dict[str, Any]:
    return {f.name: (_schema_of(f.default_factory) if f.default_factory is not MISSING  # type: ignore[arg-type]
                     else f.metadata["field"])
            for f in fields(cls)}


def _info_of(cls: type, prefix: str = "") -> dict[str, tuple[str | None, str]]:
    out: dict[str, tuple[str | None, str]] = {}
    for f in fields(cls):
        if f.default_factory is not MISSING:
            sub = f.default_factory
            sub_prefix = ("joints.X." if sub is JointConfig else "joints.O." if sub is RevoluteJointConfig
                          else "joints.P." if sub is PrismaticJointConfig else f"{prefix}{f.name}.")
            out.update(_info_of(sub, sub_prefix))  # type: ignore[arg-type]
        else:
            out[prefix + f.name] = (f.metadata["units"], f.metadata["long_name"])
    return out


def _build(cls: type, values: Mapping[str, Any]) -> Any:
    kwargs = {}
    for f in fields(cls):
        value = values[f.name]
        if f.default_factory is not MISSING:
            value = _build(f.default_factory, value)  # type: ignore[arg-type]
        elif isinstance(value, list):
            value = tuple(value)
        kwargs[f.name] = value
    return cls(**kwargs)


#: The configuration schema (docs/architecture.md): nested sections of :class:`Field`,
#: read from the :class:`Config` dataclasses.
SCHEMA: dict[str, Any] = _schema_of(Config)

#: Units (UDUNITS text; None for text and switches) and long name of each leaf key;
#: ``joints.X`` stands for both joints. Sweep coordinates carry them.
FIELD_INFO: dict[str, tuple[str | None, str]] = _info_of(Config)


def field_info(key: str) -> tuple[str | None, str] | None:
    """Units (None for text and switches) and long name of dotted leaf ``key``; None if unknown.

    >>> field_info("joints.B.clearance")
    ('m', 'radial clearance of joint B')
    """
    parts = key.split(".")
    if len(parts) == 3 and parts[0] == "joints":
        info = FIELD_INFO.get(f"joints.X.{parts[2]}")
        return None if info is None else (info[0], info[1].replace("joint X", f"joint {parts[1]}"))
    return FIELD_INFO.get(key)


#: Smallest ball radius R_j = socket_radius - clearance, as a fraction of the socket radius.
#: A ball shrunk towards a point meets the socket with a contact radius the elastic model
#: does not describe: such a case ran "ok" with a penetration hundreds of times its radius.
MIN_BALL_RADIUS_FRACTION = 0.5

#: The RSSP's crank length and longest link [m], the same in both its presets
#: (clearsweep.params.PRESETS; tests/test_joint_bounds.py checks they agree): joint O's bearing
#: sits on the crank, so its radius is at most the crank's length, and no length of a joint
#: (bearing length, base, coating, block side) exceeds the longest link, the rod.
CRANK_LENGTH_M = 0.14
LONGEST_LINK_M = 0.38
#: Each preset's (crank length, longest link) [m], the bounds above for its mechanism.
PRESET_LINKS_M = {"realistic": (CRANK_LENGTH_M, LONGEST_LINK_M),
                  "paper": (CRANK_LENGTH_M, LONGEST_LINK_M),
                  "flores_benchmark": (0.05, 0.12)}


def _links(cfg: Mapping[str, Any]) -> tuple[float, float]:
    """The (crank length, longest link) [m] of the config's preset."""
    return PRESET_LINKS_M[cfg["mechanism"]["preset"]]
#: Smallest nonzero clearance [m]: below an atomic spacing a gap is no clearance, and the
#: contact law divides by it (a denormal 5e-324 m ended in ZeroDivisionError).
MIN_CLEARANCE_M = 1.0e-10
#: Smallest bearing radius and corner radius [m]: a Hertz patch of steel under the
#: mechanism's loads is tens of micrometres wide, so a smaller radius leaves the law's validity
#: (a 1 um bearing and a 1e-300 m corner ended in ValueError).
MIN_BEARING_RADIUS_M = 1.0e-3
MIN_CORNER_RADIUS_M = 1.0e-5
#: Largest Archard coefficient [m^2/N]: k / H for the dirtiest dry wear (k ~ 1e-2) on the
#: softest coating (H ~ 1e8 Pa) is 1e-10; the shipped materials are about 1e-14.
MAX_WEAR_COEFFICIENT = 1.0e-9
#: Thinnest coating or base layer [m]: a layer of a few atoms is no elastic layer (a 5e-324 m
#: coating or base ran to numbers as if it were one).
MIN_LAYER_M = 1.0e-9


def _check_sizes(joints: Mapping[str, Any], cfg: Mapping[str, Any], source: str) -> None:
    """Every geometric input of the joints bounded against the mechanism (issue 40 item 9)."""
    longest = _links(cfg)[1]
    for joint, spec in joints.items():
        for key in ("clearance", "clearance_y", "clearance_z"):
            if key in spec and 0.0 < spec[key] < MIN_CLEARANCE_M:
                raise ConfigError(f"joints.{joint}.{key}", spec[key],
                                  f"0 (an ideal joint) or a number >= {MIN_CLEARANCE_M:g} m", source)
        k = spec.get("wear_coefficient")
        if k is not None and k > MAX_WEAR_COEFFICIENT:
            raise ConfigError(f"joints.{joint}.wear_coefficient", k,
                              f"null or a number <= {MAX_WEAR_COEFFICIENT:g} m^2/N", source)
        for key in ("base_thickness", "coating_thickness"):
            if key in spec and 0.0 < spec[key] < MIN_LAYER_M:
                raise ConfigError(f"joints.{joint}.{key}", spec[key],
                                  f"a number >= {MIN_LAYER_M:g} m (a layer of more than a few "
                                  "atoms)", source)
        for key in ("length", "base_thickness", "coating_thickness"):
            if spec.get(key) is not None and spec[key] > longest:
                raise ConfigError(f"joints.{joint}.{key}", spec[key],
                                  f"a number <= {longest:g} m, the mechanism's longest "
                                  "link (the rod)", source)
    for joint, spec in joints.items():
        section_class(joint).check_sizes(joint, spec, cfg, source)


def _check_bearing(joint: str, spec: Mapping[str, Any], cfg: Mapping[str, Any],
                   source: str) -> None:
    """A bearing's radius within the crank, and its coating thinner than its radius."""
    radius = spec["bearing_radius"]
    crank = _links(cfg)[0]
    if not MIN_BEARING_RADIUS_M <= radius <= crank:
        raise ConfigError(f"joints.{joint}.bearing_radius", radius,
                          f"a number with {MIN_BEARING_RADIUS_M:g} <= x <= {crank:g} m "
                          "(the crank's length)", source)
    if spec["coating_thickness"] >= radius:
        raise ConfigError(f"joints.{joint}.coating_thickness", spec["coating_thickness"],
                          f"a number < joints.{joint}.bearing_radius ({radius:g} m)", source)


def _check_block(joint: str, spec: Mapping[str, Any], cfg: Mapping[str, Any],
                 source: str) -> None:
    """A guide's block: its corners' radius above the floor, its sides within the rod."""
    longest = _links(cfg)[1]
    if spec["corner_radius"] < MIN_CORNER_RADIUS_M:
        raise ConfigError(f"joints.{joint}.corner_radius", spec["corner_radius"],
                          f"a number >= {MIN_CORNER_RADIUS_M:g} m", source)
    if max(spec["block"]) > longest:
        raise ConfigError(f"joints.{joint}.block", spec["block"],
                          f"sides <= {longest:g} m, the mechanism's longest link (the rod)",
                          source)


def _check_ball_fit(joint: str, spec: Mapping[str, Any], ball: str, source: str) -> None:
    """A ball's (journal's) radius R_j = R_i - clearance at least
    :data:`MIN_BALL_RADIUS_FRACTION` of R_i."""
    radius = radius_key(spec)
    most = (1.0 - MIN_BALL_RADIUS_FRACTION) * spec[radius]
    if spec["clearance"] > most:
        raise ConfigError(
            f"joints.{joint}.clearance", spec["clearance"],
            f"a number <= {1.0 - MIN_BALL_RADIUS_FRACTION:g} * joints.{joint}.{radius} "
            f"({most:.6g}), so that the {ball} radius R_j = {radius} - clearance is at "
            f"least {MIN_BALL_RADIUS_FRACTION:g} * {radius}", source)


def _check_point_band(joint: str, spec: Mapping[str, Any], tolerance: float,
                      source: str) -> None:
    """The reliability band c -+ t of a ball's (journal's) clearance: above 0 and within
    the largest clearance (:func:`_check_ball_fit`)."""
    radius = radius_key(spec)
    most = (1.0 - MIN_BALL_RADIUS_FRACTION) * spec[radius]
    if 0.0 < spec["clearance"] <= tolerance:
        raise ConfigError("reliability.clearance_tolerance", tolerance,
                          f"a number < joints.{joint}.clearance ({spec['clearance']!r}), so that "
                          "every member keeps a clearance", source)
    if spec["clearance"] > 0.0 and spec["clearance"] + tolerance > most:
        room = most - spec["clearance"]     # in full where 6 digits would read as the value
        shown = f"{room:.6g}" if f"{room:.6g}" != f"{tolerance:.6g}" else repr(room)
        raise ConfigError(
            "reliability.clearance_tolerance", tolerance,
            f"a number <= {shown}, so that the band joints.{joint}."
            f"clearance -+ tolerance ({spec['clearance']:g} -+ {tolerance:g} m) stays within "
            f"the largest clearance, {1.0 - MIN_BALL_RADIUS_FRACTION:g} * joints.{joint}."
            f"{radius} ({most:.6g} m), whatever member draws it", source)


def _check_guide_band(joint: str, spec: Mapping[str, Any], tolerance: float,
                      source: str) -> None:
    """The reliability band of a guide's smaller clearance: above 0."""
    clearance = section_clearance(spec)
    if 0.0 < clearance <= tolerance:
        raise ConfigError("reliability.clearance_tolerance", tolerance,
                          f"a number < the smaller of joints.{joint}.clearance_y and clearance_z "
                          f"({clearance!r}), so that every member keeps a clearance", source)


def section_class(joint: str) -> Any:
    """The config class of joint section ``joint`` (``JointsConfig``'s field): its checks
    (``check_sizes``, ``check_fit``, ``check_band``) are the joint type's."""
    return type(getattr(JointsConfig(), joint))


#: The joints that are a ball in a socket in the RSSP and a pin in a bearing in the
#: slider-crank (``core.joints.SLIDER_CRANK_TYPES``): their ``length`` is the pin's.
SLIDER_CRANK_PINS = ("A", "B")


def _check_mechanism(cfg: Mapping[str, Any], source: str) -> None:
    """The preset is one of the mechanism's; a pin's ``length`` (A, B) only in the
    slider-crank. The slider-crank's guide with clearance holds its block in the plane, off
    the side walls (``clearance_y``, across the plane): its clearance is the one in the
    plane, ``clearance_z``, the smaller of the two."""
    kind, preset = cfg["mechanism"]["kind"], cfg["mechanism"]["preset"]
    if PRESET_KINDS[preset] != kind:
        raise ConfigError("mechanism.preset", preset,
                          f"a preset of mechanism.kind {kind}: one of "
                          f"{', '.join(MECHANISM_KINDS[kind])} (the default, realistic, is the "
                          "RSSP's)", source)
    if kind != "slider_crank":
        for joint in SLIDER_CRANK_PINS:
            length = cfg["joints"][joint].get("length")
            if length is not None:
                raise ConfigError(f"joints.{joint}.length", length,
                                  "null where mechanism.kind is rssp (its joint is a ball in a "
                                  "socket, without a length; the slider-crank's pins take one)",
                                  source)
    if kind == "slider_crank":
        guide = cfg["joints"]["P"]
        if 0.0 < guide["clearance_y"] < guide["clearance_z"]:
            raise ConfigError("joints.P.clearance_y", guide["clearance_y"],
                              f"a number >= joints.P.clearance_z ({guide['clearance_z']:g} m) "
                              "where mechanism.kind is slider_crank: the side walls' gap "
                              "across the plane, which the block held in the plane never "
                              "closes; the guide's clearance is clearance_z, in the plane",
                              source)


#: The slider-crank's pins: a bushing at one is radial in the mechanism's plane, its axial
#: pair the radial one (params.bushing_row; docs/mechanisms.md).
PIN_JOINTS = ("A", "B")
#: The bushing's (radial, axial) pairs.
BUSHING_PAIRS = ("bushing_stiffness", "bushing_damping")


def pin_type(kind: str) -> str:
    """The type of the joints A and B (not bushings) in mechanism ``kind``, as the kernel's
    joint table gives it (``core.joints.row_types``): the RSSP's balls in sockets,
    spherical; the slider-crank's pins, revolute."""
    from .core.joints import INDEX, row_types

    types = row_types(kind == "slider_crank")
    return types[INDEX[PIN_JOINTS[0]]]


def _given(raw: Any, joint: str, key: str) -> bool:
    """Whether the raw config (a file, ``--set`` or a sweep's case) gives ``joints.<joint>.<key>``
    (else the resolved value is a default)."""
    joints = raw.get("joints") if isinstance(raw, Mapping) else None
    given = joints.get(joint) if isinstance(joints, Mapping) else None
    return isinstance(given, Mapping) and key in given


def _check_pin_types(raw: Any, cfg: dict[str, Any], source: str) -> None:
    """``joints.A.type`` and ``joints.B.type``: the mechanism's type (:func:`pin_type`) or
    ``bushing``. One not given resolves to the mechanism's, so that the resolved config says
    what runs; the other mechanism's, given, is refused."""
    kind = cfg["mechanism"]["kind"]
    own = pin_type(kind)
    either = {pin_type(k) for k in MECHANISM_KINDS}
    for joint in PIN_JOINTS:
        spec = cfg["joints"][joint]
        if not _given(raw, joint, "type"):
            if spec["type"] in either:
                spec["type"] = own
        elif spec["type"] in either and spec["type"] != own:
            what = "balls in sockets" if kind == "rssp" else "pins in bearings"
            raise ConfigError(f"joints.{joint}.type", spec["type"],
                              f"{own} or bushing where mechanism.kind is {kind} "
                              f"(its A and B are {what})", source)


def _check_pin_bushings(raw: Any, cfg: dict[str, Any], source: str) -> None:
    """The slider-crank's A and B are pins held across the plane: a bushing there is radial
    in the plane, and the kernel runs its axial pair as the radial one. An axial value
    given (in the config, ``--set`` or a sweep) that differs from the radial one is
    refused, as it would be replaced; one not given follows the radial one in the resolved
    config, so that the config says what runs (and a sweep's cases, made from it, give it
    as it is)."""
    from .jointtypes import elastic

    if cfg["mechanism"]["kind"] != "slider_crank":
        return
    for joint in PIN_JOINTS:
        spec = cfg["joints"][joint]
        for key in BUSHING_PAIRS:
            radial, axial = spec[key]
            if not _given(raw, joint, key):
                spec[key] = type(spec[key])((radial, radial))
            elif axial != radial and elastic(spec["type"]):
                raise ConfigError(
                    f"joints.{joint}.{key}", list(spec[key]),
                    f"(radial, axial) with the axial value the radial one, [{radial:g}, "
                    f"{radial:g}], where mechanism.kind is slider_crank (a {spec['type']} at "
                    f"{joint} is a pin's: radial in the mechanism's plane, the pin held across it, "
                    "so the kernel would run the radial value in place of the axial one)",
                    source)


def _check_gapless(joints: Mapping[str, Any], source: str) -> None:
    """A joint whose type has no gap (``jointtypes.JointKind.gap`` False: the bushing) has no
    clearance and no coated surface: a clearance or a coating with it is refused (either
    would be silently ignored)."""
    from .jointtypes import elastic

    for joint, spec in joints.items():
        kind = spec.get("type")
        if not elastic(kind):
            continue
        if spec["clearance"] != 0.0:
            raise ConfigError(f"joints.{joint}.clearance", spec["clearance"],
                              f"0 where joints.{joint}.type is {kind} (a {kind} has no gap)",
                              source)
        if spec["coating"] != "none":
            raise ConfigError(f"joints.{joint}.coating", spec["coating"],
                              f"'none' where joints.{joint}.type is {kind} (a {kind} has no "
                              "contact surface)", source)


#: Relations between fields, checked after each field on its own: (key, op, other).
_RELATIONS = [
    ("friction.v1", ">", "friction.v0"),
    ("solver.dt", "<=", "solver.duration"),
    ("ensemble.member", "<", "ensemble.members"),
    ("reliability.member", "<", "reliability.members"),
]
_OPS = {"<": operator.lt, "<=": operator.le, ">": operator.gt}

_SWEEP_HINT = " (sweep files are run with `clearsweep sweep`)"

#: Top-level keys of a sweep file (:mod:`clearsweep.sweeping`); all but ``name`` are keys
#: that a case config does not have.
SWEEP_FILE_KEYS = ("name", "store", "base", "sweep")


def file_kind(doc: Any) -> str | None:
    """``"sweep"`` or ``"case"`` for a parsed YAML document whose top-level keys are those of
    one kind of file only, else ``None`` (not a mapping, mixed or misspelt keys, ``name`` alone).

    The commands use it to say which command fits a file given to the other one.
    """
    if not isinstance(doc, Mapping):
        return None
    keys = set(doc) - {"name"}
    if keys and keys <= set(SWEEP_FILE_KEYS):
        return "sweep"
    if keys and keys <= set(SCHEMA):
        return "case"
    return None


def _keys_text(doc: Mapping) -> str:
    return ", ".join(str(k) for k in doc)


#: The resolved default configuration.
DEFAULTS: Config = Config()


def _unknown_key(key: str, value: Any, options: Iterable[str], source: str, got: str | None = None):
    parent, _, name = key.rpartition(".")
    options = list(options)
    match = close_match(name, options)
    where = f"the keys of {parent}" if parent else "the top-level keys"
    hint = _SWEEP_HINT if key in ("sweep", "base") else ""
    return ConfigError(key, value, f"one of {where} ({', '.join(options)}){hint}", source,
                       f"{parent}.{match}" if parent and match else match, got)


def _resolve(raw: Any, schema: Mapping[str, Any], prefix: str, source: str) -> dict[str, Any]:
    if raw is None:
        raw = {}
    if not isinstance(raw, Mapping):
        raise ConfigError(prefix or None, raw, f"a mapping with keys {', '.join(schema)}", source)
    for key in raw:
        if key not in schema:
            raise _unknown_key(f"{prefix}.{key}" if prefix else str(key), raw[key], schema, source)
    out = {}
    for name, spec in schema.items():
        key = f"{prefix}.{name}" if prefix else name
        if isinstance(spec, Mapping):
            out[name] = _resolve(raw.get(name), spec, key, source)
        else:
            out[name] = spec.check(raw[name] if name in raw else copy.deepcopy(spec.default), key, source)
    return out


def _check_together(cfg: dict[str, Any], source: str) -> None:
    """Values each valid alone that together would run nothing useful or be ignored: a
    dopri5 longest step below its shortest one, perturbations of an ensemble of one."""
    solver = cfg["solver"]
    shortest = solver["dt"] / 2 ** solver["max_substep_level"]
    if solver["method"] == "dopri5" and solver["max_step"] is not None \
            and solver["max_step"] < shortest:
        raise ConfigError(
            "solver.max_step", solver["max_step"],
            f"null or a number >= solver.dt / 2^solver.max_substep_level ({shortest:.3g} s), the "
            "shortest step dopri5 may take: a shorter longest step stops every run with "
            "unstable_step at its first step", source)
    ensemble = cfg["ensemble"]
    if ensemble["members"] == 1:
        for key, value in ensemble["perturb"].items():
            if value:
                raise ConfigError(
                    f"ensemble.perturb.{key}", value,
                    "0 while ensemble.members is 1 (one perturbed case and no ensemble to "
                    "average it over); for perturbed members set ensemble.members to 2 or more", source)


def _check_guide(spec: Mapping[str, Any], wear_map: Sequence[int], source: str,
                 joint: str = "P") -> None:
    """A guide: both clearances or neither, a corner radius that fits the block, and with
    clearance a wear map of a polar row at least for each of its four walls (they are bands
    of the map's rows)."""
    cy, cz = spec["clearance_y"], spec["clearance_z"]
    if (cy > 0.0) != (cz > 0.0):
        key, value = ((f"joints.{joint}.clearance_z", cz) if cy > 0.0
                      else (f"joints.{joint}.clearance_y", cy))
        raise ConfigError(key, value, f"a number > 0 when the other clearance of joint {joint} "
                          "is, or both 0 (an ideal guide)", source)
    smallest = min(spec["block"])
    if spec["corner_radius"] > 0.5 * smallest:
        raise ConfigError(f"joints.{joint}.corner_radius", spec["corner_radius"],
                          f"a number <= half the block's smallest side ({0.5 * smallest:g} m, "
                          f"joints.{joint}.block)", source)
    if cy > 0.0 and wear_map[0] < 4:
        raise ConfigError("wear.map", wear_map, "at least 4 polar rows with clearance at "
                          f"joint {joint} (its four walls share them)", source)


#: A length given in seconds or in crank revolutions, one of the two (docs/configs.md):
#: (seconds key, revolutions key). The resolved config holds the seconds, from
#: ``revolutions * 60 / mechanism.speed_rpm`` where the revolutions were given.
ALTERNATIVES = (("solver.duration", "solver.revolutions"),
                ("metrics.settle_time", "metrics.settle_revolutions"))


def alternative_of(key: str) -> str | None:
    """The other key of ``key``'s pair in :data:`ALTERNATIVES`, or None."""
    for pair in ALTERNATIVES:
        if key in pair:
            return pair[1 - pair.index(key)]
    return None


def _given_alternatives(raw: Any, source: str) -> list[tuple[str, str, Any]]:
    """The pairs of :data:`ALTERNATIVES` given in revolutions in ``raw``: (seconds key,
    revolutions key, revolutions). A seconds key given as null is not given (it is removed
    from ``raw``: a resolved config's dict holds it so); both given is refused."""
    given = []
    for seconds, revolutions in ALTERNATIVES:
        section, _, s_name = seconds.partition(".")
        r_name = revolutions.partition(".")[2]
        node = raw.get(section) if isinstance(raw, Mapping) else None
        if not isinstance(node, dict):
            continue        # absent, or refused by _resolve
        if s_name in node and node[s_name] is None:
            del node[s_name]
        if node.get(r_name) is None:
            continue
        if s_name in node:
            raise ConfigError(revolutions, node[r_name],
                              f"null when {seconds} is given ({short_repr(node[s_name])}): a length "
                              f"is given in one of {seconds} [s] and {revolutions}, not both", source)
        given.append((seconds, revolutions, node[r_name]))
    return given


def _validate(raw: Any, source: str, base_dir: str) -> Config:
    given = _given_alternatives(raw, source)
    cfg = _resolve(raw, SCHEMA, "", source)
    speed = cfg["mechanism"]["speed_rpm"]
    for seconds, revolutions, _ in given:
        # the checked value (normalised by _resolve) in seconds at this case's speed
        turns = get_path(cfg, revolutions)
        length = turns * 60.0 / speed
        if not math.isfinite(length) and math.isfinite(60.0 / speed):
            raise ConfigError(revolutions, turns,
                              f"a number of revolutions that lasts a finite time at "
                              f"mechanism.speed_rpm = {speed!r} ({revolutions} * 60 / "
                              f"mechanism.speed_rpm = {length!r} s)", source)
        if not math.isfinite(length):
            raise ConfigError("mechanism.speed_rpm", speed,
                              f"a speed at which {revolutions} ({turns!r}) lasts a finite time "
                              f"({revolutions} * 60 / mechanism.speed_rpm = {length!r} s)", source)
        set_path(cfg, seconds, length)
    for key, op, other in _RELATIONS:
        value, bound = get_path(cfg, key), get_path(cfg, other)
        if not _OPS[op](value, bound):
            turns = get_path(cfg, "solver.revolutions") if other == "solver.duration" else None
            if turns is not None:
                # the length was asked in revolutions: name that key, not the derived seconds
                raise ConfigError("solver.revolutions", turns,
                                  f"a run of at least one step: solver.revolutions * 60 / "
                                  f"mechanism.speed_rpm = {turns!r} * 60 / {speed!r} = {bound:.3g} s, "
                                  f"below solver.dt ({value!r} s)", source)
            raise ConfigError(key, value, f"a number {op} {other} ({bound!r})", source)
    _check_together(cfg, source)
    _check_mechanism(cfg, source)
    _check_pin_types(raw, cfg, source)
    _check_pin_bushings(raw, cfg, source)
    _check_sizes(cfg["joints"], cfg, source)
    _check_gapless(cfg["joints"], source)
    for joint, spec in cfg["joints"].items():
        section_class(joint).check_fit(joint, spec, cfg, source)
    # The tolerance band c -+ t (uniform, or the normal's cut at -+3 sigma) holds every
    # clearance a reliability member can draw: both ends must be clearances this check
    # admits, so that no seed decides whether the config is valid (docs/reliability.md).
    # A member's own config has its drawn clearance and no band (reliability.member_config).
    tolerance = cfg["reliability"]["clearance_tolerance"]
    for joint, spec in cfg["joints"].items():
        section_class(joint).check_band(joint, spec, tolerance, source)
    if cfg["materials_file"] is not None:
        path = os.path.abspath(os.path.join(base_dir, os.path.expanduser(cfg["materials_file"])))
        if not os.path.isfile(path):
            raise ConfigError("materials_file", cfg["materials_file"],
                              f"an existing YAML file (looked for {path})", source)
        cfg["materials_file"] = path
    from .materials import load_materials

    materials = load_materials(cfg["materials_file"])
    for joint in cfg["joints"]:
        coating = cfg["joints"][joint]["coating"]
        if coating != "none" and coating not in materials:
            raise ConfigError(f"joints.{joint}.coating", coating,
                              f"'none' or a known material ({', '.join(materials)})", source,
                              close_match(coating, ["none", *materials]))
    return _build(Config, cfg)


# ---------------------------------------------------------------------------- public API

def get_path(cfg: Mapping[str, Any] | _Section, key: str) -> Any:
    """Value at dotted ``key`` (``"joints.A.clearance"``) of a nested mapping.

    Raises
    ------
    ConfigError
        If the key does not exist (with the closest existing key).
    """
    node: Any = cfg.to_dict() if isinstance(cfg, _Section) else cfg
    parts = key.split(".")
    for i, part in enumerate(parts):
        if not isinstance(node, Mapping) or part not in node:
            options = node if isinstance(node, Mapping) else []
            raise _unknown_key(".".join(parts[: i + 1]), None, options, "<config>", got="no such key")
        node = node[part]
    return node


def set_path(cfg: dict[str, Any], key: str, value: Any) -> None:
    """Set dotted ``key`` of ``cfg`` to ``value`` in place, creating missing sections.

    Raises
    ------
    ConfigError
        If a part of ``key`` other than the last holds a value, not a section.
    """
    parts = key.split(".")
    node = cfg
    for i, part in enumerate(parts[:-1]):
        node = node.setdefault(part, {})
        if not isinstance(node, dict):
            parent = ".".join(parts[: i + 1])
            raise ConfigError(key, value, f"a key inside a section, but {parent} is a value", "<config>")
    node[parts[-1]] = value


def set_setting(cfg: dict[str, Any], key: str, value: Any) -> None:
    """:func:`set_path`, for a setting given after the config (``--set``, a sweep's axis,
    :meth:`Config.replace`): a value for one key of an :data:`ALTERNATIVES` pair replaces
    the length the config gave in the other unit (``solver.revolutions=10`` over a file's
    ``solver.duration: 2`` runs 10 revolutions)."""
    other = alternative_of(key)
    if other is not None and value is not None:
        section, _, name = other.partition(".")
        node = cfg.get(section)
        if isinstance(node, dict):
            node.pop(name, None)
    set_path(cfg, key, value)


def _split_override(text: str, source: str) -> tuple[str, Any]:
    key, sep, raw = str(text).partition("=")
    key = key.strip()
    if not sep or not key or any(not part for part in key.split(".")):
        raise ConfigError(None, text, "an override KEY=VALUE with a dotted key, e.g. joints.B.coating=PTFE",
                          source)
    if not raw.strip():     # YAML reads it as null: say what was typed
        raise ConfigError(key, raw, "a value after '=' (null for none)", source,
                          got="an empty value (from --set)")
    try:
        return key, parse_yaml(raw, source)
    except ConfigError as exc:
        raise ConfigError(key, raw, exc.expected, source) from None


def apply_override(cfg: dict[str, Any], text: str, *, source: str = "--set") -> dict[str, Any]:
    """Apply one override ``"dotted.key=VALUE"`` to ``cfg`` in place and return it.

    ``VALUE`` is parsed as YAML (``0.001`` is a float, ``[50, 50]`` a list,
    ``PTFE`` a string, ``null`` None). The result is not validated: pass it
    to :func:`load_config` for that.
    """
    key, value = _split_override(text, source)
    set_setting(cfg, key, value)
    return cfg


def load_config(source: str | os.PathLike | Mapping[str, Any] | Config, overrides: Iterable[str] = (),
                *, source_name: str | None = None) -> Config:
    """Read, override, validate and resolve a configuration.

    Parameters
    ----------
    source
        Path of a YAML file, a mapping (left unchanged), or a :class:`Config` (returned as
        it is when there are no overrides: it was validated when it was made). YAML text is
        not accepted.
    overrides
        Strings ``"dotted.key=VALUE"`` applied in order before validation.
    source_name
        Name used in error messages (default: the path as given, or ``"<config>"``).

    Returns
    -------
    Config
        Frozen and fully resolved, every key of :data:`SCHEMA` present;
        ``materials_file`` made absolute (relative paths are taken from the
        config file's folder, or the current folder for a mapping).

    Raises
    ------
    ConfigError
        For any unreadable, malformed, unknown, mistyped or out-of-range input.
    """
    overrides = [overrides] if isinstance(overrides, str) else list(overrides)
    if isinstance(source, Config):
        if not overrides:
            return source
        source = source.to_dict()
    if isinstance(source, Mapping):
        label, raw, base_dir = source_name or "<config>", copy.deepcopy(dict(source)), os.getcwd()
    else:
        label = source_name or str(source)
        raw, base_dir = read_yaml(source, label), os.path.dirname(os.path.abspath(source))
        if raw is None:
            raise ConfigError(None, None, f"a mapping with keys {', '.join(SCHEMA)}", label,
                              got="an empty file")
        if file_kind(raw) == "sweep":
            raise ConfigError(None, None, f"a case config; run a sweep file with `clearsweep sweep "
                              f"{label}` (check it with `clearsweep validate {label}`)", label,
                              got=f"a sweep file (top-level keys {_keys_text(raw)})")
    if not isinstance(raw, dict):
        raise ConfigError(None, raw, f"a mapping with keys {', '.join(SCHEMA)}", label)
    overridden: list[str] = []
    try:
        for text in overrides:
            key, value = _split_override(text, label)
            if alternative_of(key) in overridden:
                raise ConfigError(key, value, f"one of {alternative_of(key)} and {key}, not both "
                                  "(the same length in two units)", label,
                                  got=f"{short_repr(value)} (from --set)")
            overridden.append(key)
            set_setting(raw, key, value)
        return _validate(raw, label, base_dir)
    except ConfigError as exc:
        if exc.key and any(exc.key == k or k.startswith(exc.key + ".") for k in overridden):
            big = oversized_number(exc.value)
            shown = short_repr(exc.value) if big is None else oversized_text(big)
            raise ConfigError(exc.key, exc.value, exc.expected, label, exc.suggestion,
                              f"{shown} (from --set)") from None
        raise


def dump_config(cfg: Mapping[str, Any] | Config) -> str:
    """YAML text of ``cfg`` in schema order; ``load_config`` of it gives ``cfg`` back."""
    return dump_yaml(cfg.to_dict() if isinstance(cfg, _Section) else dict(cfg))


def resolve_materials(cfg: Config) -> dict[str, Any]:
    """Materials available to ``cfg``: the shipped ones and its ``materials_file``.

    Returns
    -------
    dict[str, clearsweep.materials.Material]
    """
    from .materials import load_materials

    return load_materials(cfg.materials_file)
