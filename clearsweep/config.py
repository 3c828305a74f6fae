"""Configuration: schema, defaults, validation, ``--set`` overrides.

The resolved configuration is the contract between modules
(docs/architecture.md): a plain nested dict with every key of :data:`SCHEMA`
present, numbers normalised (``float`` or ``int`` as the schema says, lists
as lists). Everything is checked here, before any computation; a wrong value
raises :class:`ConfigError` with a message of the form::

    <file>: <dotted.key>: got <value>; expected <what is allowed>[; did you mean '<match>'?]

YAML reading, errors and :class:`Field` live in :mod:`clearsweep.schema`.
"""

from __future__ import annotations

import copy
import operator
import os
from collections.abc import Iterable, Mapping
from typing import Any

from .schema import (  # noqa: F401
    MAX_YAML_ALIASES,
    MAX_YAML_BYTES,
    MAX_YAML_DEPTH,
    MAX_YAML_VALUES,
    ConfigError,
    Field,
    close_match,
    dump_yaml,
    parse_yaml,
    read_yaml,
    short_repr,
)

__all__ = [
    "ConfigError", "Field", "SCHEMA", "DEFAULTS", "load_config", "apply_override", "dump_config",
    "get_path", "set_path", "resolve_materials", "read_yaml", "parse_yaml", "close_match",
    "field_info", "FIELD_INFO",
]


def _positive(default: float) -> Field:
    return Field(default, lo=0.0, lo_open=True)


_JOINT = {
    "clearance": Field(0.0, lo=0.0),               # c = R_i - R_j [m]; 0 = ideal joint
    "socket_radius": _positive(0.015),             # R_i [m]
    "coating": Field("none", str),                 # material name or "none"
    "coating_thickness": _positive(1.0e-4),        # l_c [m]
    "base_thickness": _positive(4.9e-3),           # l_s [m]
    "wear_coefficient": Field(None, lo=0.0, nullable=True),  # k [m^2/N]; None = the material's
}

#: The configuration schema (docs/architecture.md): nested sections of :class:`Field`.
SCHEMA: dict[str, Any] = {
    "name": Field("case", str),
    "materials_file": Field(None, str, nullable=True),
    "mechanism": {
        "preset": Field("realistic", ("realistic", "paper")),
        "speed_rpm": _positive(60.0),                     # [r/min]
        "gravity": Field([0.0, 0.0, -9.81], size=3),      # [m/s^2]
        "theta0": Field(0.0),                             # [rad]
    },
    "initial": {
        # seated: each clearance joint starts with its ball resting on the socket wall,
        # along the ideal joint's reaction at t = 0; centred: ball in the socket centre
        "joints": Field("seated", ("seated", "centred")),
    },
    "joints": {"A": _JOINT, "B": _JOINT},
    "contact": {
        "restitution": Field(0.7, lo=0.0, lo_open=True, hi=1.0),
        "min_impact_velocity": _positive(1.0e-2),         # [m/s]
        "layer_rule": Field("series", ("series", "paper_mm")),
        "max_penetration_fraction": _positive(0.5),
    },
    "friction": {
        "enabled": Field(True, bool),
        "v0": _positive(1.0e-4),                          # [m/s]
        "v1": _positive(1.0e-3),                          # [m/s]
    },
    "wear": {
        "enabled": Field(True, bool),
        "slip": Field("sliding", ("sliding", "paper")),
        "map": Field([144, 288], int, lo=1, size=2),      # polar x azimuth bins
        "amplification": Field(1.0, lo=0.0),
        "feedback": Field(True, bool),                    # worn depth enlarges c_eff
    },
    "metrics": {
        "settle_time": Field(0.05, lo=0.0),               # start of the settled window [s]
    },
    "solver": {
        "dt": _positive(1.0e-5),                          # [s]
        "duration": _positive(1.0),                       # [s]
        "save_every": Field(10, int, lo=1),
        "baumgarte": Field([5.0, 5.0], lo=0.0, size=2),   # [alpha, beta]
        "max_substep_level": Field(8, int, lo=0, hi=16),
        "stability_limit": Field(1.0, lo=0.0, lo_open=True, hi=2.8, hi_open=True),
        "constraint_tolerance": _positive(1.0e-6),        # [m]
        "energy_tolerance": _positive(1.0e-3),
    },
}

