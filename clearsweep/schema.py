"""Leaf of the configuration: fields, bounded YAML reading, errors with close matches.

Shared by :mod:`clearsweep.config` (the case schema) and :mod:`clearsweep.materials`
(the materials files), which therefore do not import each other. Imports nothing
from clearsweep.

YAML is read with PyYAML's safe loader, extended so that a float written
without a dot (``1e-5``) is a number, as in YAML 1.2, and not a string, and
bounded: a file of at most :data:`MAX_YAML_BYTES`, :data:`MAX_YAML_ALIASES`
aliases, :data:`MAX_YAML_DEPTH` levels of nesting and
:data:`MAX_YAML_VALUES` values with aliases expanded (an "alias bomb" of a
kilobyte would otherwise stand for billions of values); a key given twice in
one mapping is an error, not "the last one wins".
"""

from __future__ import annotations

import difflib
import math
import numbers
import os
import re
import stat
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

__all__ = ["ConfigError", "Field", "close_match", "close_matches", "short_repr", "parse_yaml",
           "read_yaml", "special_file", "dump_yaml", "MAX_YAML_BYTES", "MAX_YAML_ALIASES", "MAX_YAML_DEPTH",
           "MAX_YAML_VALUES", "MAX_INTEGER", "oversized_number", "oversized_text", "OVERSIZED",
           "ClearsweepWarning"]


class ClearsweepWarning(UserWarning):
    """A warning of clearsweep's own, in its words (the CLI prints it as one
    ``clearsweep: warning: ...`` line); a library's warning that clearsweep explains is
    replaced by one of these."""

#: Largest integer a config holds (int64, as the results files store it): YAML reads an
#: integer of any length, and one beyond a float64 (400 digits) stopped ``math.isfinite``
#: with an OverflowError traceback.
MAX_INTEGER = 2**63 - 1

#: What an oversized number is refused with (the ``expected`` words).
OVERSIZED = "integers of at most 2^63 - 1 in magnitude (a larger number is written as a float: 1e30)"


def oversized_number(value: Any) -> Any:
    """The first integer in ``value`` (a number, or lists and mappings of them) beyond
    :data:`MAX_INTEGER` in magnitude, else None: YAML reads integers of any length, and
    one of 400 digits cannot become a float64 or an int64."""
    if isinstance(value, bool):
        return None
    if isinstance(value, int):
        return value if abs(value) > MAX_INTEGER else None
    if isinstance(value, (list, tuple)):
        items: Iterable[Any] = value
    elif isinstance(value, dict):
        items = [*value.keys(), *value.values()]
    else:
        return None
    for item in items:
        found = oversized_number(item)
        if found is not None:
            return found
    return None


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


def oversized_text(value: int) -> str:
    """An oversized integer in words: its first digits and its length."""
    text = str(abs(value))
    return f"{'-' if value < 0 else ''}{text[:12]}... (an integer of {len(text)} digits)"


def close_matches(word: Any, options: Iterable[Any], n: int = 1) -> list[str]:
    """Up to ``n`` options closest to ``word``, best first (case-insensitive, :mod:`difflib`);
    an option equal to ``word`` but for case comes first. The one close-match rule of every
    "did you mean" in clearsweep (config keys and values, materials, sweep keys, reports)."""
    by_lower = {str(o).lower(): str(o) for o in options}
    word = str(word).lower()
    exact = [by_lower[word]] if word in by_lower else []
    hits = difflib.get_close_matches(word, [o for o in by_lower if o != word], n=n, cutoff=0.6)
    return (exact + [by_lower[h] for h in hits])[:n]


def close_match(word: Any, options: Iterable[Any]) -> str | None:
    """The option closest to ``word`` (:func:`close_matches`), or ``None``."""
    hits = close_matches(word, options, n=1)
    return hits[0] if hits else None


# ---------------------------------------------------------------------------- YAML

#: Largest YAML file or text read [bytes]; configs, sweeps and materials files are far smaller.
MAX_YAML_BYTES = 1 << 20
#: Most aliases (``*name``) in one document.
MAX_YAML_ALIASES = 100
#: Deepest nesting of mappings and lists.
MAX_YAML_DEPTH = 32
#: Most values (scalars, lists, mappings) in one document with every alias expanded:
#: a few aliases can otherwise stand for billions of values ("billion laughs").
MAX_YAML_VALUES = 100_000


class _Refused(yaml.YAMLError):
    """A YAML document outside the limits, or with a duplicate key (turned into ConfigError)."""

    def __init__(self, got: str, expected: str, line: int | None = None):
        super().__init__(got)
        self.got, self.expected, self.line = got, expected, line


