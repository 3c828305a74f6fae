"""The check that a script starting worker processes keeps its work under ``if __name__ == "__main__":``.

A pool worker (``forkserver`` or ``spawn``) starts by importing the script that
started the pool, under the name ``__mp_main__``. A script whose sweep call is
not guarded would start the sweep again in every worker: the workers die, every
case fails, and the run takes many times as long. :func:`require_main_guard`
stops that before anything starts.
"""

from __future__ import annotations

import ast
import sys
from pathlib import Path
from types import FrameType

#: The advice every refusal ends with.
ADVICE = ('put the script\'s work under `if __name__ == "__main__":` (the README\'s Python '
          'example shows it), or pass workers=1')


class UnguardedScript(RuntimeError):
    """Worker processes were asked for from a script's top level, outside ``if __name__ == "__main__":``."""


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


def _top_level_frame(main_globals: dict) -> FrameType | None:
    """The frame running the main module's own top-level code, if this call came from it."""
    frame: FrameType | None = sys._getframe(1)
    found = None
    while frame is not None:
        if frame.f_globals is main_globals and frame.f_code.co_name == "<module>":
            found = frame
        frame = frame.f_back
    return found


def require_main_guard(workers: int) -> None:
    """Raise :class:`UnguardedScript` where starting ``workers`` worker processes now would
    re-run the calling script in each of them.

    Two cases: this process is itself a worker re-running a script (its ``__main__`` is
    ``__mp_main__``), or the call comes from the top level of a script file, outside
    ``if __name__ == "__main__":``. An interactive session, ``python -c`` and a call from a
    guarded block pass.
    """
    main = sys.modules.get("__main__")
    if main is None:
        return
    if getattr(main, "__name__", None) == "__mp_main__":
        raise UnguardedScript(
            f"a sweep with {workers} worker processes was started while a worker process was "
            f"importing the script {getattr(main, '__file__', '?')!r}: the script starts its "
            f"work when imported; {ADVICE}")
    path = getattr(main, "__file__", None)
    frame = _top_level_frame(vars(main))
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