#: Units (UDUNITS text; None for text and switches) and long name of each leaf key;
#: ``joints.X`` stands for both joints. Sweep coordinates carry them.
FIELD_INFO: dict[str, tuple[str | None, str]] = {
    "name": (None, "case name"),
    "materials_file": (None, "user materials file"),
    "mechanism.preset": (None, "mechanism data preset"),
    "mechanism.speed_rpm": ("min-1", "crank speed in revolutions per minute"),
    "mechanism.gravity": ("m s-2", "gravity vector"),
    "mechanism.theta0": ("rad", "initial crank angle"),
    "initial.joints": (None, "initial ball position in the clearance joints"),
    "joints.X.clearance": ("m", "radial clearance of joint X"),
    "joints.X.socket_radius": ("m", "socket radius of joint X"),
    "joints.X.coating": (None, "socket coating of joint X"),
    "joints.X.coating_thickness": ("m", "coating thickness of joint X"),
    "joints.X.base_thickness": ("m", "socket base thickness of joint X"),
    "joints.X.wear_coefficient": ("m2 N-1", "Archard wear coefficient of joint X's socket"),
    "contact.restitution": ("1", "coefficient of restitution"),
    "contact.min_impact_velocity": ("m s-1", "floor of the impact velocity"),
    "contact.layer_rule": (None, "double elastic layer rule"),
    "contact.max_penetration_fraction": ("1", "largest penetration accepted, fraction of the clearance"),
    "friction.enabled": (None, "friction on"),
    "friction.v0": ("m s-1", "friction ramp start velocity"),
    "friction.v1": ("m s-1", "friction ramp end velocity"),
    "wear.enabled": (None, "wear on"),
    "wear.slip": (None, "wear slip rule"),
    "wear.map": ("1", "wear map bins (polar, azimuth)"),
    "wear.amplification": ("1", "wear amplification"),
    "wear.feedback": (None, "wear enlarges the clearance"),
    "metrics.settle_time": ("s", "start of the settled window"),
    "solver.dt": ("s", "output-grid time step"),
    "solver.duration": ("s", "simulated duration"),
    "solver.save_every": ("1", "steps per output sample"),
    "solver.baumgarte": ("s-1", "Baumgarte coefficients (alpha, beta)"),
    "solver.max_substep_level": ("1", "deepest sub-step level"),
    "solver.stability_limit": ("1", "largest stiff rate times step"),
    "solver.constraint_tolerance": ("m", "constraint violation stop"),
    "solver.energy_tolerance": ("1", "energy residual stop, fraction of the throughput"),
}


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

#: Relations between fields, checked after each field on its own: (key, op, other).
_RELATIONS = [
    ("friction.v1", ">", "friction.v0"),
    ("solver.dt", "<=", "solver.duration"),
]
_OPS = {"<": operator.lt, "<=": operator.le, ">": operator.gt}

_SWEEP_HINT = " (sweep files are run with `clearsweep sweep`)"


def _defaults(schema: Mapping[str, Any]) -> dict[str, Any]:
    return {k: _defaults(v) if isinstance(v, Mapping) else copy.deepcopy(v.default)
            for k, v in schema.items()}


#: The resolved default configuration (copy it before changing it).
DEFAULTS: dict[str, Any] = _defaults(SCHEMA)


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


