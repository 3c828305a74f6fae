"""Configuration: schema, defaults, validation, ``--set`` overrides.

The resolved configuration is the contract between modules
(docs/architecture.md): a plain nested dict with every key of :data:`SCHEMA`
present, numbers normalised (``float`` or ``int`` as the schema says, lists
as lists). Everything is checked here, before any computation; a wrong value
raises :class:`ConfigError` with a message of the form::

    <file>: <dotted.key>: got <value>; expected <what is allowed>[; did you mean '<match>'?]

YAML is read with PyYAML's safe loader, extended so that a float written
without a dot (``1e-5``) is a number, as in YAML 1.2, and not a string.
"""

from __future__ import annotations

import copy
import difflib
import math
import numbers
import operator
import os
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

__all__ = [
    "ConfigError", "Field", "SCHEMA", "DEFAULTS", "load_config", "apply_override", "dump_config",
    "get_path", "set_path", "resolve_materials", "read_yaml", "parse_yaml", "close_match",
]


def short_repr(value: Any, limit: int = 80) -> str:
    """``repr(value)``, cut to ``limit`` characters."""
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


class ConfigError(ValueError):
    """A configuration or materials value that is not allowed.

    Parameters
    ----------
    key
        Dotted key of the offending value (``"joints.A.clearance"``), or
        ``None`` for the file as a whole.
    value
        The value received.
    expected
        What is allowed, in words.
    source
        The file as given by the caller, or ``"<config>"`` for a dict.
    suggestion
        A close match for a misspelt key or name.
    got
        Text shown in place of ``repr(value)``.
    line
        Line number [1-based] in ``source``, for YAML syntax errors.
    """

    def __init__(self, key: str | None, value: Any, expected: str, source: str = "<config>",
                 suggestion: str | None = None, got: str | None = None, line: int | None = None):
        self.key, self.value, self.expected = key, value, expected
        self.source, self.suggestion, self.got, self.line = str(source), suggestion, got, line
        where = self.source + (f": line {line}" if line else "") + (f": {key}" if key else "")
        text = f"{where}: got {got if got is not None else short_repr(value)}; expected {expected}"
        if suggestion is not None:
            text += f"; did you mean {suggestion!r}?"
        super().__init__(text)

    def __str__(self) -> str:
        return self.args[0]

    def __reduce__(self):
        # Survive pickling (process pools): rebuild from the fields, not from the message.
        return (type(self), (self.key, self.value, self.expected, self.source, self.suggestion,
                             self.got, self.line))


def close_match(word: Any, options: Iterable[Any]) -> str | None:
    """The option closest to ``word`` (case-insensitive, :mod:`difflib`), or ``None``."""
    by_lower = {str(o).lower(): str(o) for o in options}
    word = str(word).lower()
    if word in by_lower:
        return by_lower[word]
    hits = difflib.get_close_matches(word, list(by_lower), n=1, cutoff=0.6)
    return by_lower[hits[0]] if hits else None


# ---------------------------------------------------------------------------- YAML

class _Loader(yaml.SafeLoader):
    """Safe loader that also reads ``1e-5`` (no dot) as a float."""


class _Dumper(yaml.SafeDumper):
    """Safe dumper: sections in block style, lists inline, strings quoted where ``_Loader`` needs."""


_Dumper.add_representer(list, lambda dumper, value: dumper.represent_sequence(
    "tag:yaml.org,2002:seq", value, flow_style=True))
_FLOAT_WITHOUT_DOT = re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9][0-9_]*)[eE][-+]?[0-9]+$")
_Loader.add_implicit_resolver("tag:yaml.org,2002:float", _FLOAT_WITHOUT_DOT, list("-+0123456789."))
_Dumper.add_implicit_resolver("tag:yaml.org,2002:float", _FLOAT_WITHOUT_DOT, list("-+0123456789."))


def parse_yaml(text: str, source: str = "<config>") -> Any:
    """Parse YAML ``text``; a syntax error becomes a :class:`ConfigError` naming the line."""
    try:
        return yaml.load(text, Loader=_Loader)
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        lines = text.splitlines()
        line = mark.line if mark is not None and mark.line < len(lines) else len(lines) - 1
        raise ConfigError(None, lines[line].strip() if lines else text,
                          f"valid YAML ({exc.problem or exc.context})", source, line=line + 1) from None
    except yaml.YAMLError as exc:
        raise ConfigError(None, text, f"valid YAML ({exc})", source) from None


