"""The joint types as the host sees them: one :class:`JointKind` per registered type.

The kernel's side of a joint type is its module of ``core/`` and the compiled protocol
``core.joints.PROTOCOL``; this is the host's side, read by the results, the plots and the
reports so that none of them branches on a type's name (docs/architecture.md, "Joint
types"): what the joint's moving part and its worn surface are called, the shape of its gap
in an orbit plot, the wear figure it takes, the rows of the wear map and of the projections
it fills, the packed columns it owns (``core.layout``, "per-joint parameters"), and the
contact law its report names. Where ``params`` needs a type's behaviour (packing its own
columns, its step bound, its seated start), it looks it up in ``params.HOST_HOOKS`` by the
same name. A new type is one entry of :data:`KINDS` (and one of ``params.HOST_HOOKS`` where
its behaviour differs from a point joint's); tests/test_jointtypes.py fails for a registered
type without one.

A joint of the table takes its table type (``core.joints.JOINTS``); a dataset that records
a joint's type (``joint_<J>_type``, ``params.joint_attributes``) is read by that.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from .core import layout
from .core.joints import JOINT_TYPES, JOINTS

#: Shapes of a joint's gap in the orbit plot (``plotting.orbit``): the ball's clearance circle
#: in each of the three planes, the journal's in its bearing's plane (y, z), the block's
#: clearance rectangle across its guide (y, z), or none (a joint without a gap).
ORBIT_GAPS = ("sphere", "circle", "rectangle", "none")

#: Wear figures (``plotting.wear``): the socket's map over its sphere (polar angle by
#: azimuth, and on the unit sphere), the bearing's one row around it, the guide's four wall
#: strips, or none (a type that does not wear).
WEAR_FIGURES = ("sphere", "bearing", "walls", "none")


@dataclass(frozen=True)
class JointKind:
    """A joint type's host-side description (one entry of :data:`KINDS`)."""

    #: the type's name: its key in ``core.joints.JOINT_TYPES`` and in ``params.HOST_HOOKS``
    name: str
    #: what the joint's moving part is called ("ball", "journal", "block")
    centre: str
    #: the worn surface, in figure titles ("socket", "bearing", "guide")
    surface: str
    #: how a figure names the joint ("joint A", "bearing O", "guide P")
    title: str
    #: the body the joint force acts on, in the forces figure; None: the joint's force is the
    #: reaction ``reaction_O`` drawn on its own
    force_on: str | None
    #: its gap's shape in the orbit plot (:data:`ORBIT_GAPS`)
    orbit_gap: str
    #: its wear figure (:data:`WEAR_FIGURES`)
    wear_figure: str
    #: whether its wear is a profile about the axes (``wear_projection``: the wear-polar
    #: figure and the flat wear table's rows); a flat wall's is not
    wear_profile: bool
    #: whether its map's bins cover equal areas (the guide's: each bin the same length along
    #: the guide and width across it), else the socket's sphere areas (``wear.bin_areas``)
    equal_bins: bool
    #: rows of the wear map its map takes, from the map's polar bins
    map_rows: Callable[[int], int]
    #: rows of N_ANGLE_BINS projection bins its wear fills (x, y, z), 0: none
    proj_rows: int
    #: whether the undo buffer holds its wear row by row (``rk4.accept_substep``)
    undo_rows: bool
    #: whether the joint's moving part stays on its axis (the journal in its bearing's plane,
    #: the block across its guide): its axial offset and load are ideal
    axial_ideal: bool
    #: whether its contact always takes Hertz's power law (else only under
    #: ``contact.elastic: hertz``)
    power_law: bool
    #: its contact law in words where it is not the point contact's (the report's ``contact``
    #: attribute), else None
    contact_law: str | None
    #: the per-joint packed columns (``core.layout.J_*``) of its own, beyond
    #: :data:`COMMON_COLUMNS`: a column that another type names and it does not is 0 in its
    #: row
    columns: tuple[str, ...]
    #: the wear-depth report's own columns (the guide's tracks), () for none
    report_columns: tuple[str, ...] = ()
    #: whether the joint has a gap (contact, impacts, wear); False: an elastic joint (the
    #: bushing), ideal to the contact and wear figures, whose deflection is its orbit
    gap: bool = True
    #: the component of its offset (``ball_offset``, the start's offsets) across the planar
    #: slider-crank's plane: x (0) in a socket's frame; the guide's side (1) in the guide's
    #: frame (along, side, up: the slider-crank's side is -x, docs/mechanisms.md)
    off_plane_axis: int = 0


