"""Documentation claims that can be checked without running the kernel: every figure the
docs show exists and is made by a command in the repository, and the docs refer to nothing
outside the repository."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def test_every_committed_figure_is_made_by_a_command():
    """Each PNG under docs/figures is named by a plot command in README.md or a docs page, or
    by a docs/*.py script that writes it."""
    pages = "\n".join(doc.read_text() for doc in DOCS)
    scripts = "\n".join(p.read_text() for p in (ROOT / "docs").glob("*.py"))
    for png in (ROOT / "docs" / "figures").rglob("*.png"):
        rel = png.relative_to(ROOT).as_posix()
        in_readme = f"-o {rel}" in pages
        in_script = png.name in scripts
        assert in_readme or in_script, f"{rel}: no command in the repository makes it"


def test_figures_linked_from_the_docs_exist():
    for doc in DOCS:
        for target in re.findall(r"\]\(([^)\s]+\.png)\)", doc.read_text()):
            assert (doc.parent / target).is_file(), f"{doc.name}: {target} is missing"


def test_docs_refer_to_nothing_outside_the_repository():
    for doc in DOCS:
        text = doc.read_text()
        # named references outside the repository: tests/test_layout.py checks every file
        for target in re.findall(r"\]\(([^)\s#]+)", text):
            if target.startswith(("http://", "https://")):
                continue
            assert (doc.parent / target).resolve().is_relative_to(ROOT), (doc.name, target)
            assert (doc.parent / target).exists(), (doc.name, target)


def test_physics_sections_are_numbered_1_to_11():
    text = (ROOT / "docs" / "physics.md").read_text()
    numbers = [int(n) for n in re.findall(r"^## (\d+)\. ", text, re.M)]
    assert numbers == list(range(1, 12))