def read_yaml(path: Any, source: str | None = None) -> Any:
    """Read and parse a YAML file; errors name ``source`` (default: the path as given)."""
    source = str(path) if source is None else source
    try:
        text = (path if hasattr(path, "read_text") else Path(path)).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        reason = getattr(exc, "strerror", None) or exc
        raise ConfigError(None, str(path), "a readable YAML file", source,
                          got=f"{str(path)!r} ({reason})") from None
    return parse_yaml(text, source)


# ---------------------------------------------------------------------------- schema

@dataclass(frozen=True)
class Field:
    """One leaf of a schema: its default and the values it admits.

    ``kind`` is ``float``, ``int``, ``bool``, ``str`` or a tuple of allowed
    strings; numbers must be finite and satisfy ``lo``/``hi`` (excluded when
    ``lo_open``/``hi_open``); ``size`` makes it a list of that many;
    ``nullable`` admits ``None``.
    """

    default: Any
    kind: Any = float
    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    hi_open: bool = False
    size: int | None = None
    nullable: bool = False

    def describe(self) -> str:
        """What the field admits, in words (the ``expected`` part of an error)."""
        if isinstance(self.kind, tuple):
            text = "one of " + ", ".join(repr(k) for k in self.kind)
        elif self.kind is bool:
            text = "true or false"
        elif self.kind is str:
            text = "a string"
        else:
            noun = "number" if self.kind is float else "integer"
            article = "a" if self.kind is float else "an"
            text = f"a list of {self.size} {noun}s" if self.size else f"{article} {noun}"
            text += self._bounds()
        return f"null or {text}" if self.nullable else text

    def _bounds(self) -> str:
        lo_op, hi_op = ("<" if self.lo_open else "<="), ("<" if self.hi_open else "<=")
        if self.lo is not None and self.hi is not None:
            return f" with {self.lo:g} {lo_op} x {hi_op} {self.hi:g}"
        if self.lo is not None:
            return f" {'>' if self.lo_open else '>='} {self.lo:g}"
        return f" {hi_op} {self.hi:g}" if self.hi is not None else ""

    def _admits(self, v: Any) -> bool:
        if isinstance(self.kind, tuple):
            return isinstance(v, str) and v in self.kind
        if self.kind in (bool, str):
            return isinstance(v, self.kind)
        number = isinstance(v, numbers.Integral if self.kind is int else numbers.Real)
        if not number or isinstance(v, bool) or not math.isfinite(v):
            return False
        below = self.lo is not None and (v <= self.lo if self.lo_open else v < self.lo)
        above = self.hi is not None and (v >= self.hi if self.hi_open else v > self.hi)
        return not (below or above)

    def check(self, value: Any, key: str, source: str = "<config>") -> Any:
        """``value`` normalised (``float`` or ``int``, lists as lists); else raise :class:`ConfigError`."""
        if value is None and self.nullable:
            return None
        items = value if self.size else [value]
        if self.size and not (isinstance(value, (list, tuple)) and len(value) == self.size):
            items = None
        if items is None or not all(self._admits(v) for v in items):
            suggestion = close_match(value, self.kind) if isinstance(self.kind, tuple) else None
            raise ConfigError(key, value, self.describe(), source, suggestion)
        cast = self.kind if self.kind in (float, int) else (lambda v: v)
        return [cast(v) for v in items] if self.size else cast(value)


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
        "map": Field([36, 72], int, lo=1, size=2),        # polar x azimuth bins
        "amplification": Field(1.0, lo=0.0),
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

#: Relations between fields, checked after each field on its own: (key, op, other).
_RELATIONS = [
    *((f"joints.{j}.clearance", "<", f"joints.{j}.socket_radius") for j in ("A", "B")),
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
    return yaml.dump(dict(cfg), Dumper=_Dumper, sort_keys=False, default_flow_style=False)


def resolve_materials(cfg: Mapping[str, Any]) -> dict[str, Any]:
    """Materials available to ``cfg``: the shipped ones and its ``materials_file``.

    Returns
    -------
    dict[str, clearsweep.materials.Material]
    """
    from .materials import load_materials  # materials imports this module

    return load_materials(cfg.get("materials_file"))