def _validate(raw: Any, source: str, base_dir: str) -> dict[str, Any]:
    cfg = _resolve(raw, SCHEMA, "", source)
    for key, op, other in _RELATIONS:
        value, bound = get_path(cfg, key), get_path(cfg, other)
        if not _OPS[op](value, bound):
            raise ConfigError(key, value, f"a number {op} {other} ({bound!r})", source)
    for joint, spec in cfg["joints"].items():
        most = (1.0 - MIN_BALL_RADIUS_FRACTION) * spec["socket_radius"]
        if spec["clearance"] > most:
            raise ConfigError(
                f"joints.{joint}.clearance", spec["clearance"],
                f"a number <= {1.0 - MIN_BALL_RADIUS_FRACTION:g} * joints.{joint}.socket_radius "
                f"({most:.6g}), so that the ball radius R_j = socket_radius - clearance is at "
                f"least {MIN_BALL_RADIUS_FRACTION:g} * socket_radius", source)
    if cfg["materials_file"] is not None:
        path = os.path.abspath(os.path.join(base_dir, os.path.expanduser(cfg["materials_file"])))
        if not os.path.isfile(path):
            raise ConfigError("materials_file", cfg["materials_file"],
                              f"an existing YAML file (looked for {path})", source)
        cfg["materials_file"] = path
    materials = resolve_materials(cfg)
    for joint in cfg["joints"]:
        coating = cfg["joints"][joint]["coating"]
        if coating != "none" and coating not in materials:
            raise ConfigError(f"joints.{joint}.coating", coating,
                              f"'none' or a known material ({', '.join(materials)})", source,
                              close_match(coating, ["none", *materials]))
    return cfg


# ---------------------------------------------------------------------------- public API

def get_path(cfg: Mapping[str, Any], key: str) -> Any:
    """Value at dotted ``key`` (``"joints.A.clearance"``) of a nested mapping.

    Raises
    ------
    ConfigError
        If the key does not exist (with the closest existing key).
    """
    node: Any = cfg
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


def _split_override(text: str, source: str) -> tuple[str, Any]:
    key, sep, raw = str(text).partition("=")
    key = key.strip()
    if not sep or not key or any(not part for part in key.split(".")):
        raise ConfigError(None, text, "an override KEY=VALUE with a dotted key, e.g. joints.B.coating=PTFE",
                          source)
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
    set_path(cfg, key, value)
    return cfg


def load_config(source: str | os.PathLike | Mapping[str, Any], overrides: Iterable[str] = (), *,
                source_name: str | None = None) -> dict[str, Any]:
    """Read, override, validate and resolve a configuration.

    Parameters
    ----------
    source
        Path of a YAML file, or a mapping (left unchanged). YAML text is not accepted.
    overrides
        Strings ``"dotted.key=VALUE"`` applied in order before validation.
    source_name
        Name used in error messages (default: the path as given, or ``"<config>"``).

    Returns
    -------
    dict
        A new, fully resolved nested dict with every key of :data:`SCHEMA`;
        ``materials_file`` made absolute (relative paths are taken from the
        config file's folder, or the current folder for a mapping).

    Raises
    ------
    ConfigError
        For any unreadable, malformed, unknown, mistyped or out-of-range input.
    """
    if isinstance(source, Mapping):
        label, raw, base_dir = source_name or "<config>", copy.deepcopy(dict(source)), os.getcwd()
    else:
        label = source_name or str(source)
        raw, base_dir = read_yaml(source, label), os.path.dirname(os.path.abspath(source))
        if raw is None:
            raise ConfigError(None, None, f"a mapping with keys {', '.join(SCHEMA)}", label,
                              got="an empty file")
    if not isinstance(raw, dict):
        raise ConfigError(None, raw, f"a mapping with keys {', '.join(SCHEMA)}", label)
    overridden: list[str] = []
    try:
        for text in [overrides] if isinstance(overrides, str) else overrides:
            key, value = _split_override(text, label)
            overridden.append(key)
            set_path(raw, key, value)
        return _validate(raw, label, base_dir)
    except ConfigError as exc:
        if exc.key and any(exc.key == k or k.startswith(exc.key + ".") for k in overridden):
            raise ConfigError(exc.key, exc.value, exc.expected, label, exc.suggestion,
                              f"{short_repr(exc.value)} (from --set)") from None
        raise


def dump_config(cfg: Mapping[str, Any]) -> str:
    """YAML text of ``cfg`` in schema order; ``load_config`` of it gives ``cfg`` back."""
    return dump_yaml(dict(cfg))


def resolve_materials(cfg: Mapping[str, Any]) -> dict[str, Any]:
    """Materials available to ``cfg``: the shipped ones and its ``materials_file``.

    Returns
    -------
    dict[str, clearsweep.materials.Material]
    """
    from .materials import load_materials

    return load_materials(cfg.get("materials_file"))