class _Loader(yaml.SafeLoader):
    """Safe loader that also reads ``1e-5`` (no dot) as a float, within limits.

    Refuses (:class:`_Refused`) more than :data:`MAX_YAML_ALIASES` aliases,
    nesting deeper than :data:`MAX_YAML_DEPTH`, more than
    :data:`MAX_YAML_VALUES` values once aliases are expanded, and a key given
    twice in one mapping (PyYAML would keep the last one silently).
    """

    def __init__(self, stream):
        super().__init__(stream)
        self._aliases = 0
        self._depth = 0

    def compose_node(self, parent, index):
        if self.check_event(yaml.AliasEvent):
            self._aliases += 1
            if self._aliases > MAX_YAML_ALIASES:
                event = self.peek_event()
                raise _Refused(f"more than {MAX_YAML_ALIASES} aliases (*{event.anchor})",
                               f"at most {MAX_YAML_ALIASES} aliases", event.start_mark.line + 1)
            return super().compose_node(parent, index)
        self._depth += 1
        try:
            if self._depth > MAX_YAML_DEPTH:
                raise _Refused(f"mappings and lists nested more than {MAX_YAML_DEPTH} deep",
                               f"at most {MAX_YAML_DEPTH} levels of nesting",
                               self.peek_event().start_mark.line + 1)
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1

    def get_single_node(self):
        node = super().get_single_node()
        if node is not None:
            _count_values(node)
        return node

    def construct_mapping(self, node, deep=False):
        if isinstance(node, yaml.MappingNode):
            first: dict[Any, int] = {}
            for key_node, _ in node.value:
                if not isinstance(key_node, yaml.ScalarNode) or key_node.tag == "tag:yaml.org,2002:merge":
                    continue
                key = self.construct_object(key_node)
                line = key_node.start_mark.line + 1
                try:
                    if key in first:
                        raise _Refused(f"the key {key!r} a second time (first on line {first[key]})",
                                       "each key once in a mapping", line)
                    first[key] = line
                except TypeError:       # an unhashable key: left to PyYAML's own error
                    continue
        return super().construct_mapping(node, deep)


def _count_values(root: yaml.Node) -> int:
    """Values in the document under ``root`` with every alias expanded; refuse too many.

    Aliases make the node graph a DAG; each node's expanded count is computed
    once, so this costs the size of the file, not of the expansion.
    """
    counts: dict[int, int] = {}

    def count(node: yaml.Node) -> int:
        if id(node) in counts:
            return counts[id(node)]
        total = 1
        if isinstance(node, yaml.SequenceNode):
            total += sum(count(child) for child in node.value)
        elif isinstance(node, yaml.MappingNode):
            total += sum(count(k) + count(v) for k, v in node.value)
        if total > MAX_YAML_VALUES:
            raise _Refused(f"a document of more than {MAX_YAML_VALUES} values once its aliases "
                           "are expanded", f"at most {MAX_YAML_VALUES} values",
                           node.start_mark.line + 1)
        counts[id(node)] = total
        return total

    return count(root)


class _Dumper(getattr(yaml, "CSafeDumper", yaml.SafeDumper)):  # type: ignore[misc]
    """Safe dumper: sections in block style, lists inline, strings quoted where ``_Loader`` needs.

    libyaml's emitter where PyYAML has it: every case of a sweep carries its config's text,
    and the pure-Python emitter took a third of a small case's time outside the kernel."""


_Dumper.add_representer(list, lambda dumper, value: dumper.represent_sequence(
    "tag:yaml.org,2002:seq", value, flow_style=True))
_FLOAT_WITHOUT_DOT = re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9][0-9_]*)[eE][-+]?[0-9]+$")
_Loader.add_implicit_resolver("tag:yaml.org,2002:float", _FLOAT_WITHOUT_DOT, list("-+0123456789."))
_Dumper.add_implicit_resolver("tag:yaml.org,2002:float", _FLOAT_WITHOUT_DOT, list("-+0123456789."))
# No config or materials value is a date: 2020-01-01 reads as text (an error then names
# '2020-01-01', not datetime.date(2020, 1, 1)).
_Loader.yaml_implicit_resolvers = {
    first: [(tag, regexp) for tag, regexp in resolvers if tag != "tag:yaml.org,2002:timestamp"]
    for first, resolvers in _Loader.yaml_implicit_resolvers.items()}


