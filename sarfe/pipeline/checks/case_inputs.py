"""Every file a case reads, in one place — so that no output folder ever holds one of them.

    case_inputs(case) -> {Path: what}        the case file, its mesh / deck (+ INCLUDEs) / matrix
                                             / curve files, and any other file a key names
    named_files(data, base_dir) -> {Path: what}   the same for a case mapping (a batch variant)

``what`` says where the file comes from (``the case file``, ``model.fe.deck``, ``an INCLUDE of
model.fe.deck``, ``contacts[0].curve_file`` …): the refusal of an output folder names it
(:func:`sarfe.results.folder.check_output_folder`, ``protected``). Files are found by walking the
case mapping: every string value that names an existing file, relative to the case file's folder
(or absolute), is an input — the known keys (``model.fe.mesh``, ``model.fe.deck``,
``model.matrices.mass|stiffness|damping``, a tabulated contact's ``curve_file``) and any key a later
feature adds (a background spectrum file …) alike; the deck's INCLUDEs are followed
(:func:`sarfe.pipeline.model.deck_model.deck_files`). ``output.directory`` names a folder, never an
input.
"""
from __future__ import annotations

import functools
import os
from pathlib import Path

from sarfe.case.errors import format_key_path
from sarfe.case.read import load_case
from sarfe.pipeline.model.deck_model import deck_files

DECK_PATH = ("model", "fe", "deck")


def _strings(data, path=()):
    """(key path, value) of every string value of a nested mapping / list."""
    if isinstance(data, str):
        yield path, data
    elif isinstance(data, dict):
        for key, value in data.items():
            if path + (key,) != ("output", "directory"):
                yield from _strings(value, path + (key,))
    elif isinstance(data, (list, tuple)):
        for index, value in enumerate(data):
            yield from _strings(value, path + (index,))


def _existing_file(text: str, base_dir: Path) -> Path | None:
    if not text or "\n" in text or len(text) > 4096:
        return None
    try:
        path = Path(text).expanduser()
        path = path if path.is_absolute() else Path(base_dir) / path
        return Path(os.path.normpath(path.absolute())) if path.is_file() else None
    except (OSError, ValueError):       # a name too long, a NUL byte: not a file
        return None


@functools.lru_cache(maxsize=64)
def _includes(deck: str, mtime_ns: int, size: int) -> tuple:
    """The files the deck INCLUDEs (read once per deck version: a batch's variants share it)."""
    return tuple(deck_files(Path(deck))[1:])


def named_files(data: dict, base_dir) -> dict:
    """{absolute path: key path} of every existing file a string value of the case mapping
    ``data`` names (relative to ``base_dir``), with the deck's INCLUDEs (module docstring)."""
    found = {}
    for path, text in _strings(data):
        file = _existing_file(text, Path(base_dir))
        if file is None:
            continue
        found.setdefault(file, format_key_path(path))
        if path == DECK_PATH:
            stat = file.stat()
            for include in _includes(str(file), stat.st_mtime_ns, stat.st_size):
                found.setdefault(Path(os.path.normpath(Path(include).absolute())), f"an INCLUDE of {format_key_path(path)}")
    return found


def case_inputs(case) -> dict:
    """{absolute path: what} of every file the case reads: the case file itself (when read from
    one) and :func:`named_files` of its normalized mapping."""
    case = load_case(case)
    found = {} if case.source is None else {
        Path(os.path.normpath(Path(case.source).absolute())): "the case file"}
    for file, what in named_files(case.data, case.base_dir).items():
        found.setdefault(file, what)
    return found


__all__ = ["case_inputs", "named_files"]
