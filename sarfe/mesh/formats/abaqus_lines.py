"""Abaqus ``.inp`` files as keyword blocks: the lexing under :mod:`sarfe.mesh.formats.abaqus`.

A keyword line ``*KEYWORD, OPTION=value, FLAG`` (continued when it ends in ',') opens a
:class:`KeywordBlock`; its data lines are split at commas (an ``*ELEMENT`` data line ending in ','
continues on the next line); ``**`` comment lines and blank lines are skipped;
``*INCLUDE, INPUT=<file>`` inlines the file (relative to the including one); text lines before the
first keyword (a preamble such as ``>**``) are skipped, numeric ones refused. Every block and data
line keeps its file and line number for messages ("plate.inp:47: *SHELL SECTION: …").
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from sarfe.mesh.formats.deck import DeckError


@dataclass(frozen=True)
class KeywordBlock:
    """One keyword with its options and data lines: data = [(fields, file, line), …]."""

    keyword: str                 # upper case, single spaces, no '*'
    options: dict                # {OPTION: value or True}
    data: list
    file: str
    line: int

    def where(self, line=None) -> str:
        return f"{self.file}:{line or self.line}: *{self.keyword}"


def read_lines(path: Path, stack=()):
    """(file, line number, text) of every line, ``*INCLUDE, INPUT=`` files inlined."""
    path = Path(path)
    if path.resolve() in stack:
        raise DeckError(f"{path}: *INCLUDE of itself (include loop)")
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError as exc:
        raise DeckError(f"cannot read {path}: {exc.strerror or exc}") from None
    for number, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        if stripped.upper().startswith("*INCLUDE"):
            options = parse_options(stripped[1:].split(",")[1:])
            name = options.get("INPUT")
            if not isinstance(name, str):
                raise DeckError(f"{path}:{number}: *INCLUDE needs INPUT=<file>")
            target = Path(name.strip("'\"")) if Path(name).is_absolute() else path.parent / name.strip("'\"")
            if not target.is_file():
                raise DeckError(f"{path}:{number}: *INCLUDE file not found: {target}")
            yield from read_lines(target, stack + (path.resolve(),))
        else:
            yield str(path), number, line


def parse_options(parts) -> dict:
    options = {}
    for part in parts:
        part = part.strip()
        if not part:
            continue
        key, _, value = part.partition("=")
        options[" ".join(key.split()).upper()] = value.strip() if value else True
    return options


def keyword_blocks(path: Path):
    """Keyword blocks of a file; keyword and data lines ending in ',' continue."""
    block, pending = None, None
    for file, number, line in read_lines(path):
        text = line.strip()
        if not text or text.startswith("**"):
            continue
        if pending is not None:                     # continued keyword line
            pending = (pending[0] + text, pending[1], pending[2])
        elif text.startswith("*"):
            if block is not None:
                yield block
            block = None
            pending = (text, file, number)
        else:
            if block is None:
                if _numeric(text):     # numbers before any keyword: a file cut at its head
                    raise DeckError(f"{file}:{number}: data line before any keyword: "
                                    f"{text[:40]!r}")
                continue               # a preamble line (e.g. '>**' of some writers): no data
            fields = [f.strip() for f in text.split(",")]
            if block.data and block.data[-1][0] and block.data[-1][0][-1] == "" \
                    and block.keyword == "ELEMENT":     # element line continued after ','
                block.data[-1] = (block.data[-1][0][:-1] + fields, block.data[-1][1],
                                  block.data[-1][2])
            else:
                block.data.append((fields, file, number))
            continue
        if pending[0].endswith(","):
            continue
        text, file, number = pending
        pending = None
        head, *rest = text[1:].split(",")
        block = KeywordBlock(" ".join(head.split()).upper(), parse_options(rest), [], file, number)
    if block is not None:
        yield block


def _numeric(text: str) -> bool:
    """Whether a line's first field is a number (a data line, not a preamble)."""
    try:
        float(text.split(",")[0].replace("d", "e").replace("D", "E"))
    except ValueError:
        return False
    return True


def trimmed(fields):
    return fields[:-1] if fields and fields[-1] == "" else fields


def parse_number(text, block, line, what="value"):
    try:
        return float(text.replace("d", "e").replace("D", "E"))
    except ValueError:
        raise DeckError(f"{block.where(line)}: {what} {text!r} is not a number") from None


def parse_label(text, block, line):
    try:
        return int(text)
    except ValueError:
        raise DeckError(f"{block.where(line)}: {text!r} is not an integer id") from None

