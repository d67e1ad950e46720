"""Errors a user can fix in a case file: one line naming the file, the key path and the problem.

    cases/x.yaml: contacts[2].between[1]: node group 'clip_99' not in mesh (available: clip_1, …)

The CLI prints ``str(error)`` on one line and exits with code 2 (no traceback unless ``--debug``).
"""
from __future__ import annotations

EXIT_CASE_ERROR = 2
EXIT_NOT_CONVERGED = 3
# output.target_dba exceeded at the loudest converged point (as the batch gate's 4). Precedence of
# `sarfe solve`: 1 internal and 2 input errors first (nothing solved); then 4 — an exceeded target
# is established by converged points, and a point that did not converge could only be louder; then
# 3 — an incomplete run cannot declare a target met; else 0.
EXIT_TARGET_EXCEEDED = 4


def format_key_path(path) -> str:
    """Key path as written in a case file: ('contacts', 2, 'between', 1) → 'contacts[2].between[1]'."""
    text = ""
    for part in path:
        if isinstance(part, int):
            text += f"[{part}]"
        else:
            text += ("." if text else "") + str(part)
    return text


def line_of(lines: dict, path) -> int | None:
    """1-based line of the deepest key of ``path`` that ``lines`` ({key path tuple: line}, from
    :func:`sarfe.case.read.read_yaml`) knows; None when it knows none."""
    path = tuple(path)
    while path and path not in lines:
        path = path[:-1]
    return lines.get(path) if path else None


class CaseError(ValueError):
    """A problem in a case file (or a file it refers to) that the user must fix.

    ``source``: the case file (or '<dict>'); ``key_path``: tuple of keys/indices or a string;
    ``line``: 1-based line in the YAML file when known. ``str(error)`` is a single line.
    """

    def __init__(self, message: str, key_path=(), source=None, line=None):
        self.message = " ".join(str(message).split())  # never multi-line
        self.key_path = key_path if isinstance(key_path, str) else format_key_path(key_path)
        self.source = source
        self.line = line
        super().__init__(self.__str__())

    def located(self, source=None, line=None) -> "CaseError":
        """Same error with the file (and line) filled in where still unknown."""
        return CaseError(self.message, self.key_path, self.source or source, self.line or line)

    def __str__(self) -> str:
        parts = [p for p in (self.source, self.key_path) if p]
        text = ": ".join(parts + [self.message])
        if self.line:
            text += f" (line {self.line})"
        return text
