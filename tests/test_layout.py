"""The repository's layout rules that no linter checks (import-linter guards the imports)."""

import ast
import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "clearsweep"

#: A reference to something outside the repository: the old design spec (now
#: docs/physics.md) or the shared folder beside the checkout.
OUTSIDE = re.compile(r"DESIGN|\bshared/")
#: The test that holds the repository to this rule names what it looks for.
CHECKERS = ("tests/test_layout.py",)


def _tracked() -> list[str]:
    try:
        out = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True, check=True)
    except (OSError, subprocess.CalledProcessError):
        pytest.skip("not a git checkout")
    return out.stdout.split()


def test_no_file_refers_outside_the_repository():
    found = []
    for name in _tracked():
        if name in CHECKERS:
            continue
        try:
            text = (ROOT / name).read_text(encoding="utf-8")
        except (UnicodeDecodeError, OSError):
            continue
        found += [f"{name}:{i}: {line.strip()}" for i, line in enumerate(text.splitlines(), 1)
                  if OUTSIDE.search(line)]
    assert not found, "cite docs/physics.md section N instead:\n" + "\n".join(found)


def test_click_is_imported_by_cli_only():
    users = [p.relative_to(ROOT).as_posix() for p in PACKAGE.rglob("*.py")
             if p.name != "cli.py" and any(
                 isinstance(n, (ast.Import, ast.ImportFrom)) and "click" in (
                     [a.name for a in n.names] if isinstance(n, ast.Import) else [n.module or ""])
                 for n in ast.walk(ast.parse(p.read_text())))]
    assert not users, f"click commands belong in cli.py: {users}"