def _rows_polar(npolar: int) -> int:
    return npolar


def _rows_one(npolar: int) -> int:
    return 1


def _rows_none(npolar: int) -> int:
    return 0


#: The registered joint types' host descriptions, by type name.
KINDS: Mapping[str, JointKind] = {
    "spherical": JointKind(
        name="spherical", centre="ball", surface="socket", title="joint", force_on="the ball",
        orbit_gap="sphere", wear_figure="sphere", wear_profile=True, equal_bins=False,
        map_rows=_rows_polar, proj_rows=3, undo_rows=True, axial_ideal=False,
        power_law=False, contact_law=None,
        columns=("J_RI", "J_RJ")),
    "revolute": JointKind(
        name="revolute", centre="journal", surface="bearing", title="bearing", force_on=None,
        orbit_gap="circle", wear_figure="bearing", wear_profile=True, equal_bins=False,
        map_rows=_rows_one, proj_rows=3, undo_rows=True, axial_ideal=True,
        power_law=True, contact_law=None,
        columns=("J_RI", "J_RJ", "J_LENGTH", "J_FILM")),
    "prismatic": JointKind(
        name="prismatic", centre="block", surface="guide", title="guide",
        force_on="the slider", orbit_gap="rectangle", wear_figure="walls",
        wear_profile=False, equal_bins=True, map_rows=_rows_polar, proj_rows=0,
        undo_rows=False, axial_ideal=True, power_law=True,
        contact_law="elastic foundation on the faces' edge lines, E*",
        columns=("J_BLOCK_LENGTH", "J_CORNER_RADIUS", "J_WIDTH", "J_HEIGHT", "J_CY", "J_CZ",
                 "J_X0", "J_XSPAN"),
        report_columns=("track_depth",), off_plane_axis=1),
    "bushing": JointKind(
        name="bushing", centre="ball", surface="bushing", title="bushing", force_on="the ball",
        orbit_gap="none", wear_figure="none", wear_profile=False, equal_bins=False,
        map_rows=_rows_none, proj_rows=0, undo_rows=False, axial_ideal=False,
        power_law=False, contact_law="linear spring-damper (bushing), no contact",
        columns=("J_BUSHING", "J_K_RADIAL", "J_K_AXIAL", "J_C_RADIAL", "J_C_AXIAL"),
        gap=False),
}


#: The packed columns every type fills (``core.layout.J_*``): those no type names as its own
#: (the clearance flag and the clearance c, the surface's and the base's contact values, the
#: coating and the stop).
COMMON_COLUMNS = tuple(name for name, value in vars(layout).items()
                       if name.startswith("J_") and isinstance(value, int)
                       and not any(name in k.columns for k in KINDS.values()))


def kind(type_name: str) -> JointKind:
    """The host description of the joint type ``type_name``."""
    return KINDS[type_name]


def elastic(type_name: Any) -> bool:
    """Whether ``type_name`` (a recorded ``joint_<J>_type``, any value) names a registered
    type without a gap (:attr:`JointKind.gap`: the bushing)."""
    found = KINDS.get(str(type_name))
    return found is not None and not found.gap


#: Each joint of the table's type by name.
TABLE_TYPES = {joint.name: joint.type for joint in JOINTS}


def type_of(joint: Any, attrs: Mapping[str, Any] | None = None) -> str | None:
    """The type name of the joint named ``joint`` (a name, or an array element holding one):
    the dataset's record ``joint_<J>_type`` where ``attrs`` has one, else the joint table's;
    None for a name that is neither."""
    name = str(joint.item() if hasattr(joint, "item") else joint)
    if attrs is not None:
        recorded = attrs.get(f"joint_{name}_type")
        if isinstance(recorded, str) and recorded in KINDS:
            return recorded
    return TABLE_TYPES.get(name)


def kind_of(joint: Any, attrs: Mapping[str, Any] | None = None) -> JointKind | None:
    """The :class:`JointKind` of the joint named ``joint`` (:func:`type_of`), None where the
    name is no joint's."""
    found = type_of(joint, attrs)
    return None if found is None else KINDS[found]


def describe(joint: Any, attrs: Mapping[str, Any] | None = None) -> JointKind:
    """:func:`kind_of`, where a name that is no joint's reads as a ball in a socket (the
    figures' and reports' reading of a dataset whose joints the table does not name)."""
    found = kind_of(joint, attrs)
    return KINDS["spherical"] if found is None else found


def registered() -> tuple[str, ...]:
    """The type names the kernel registers (``core.joints.JOINT_TYPES``), in its order."""
    return tuple(JOINT_TYPES)