def dump_yaml(data: Any) -> str:
    """YAML text of ``data`` in its own key order; :func:`parse_yaml` reads it back as it was."""
    return yaml.dump(data, Dumper=_Dumper, sort_keys=False, default_flow_style=False)


def parse_yaml(text: str, source: str = "<config>") -> Any:
    """Parse YAML ``text`` within the limits of :class:`_Loader`.

    A syntax error, a duplicate key, or text beyond the limits (size, aliases,
    nesting, expanded values) becomes a :class:`ConfigError` naming the line.
    """
    if len(text) > MAX_YAML_BYTES:
        raise ConfigError(None, None, f"YAML text of at most {MAX_YAML_BYTES} bytes", source,
                          got=f"{len(text)} characters")
    try:
        return yaml.load(text, Loader=_Loader)
    except _Refused as exc:
        raise ConfigError(None, None, exc.expected, source, got=exc.got, line=exc.line) from None
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        lines = text.splitlines()
        line = mark.line if mark is not None and mark.line < len(lines) else len(lines) - 1
        raise ConfigError(None, lines[line].strip() if lines else text,
                          f"valid YAML ({exc.problem or exc.context})", source, line=line + 1) from None
    except yaml.YAMLError as exc:
        raise ConfigError(None, text, f"valid YAML ({exc})", source) from None
    except RecursionError:      # nesting the depth limit did not catch (a deep key)
        raise ConfigError(None, None, f"at most {MAX_YAML_DEPTH} levels of nesting", source,
                          got="nesting too deep to read") from None


#: What a file that is not a regular file is, by ``stat.S_IFMT`` of its mode.
_SPECIAL_FILES = {stat.S_IFIFO: "a FIFO", stat.S_IFCHR: "a character device",
                  stat.S_IFBLK: "a block device", stat.S_IFSOCK: "a socket",
                  stat.S_IFDIR: "a folder"}


def special_file(mode: int) -> str | None:
    """What a file of ``st_mode`` ``mode`` is when it is not a regular file (``"a FIFO"``),
    else None: a command refuses such an input at once, where reading it would wait for a
    writer (a FIFO) or never end (``/dev/zero``)."""
    return None if stat.S_ISREG(mode) else _SPECIAL_FILES.get(stat.S_IFMT(mode), "not a regular file")


def _open_regular(path: Path):
    """``path`` opened for reading, refused (OSError) unless it is a regular file: opened
    without blocking, so that a FIFO with no writer is refused, not waited on."""
    fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    try:
        kind = special_file(os.fstat(fd).st_mode)
        if kind is not None:
            raise OSError(f"{kind}, not a regular file")
        os.set_blocking(fd, True)
        return os.fdopen(fd, "rb")
    except BaseException:
        os.close(fd)
        raise


#: The first bytes of a netCDF file (classic, 64-bit offset, netCDF-4/HDF5).
NETCDF_MAGIC = (b"CDF\x01", b"CDF\x02", b"CDF\x05", b"\x89HDF")


def read_yaml(path: Any, source: str | None = None) -> Any:
    """Read and parse a YAML file (at most :data:`MAX_YAML_BYTES`; a regular file, not a
    FIFO or a device); errors name ``source``."""
    source = str(path) if source is None else source
    try:
        with (path.open("rb") if hasattr(path, "open") and not isinstance(path, Path)
              else _open_regular(Path(path))) as f:
            data = f.read(MAX_YAML_BYTES + 1)
        if data[:4] in NETCDF_MAGIC:
            raise ConfigError(None, str(path), "a YAML config (this is a netCDF results file: "
                              "`clearsweep report` and `clearsweep plot` read results)", source,
                              got=f"{str(path)!r}")
        if len(data) > MAX_YAML_BYTES:
            raise ConfigError(None, str(path), f"a YAML file of at most {MAX_YAML_BYTES} bytes",
                              source, got=f"{str(path)!r} (more than {MAX_YAML_BYTES} bytes)")
        text = data.decode("utf-8")
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
        if self.kind in (float, int) and oversized_number(value) is not None:
            raise ConfigError(key, value, f"{self.describe()}; {OVERSIZED}", source,
                              got=oversized_text(oversized_number(value)))
        items = value if self.size else [value]
        if self.size and not (isinstance(value, (list, tuple)) and len(value) == self.size):
            items = None
        if items is None or not all(self._admits(v) for v in items):
            suggestion = close_match(value, self.kind) if isinstance(self.kind, tuple) else None
            raise ConfigError(key, value, self.describe(), source, suggestion)
        cast = self.kind if self.kind in (float, int) else (lambda v: v)
        return [cast(v) for v in items] if self.size else cast(value)
