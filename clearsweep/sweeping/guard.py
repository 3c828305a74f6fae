"""The check that a script starting worker processes keeps its work under ``if __name__ == "__main__":``.

A pool worker (``forkserver`` or ``spawn``) starts by importing the script that
started the pool, under the name ``__mp_main__``. A script whose sweep call is
not guarded would start the sweep again in every worker: the workers die, every
case fails, and the run takes many times as long. A script read from standard input
cannot be re-imported at all, and a daemonic ``multiprocessing.Pool`` worker may not
start processes. :func:`require_main_guard` stops these before anything starts, and
lets through what works: a guarded script, a process that ``multiprocessing`` started
(its target runs after the script's import), ``python -c``, an interactive session and
a notebook, whose workers import no script.
"""

from __future__ import annotations

import ast
import os
import sys
from pathlib import Path
from types import FrameType

#: The advice every refusal ends with.
ADVICE = ('put the script\'s work under `if __name__ == "__main__":` (the README\'s Python '
          'example shows it), or pass workers=1')


class UnguardedScript(RuntimeError):
    """Worker processes were asked for where they would fail: from a script's top level,
    outside ``if __name__ == "__main__":``, from a script that a worker cannot re-import
    (read from standard input), or in a daemonic pool worker."""


def _is_main_test(node: ast.expr) -> bool:
    """``__name__ == "__main__"``, either way round."""
    if not (isinstance(node, ast.Compare) and len(node.ops) == 1 and isinstance(node.ops[0], ast.Eq)):
        return False
    sides = [node.left, node.comparators[0]]
    return (any(isinstance(s, ast.Name) and s.id == "__name__" for s in sides)
            and any(isinstance(s, ast.Constant) and s.value == "__main__" for s in sides))


def _guarded(source: str, line: int) -> bool | None:
    """Whether ``line`` of the module ``source`` runs under a ``__main__`` guard (``None``:
    the source cannot be read as Python, or holds no statement at that line)."""
    try:
        tree = ast.parse(source)
    except (SyntaxError, ValueError):
        return None
    for stmt in tree.body:
        if stmt.lineno <= line <= (stmt.end_lineno or stmt.lineno):
            return (isinstance(stmt, ast.If) and _is_main_test(stmt.test)
                    and any(s.lineno <= line <= (s.end_lineno or s.lineno) for s in stmt.body))
    return None


def _top_level_frame(main_globals: dict, filename: str | None = None) -> FrameType | None:
    """The frame running the main module's own top-level code (read from ``filename``, where
    given), if this call came from it."""
    frame: FrameType | None = sys._getframe(1)
    found = None
    while frame is not None:
        if (frame.f_globals is main_globals and frame.f_code.co_name == "<module>"
                and (filename is None or frame.f_code.co_filename == filename)):
            found = frame
        frame = frame.f_back
    return found


def _reimported_from(main) -> str | None:
    """The path a worker process started by ``spawn`` or ``forkserver`` runs as the main
    module before its first case (``multiprocessing.spawn.get_preparation_data``'s rule):
    the main module's ``__file__``, unless it was started by module name (``python -m``);
    ``None`` where a worker imports no script (``python -c``, an interactive session, a
    notebook)."""
    if getattr(getattr(main, "__spec__", None), "name", None) is not None:
        return None
    path = getattr(main, "__file__", None)
    return None if path is None else str(path)


def require_main_guard(workers: int) -> None:
    """Raise :class:`UnguardedScript` where starting ``workers`` worker processes now would
    fail: the workers would re-run the calling script, or could not start at all.

    Refused, before any worker starts:

    - a worker process importing a script (its ``__main__`` is ``__mp_main__``) that asks
      for workers from the script's top level, i.e. while it is imported;
    - a call from the top level of a script file, outside ``if __name__ == "__main__":``;
    - a script that a worker cannot re-import: one read from standard input
      (``python - <<EOF``, ``python < script.py``), or whose file is gone;
    - a daemonic process (a ``multiprocessing.Pool`` worker), which may not start
      processes of its own.

    A process started by ``multiprocessing`` (``spawn``, the default on macOS and Windows)
    that calls a sweep after importing a guarded script, ``python -c``, an interactive
    session, a notebook and a call from a guarded block pass: their workers import no
    script, or one that starts nothing when imported.
    """
    import multiprocessing

    main = sys.modules.get("__main__")
    if main is None:
        return
    # A process started by spawn or forkserver runs the parent's script as ``__mp_main__``
    # (runpy) while multiprocessing's ``_inheriting`` is set, before its target; after that
    # its ``__main__`` is that module, and a sweep its target starts is no import's
    if getattr(multiprocessing.current_process(), "_inheriting", False):
        importing = sys.modules.get("__mp_main__")
        script = getattr(importing, "__file__", None) or getattr(main, "__file__", None)
        raise UnguardedScript(
            f"a sweep with {workers} worker processes was started while a worker process "
            f"was importing the script {script or '?'!r}: the script starts its work "
            f"when imported; {ADVICE}")
    if multiprocessing.current_process().daemon:
        raise UnguardedScript(
            f"a sweep with {workers} worker processes was started in the daemonic process "
            f"{multiprocessing.current_process().name!r} (a multiprocessing.Pool worker), "
            "which may not start processes of its own; pass workers=1 to run the sweep's "
            "cases in this process, or start the sweep outside the pool")
    reimported = _reimported_from(main)
    started_in = getattr(multiprocessing.process, "ORIGINAL_DIR", None) or ""
    if reimported is not None and not os.path.isfile(os.path.join(started_in, reimported)):
        what = ("read from standard input" if reimported == "<stdin>"
                else f"whose file {reimported!r} a worker cannot read")
        raise UnguardedScript(
            f"a sweep with {workers} worker processes was started from a script {what}: each "
            f"worker process starts by re-importing the script from its file; save the script "
            f"to a file and run that (its work under `if __name__ == \"__main__\":`), or pass "
            f"workers=1")
    # a script run from its file, or as a module (python -m: re-imported by name)
    path = getattr(main, "__file__", None)
    frame = None if path is None else _top_level_frame(vars(main), path)
    if path is None or frame is None:
        return
    try:
        source = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return
    if _guarded(source, frame.f_lineno) is False:
        raise UnguardedScript(
            f"a sweep with {workers} worker processes was started from the top level of the "
            f"script {path!r} (line {frame.f_lineno}), outside `if __name__ == \"__main__\":`: "
            f"each worker process starts by re-running the script, which would start the sweep "
            f"again in every worker; {ADVICE}")
