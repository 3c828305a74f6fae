"""The commands of the docs and the README never overwrite a tracked file (issue 45 item 7):
each writes to a working folder (``results/``, ignored by git). A command that regenerates
a tracked figure on purpose says ``--overwrite`` and stands under a heading "Regenerate the
docs figures" (docs/gallery.md's convention: docs/runs.md, "Docs commands"). And the plot
kinds docs/runs.md lists are the ones the CLI accepts."""

from __future__ import annotations

import re
import shlex
import subprocess
from pathlib import Path

import pytest

from clearsweep.choices import KINDS

ROOT = Path(__file__).resolve().parents[1]
PAGES = sorted((ROOT / "docs").glob("*.md")) + [ROOT / "README.md"]
#: The heading under which a command may regenerate a tracked file (with ``--overwrite``).
REGENERATE_HEADING = "regenerate the docs figures"
#: The options that name a file a command writes.
OUTPUT_OPTIONS = ("-o", "--out", "--output")
_PROGRAM = re.compile(r"^(\S*/)?(clearsweep|python3?)\b")
_FENCE = re.compile(r"^(\s*)(```|~~~)\s*\{?(\w*)\}?")
_INLINE = re.compile(r"`((?:\S*/)?clearsweep [^`]+)`")
_SHELL = ("", "bash", "sh", "shell", "console", "text")


def commands(text: str) -> list[tuple[int, str, bool]]:
    """``(line number, command, under the regenerate heading)`` of every shell command of a
    Markdown page: the lines of fenced shell blocks and of indented code blocks that run
    ``clearsweep`` or ``python``, and inline ```clearsweep ...``` code."""
    out = []
    heading = ""
    fence: str | None = None
    shell = False
    previous_blank = True
    for number, line in enumerate(text.splitlines(), 1):
        match = _FENCE.match(line)
        if fence is None and match:
            fence, shell = match.group(2), match.group(3).lower() in _SHELL
            continue
        if fence is not None:
            if line.strip().startswith(fence):
                fence = None
            elif shell:
                stripped = line.strip().removeprefix("$ ")
                if _PROGRAM.match(stripped):
                    out.append((number, stripped, REGENERATE_HEADING in heading))
            continue
        if line.startswith("#"):
            heading = line.lower()
        indented = line.startswith("    ") and (previous_blank or out and out[-1][0] == number - 1)
        if indented and _PROGRAM.match(line.strip()):
            out.append((number, line.strip(), REGENERATE_HEADING in heading))
        else:
            out += [(number, m.group(1), REGENERATE_HEADING in heading)
                    for m in _INLINE.finditer(line)]
        previous_blank = not line.strip()
    return out


def outputs(command: str) -> list[str]:
    """The paths a command's ``-o``/``--out`` options name."""
    try:
        words = shlex.split(command, comments=True)
    except ValueError:
        words = command.split()
    found = []
    for i, word in enumerate(words):
        name, sep, value = word.partition("=")
        if name in OUTPUT_OPTIONS and sep:
            found.append(value)
        elif word in OUTPUT_OPTIONS and i + 1 < len(words):
            found.append(words[i + 1])
    return found


def tracked() -> set[str]:
    listing = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True,
                             check=True).stdout
    return set(listing.split())


def test_the_extraction_finds_fenced_indented_and_inline_commands():
    page = ("Run `clearsweep run a.yaml -o out.nc` first.\n\n"
            "```bash\n.venv/bin/clearsweep plot out.nc --kind slider -o docs/figures/x.png\n```\n\n"
            "    .venv/bin/clearsweep sweep s.yaml --out=results/s.nc\n\n"
            "## Regenerate the docs figures\n\n"
            "    clearsweep plot r.nc --kind sweep -o docs/figures/y.png --overwrite\n")
    found = commands(page)
    assert [(n, regenerate) for n, _, regenerate in found] == [(1, False), (4, False), (7, False),
                                                                (11, True)]
    assert [outputs(c) for _, c, _ in found] == [["out.nc"], ["docs/figures/x.png"],
                                                 ["results/s.nc"], ["docs/figures/y.png"]]


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_no_docs_command_overwrites_a_tracked_file(page):
    files = tracked()
    problems = []
    for number, command, regenerate in commands(page.read_text(encoding="utf-8")):
        for path in outputs(command):
            if path not in files:
                continue
            if not regenerate:
                problems.append(f"line {number}: {command!r} writes the tracked {path}; write "
                                "to results/ (or move it under a 'Regenerate the docs figures' "
                                "heading, with --overwrite)")
            elif "--overwrite" not in command.split():
                problems.append(f"line {number}: {command!r} regenerates {path} without "
                                "--overwrite")
    assert problems == []


def test_the_docs_pages_hold_commands():
    """The extraction reads the commands the pages show (not an empty list that passes)."""
    found = {page.name: commands(page.read_text(encoding="utf-8")) for page in PAGES}
    assert any(outputs(c) for _, c, _ in found["mixed_clearances.md"])
    assert any(outputs(c) for _, c, _ in found["README.md"])


def test_runs_md_lists_the_plot_kinds_the_cli_accepts():
    text = (ROOT / "docs" / "runs.md").read_text(encoding="utf-8")
    match = re.search(r"draws one figure from a results file; the kinds\s*\(([^)]*)\)", text)
    assert match, "docs/runs.md: the sentence listing the plot kinds is gone"
    listed = re.findall(r"`([\w-]+)`", match.group(1))
    assert sorted(listed) == sorted(KINDS)
