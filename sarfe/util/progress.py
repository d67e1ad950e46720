"""Progress of a solve: a live tqdm bar on a terminal, one line per stage in logs.

    bar(progress, description, total, unit) -> tqdm | StageLine | None

On a terminal (stderr is a TTY) a tqdm bar (linear stage, Craig–Bampton blocks, frequency points,
error estimates). Otherwise — a log file, CI, a pipe — a :class:`StageLine` that writes one line
``sarfe: <stage> …`` to stderr when the stage starts (and when its description changes), so
``sarfe solve`` never sits silent for a minute in a log either. ``progress=False``: None.
"""
from __future__ import annotations

import sys


class StageLine:
    """The tqdm calls the pipeline makes (update, set_description, close), as one log line per
    stage on stderr."""

    def __init__(self, description, total=None, unit="", stream=None):
        self.stream = stream if stream is not None else sys.stderr
        self.total = total if unit in ("point", "variant") else None
        self.unit, self.n = unit, 0
        self.set_description(description)

    def set_description(self, description, refresh=True):
        size = f" ({self.total} {self.unit}{'s' if self.total != 1 else ''})" if self.total else ""
        print(f"sarfe: {description}{size} …", file=self.stream, flush=True)

    def update(self, n=1):
        self.n += n       # as tqdm's count

    def set_postfix(self, *args, **kwargs):
        pass

    def close(self):
        pass


def bar(progress, description, total=None, unit="block"):
    """A progress indicator for one stage (module docstring) or None."""
    if not progress:
        return None
    if not sys.stderr.isatty():
        return StageLine(description, total, unit)
    from tqdm import tqdm

    return tqdm(total=total, desc=description, unit=unit, leave=False, file=sys.stderr)
