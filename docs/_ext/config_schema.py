"""Writes the configuration-schema page from the typed config's field metadata.

Each leaf of :class:`clearsweep.config.Config` is a dataclass field whose metadata holds
its rule (:class:`clearsweep.schema.Field`), units (UDUNITS) and long name; the page lists
them with their defaults, section by section, at every build. Nothing in it is written by
hand, so it cannot drift from the code.
"""

from __future__ import annotations

from dataclasses import MISSING, fields
from pathlib import Path

PAGE = "config_schema.md"

HEADER = """\
# Configuration schema

Every key a case configuration accepts, with its default, the values it admits, its units
and its long name. This page is generated at each documentation build from the field
metadata of the typed configuration (`clearsweep.config.Config`), the same metadata that
validation, error messages and the units of sweep coordinates read; it is never edited by
hand. Keys are the dotted paths of `--set`, sweep axes and error messages; `joints.X`
stands for both `joints.A` and `joints.B`. How a configuration is written and checked:
[Configurations](configs.md).
"""


def _value(v) -> str:
    if v is None:
        return "`null`"
    if isinstance(v, bool):
        return "`true`" if v else "`false`"
    if isinstance(v, tuple):
        return "`[" + ", ".join(_value(x).strip("`") for x in v) + "]`"
    return f"`{v}`"


def _cell(text) -> str:
    return "" if text is None else str(text).replace("|", "\\|")


def _rows(cls: type, prefix: str) -> list[tuple[str, list[str]]]:
    """``(section, [table row, ...])`` for ``cls`` and its subsections, in field order."""
    from clearsweep.config import JointConfig

    own: list[str] = []
    nested: list[tuple[str, list[str]]] = []
    for f in fields(cls):
        if f.default_factory is not MISSING:
            sub = f.default_factory
            if sub is JointConfig:
                if f.name == "A":     # one table for both joints
                    nested += _rows(sub, prefix + "X.")
                continue
            nested += _rows(sub, f"{prefix}{f.name}.")
            continue
        rule = f.metadata["field"]
        units = f.metadata["units"]
        own.append(f"| `{prefix}{f.name}` | {_value(f.default)} | {_cell(rule.describe())} | "
                   f"{'`' + units + '`' if units else ''} | {_cell(f.metadata['long_name'])} |")
    section = prefix.rstrip(".") or "top level"
    return ([(section, own)] if own else []) + nested


def schema_markdown() -> str:
    """The page's Markdown text."""
    from clearsweep.config import Config

    parts = [HEADER]
    for section, rows in _rows(Config, ""):
        parts.append(f"\n## `{section}`\n" if section != "top level" else "\n## Top level\n")
        parts.append("| key | default | admits | units | long name |\n|---|---|---|---|---|")
        parts.extend(rows)
    return "\n".join(parts) + "\n"


def write_page(app) -> None:
    """``builder-inited``: write the page into the source folder, only when it changed."""
    path = Path(app.srcdir) / PAGE
    text = schema_markdown()
    if not path.exists() or path.read_text() != text:
        path.write_text(text)


def setup(app):
    app.connect("builder-inited", write_page)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
