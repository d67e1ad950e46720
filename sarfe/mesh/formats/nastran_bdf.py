"""A Nastran deck file: read and cross-referenced by pyNastran, and its cards' lines for messages.

- :func:`load_bdf`: the pyNastran ``BDF`` model of a deck (bulk data alone or a whole job,
  INCLUDEs followed), cross-referenced; a missing INCLUDE file, a card naming a GRID the deck
  lacks, or any pyNastran reading error is one :class:`~sarfe.mesh.formats.deck.DeckError` line
  naming the file, the card and its line.
- :func:`bulk_fields`, :func:`card_line`, :func:`card_where`: where a card is ("deck.bdf:1473:
  MAT1 1"), by a plain scan of free, small and large field lines (not a parser).

pyNastran (BSD-3) is imported when a deck is read, not at ``import sarfe``.
"""
from __future__ import annotations

import contextlib
import io
import os
import re
import warnings
from pathlib import Path

import numpy as np

from sarfe.mesh.formats.deck import DeckError

__all__ = ["load_bdf", "bulk_fields", "card_line", "card_where", "first_lines"]


def load_bdf(path: Path):
    """The pyNastran model of a deck, cross-referenced. pyNastran's console output while
    reading (``UserWarning: bad fields``, ``problem adding …``) is held back: the error it
    leads to is raised as one line instead. A card referring to a GRID the deck does not have
    is a DeckError naming the card, its line and the missing ids (before pyNastran's
    cross-reference, whose message lists every GRID of the deck)."""
    if not hasattr(np, "in1d"):  # pyNastran 1.4 calls np.in1d, removed in NumPy 2.4
        np.in1d = np.isin
    from pyNastran.bdf.bdf import BDF

    with open(path, errors="replace") as handle:
        text = handle.read()
    upper = text.upper()
    has_bulk = "BEGIN BULK" in upper
    has_control = has_bulk and "CEND" in upper.split("BEGIN BULK")[0]
    _check_includes(path)     # pyNastran would dump a pyNastran_crash.bdf into the folder
    model = BDF(debug=None)
    model.log.level = "error"
    cwd = os.getcwd()
    console = io.StringIO()
    try:
        with warnings.catch_warnings(), contextlib.redirect_stdout(console):
            warnings.simplefilter("ignore")
            if has_bulk and not has_control:  # BEGIN BULK without executive/case control
                os.chdir(path.resolve().parent)  # INCLUDEs are relative to the deck
                model.read_bdf(io.StringIO("CEND\n" + text), xref=False, encoding="latin-1")
            else:  # a whole job, or bulk data alone (pyNastran's punch mode)
                model.read_bdf(os.fspath(path), xref=False, punch=not has_bulk,
                               encoding="latin-1")
            _check_node_references(model, path)
            model.cross_reference()          # what read_bdf(xref=True) does after reading
            model._xref = True
    except DeckError:
        raise
    except Exception as error:
        raise DeckError(_pynastran_message(error, path)) from error
    finally:
        os.chdir(cwd)
    return model


_INCLUDE = re.compile(r"^\s*INCLUDE\s+'?([^'\s]+)", re.IGNORECASE)


def _check_includes(path: Path, root: Path | None = None, seen=()) -> None:
    """DeckError "deck.bdf:7: INCLUDE 'x.inc': file not found" for the first INCLUDE (in the
    deck or the files it includes) that names no file, relative to the including file or to
    the deck's folder (where pyNastran looks)."""
    root = path if root is None else root
    if path in seen:
        return
    with open(path, errors="replace") as handle:
        for number, text in enumerate(handle, start=1):
            include = _INCLUDE.match(text)
            if include:
                name = include.group(1)
                found = [p for p in (path.parent / name, root.parent / name) if p.is_file()]
                if not found:
                    raise DeckError(f"{path}:{number}: INCLUDE '{name}': file not found "
                                    f"({path.parent / name})")
                _check_includes(found[0], root, seen + (path,))


_SHOWN_IDS = 5   # ids listed in a message before "…"


def _ids_text(ids) -> str:
    ids = [int(i) for i in ids]
    return ", ".join(map(str, ids[:_SHOWN_IDS])) + (f", … ({len(ids)} in all)"
                                                    if len(ids) > _SHOWN_IDS else "")


def _check_node_references(model, path: Path) -> None:
    """DeckError for the first element, point mass or rigid element whose GRIDs are not in
    the deck: "deck.bdf:1502: CQUAD4 1: GRID 999999 is not in the deck" (a few ids at most)."""
    known = model.nodes.keys() | model.spoints.keys() | model.epoints.keys()
    tables = (("element", model.elements), ("mass", model.masses),
              ("rigid", model.rigid_elements))
    for kind, table in tables:
        for eid, card in sorted(table.items()):
            try:
                ids = (list(card.independent_nodes) + list(card.dependent_nodes)
                       if kind == "rigid" else list(card.node_ids))
            except (AttributeError, TypeError):   # a card without node lists: pyNastran checks it
                continue
            missing = sorted({int(n) for n in ids if n not in (None, 0) and n not in known})
            if missing:
                raise DeckError(f"{card_where(path, card.type, eid)}: GRID"
                                f"{'s' if len(missing) > 1 else ''} {_ids_text(missing)} "
                                f"{'are' if len(missing) > 1 else 'is'} not in the deck")


def _pynastran_message(error, path: Path) -> str:
    """One short line of a pyNastran reading error: its first statement, long id lists cut,
    and the deck line of the card it names (``card=['GRID*', '1', …]`` / ``CQUAD4 eid=1``)."""
    text = re.sub(r"^There are [\w -]+errors[^\n]*\n", "", str(error).strip())
    first = re.split(r"\ncard=", text.strip())[0]              # the first error only
    cards = re.findall(r"card=\[?'?([A-Z][A-Z0-9]*)\*?'?,?\s+'?(\d+)", text)
    cards += re.findall(r"required by ([A-Z][A-Z0-9]*) [a-z]+=(\d+)", text)
    cards += re.findall(r"new_\w+=\s*([A-Z][A-Z0-9]*)\*?\s+(\d+)", text)
    first = re.sub(r"(nids|spoints|epoints|Allowed \w+)=[^=]*?(\]\)?|$)", "", first)
    first = re.sub(r"^\w+Error: '?", "", first.strip()).strip(" .'\"\n")
    first = re.sub(r"\s+cwd: .*", "", first, flags=re.DOTALL)      # a missing INCLUDE file
    twice = re.match(r"\w+=\d+\s+old_\w+=\s*(.*?)\s+new_\w+=\s*(.*)", first, re.DOTALL)
    if twice:   # a duplicate id: both cards, short
        first = (f"the id is used twice: {' '.join(twice.group(1).split())} and "
                 f"{' '.join(twice.group(2).split())}")
    where = card_where(path, *cards[0]) if cards else f"cannot read Nastran deck {path}"
    line = " ".join(first.split()) or type(error).__name__
    return f"{where}: {line[:240]}{'…' if len(line) > 240 else ''}"


def bulk_fields(text: str) -> list[str]:
    """The fields of one bulk-data line, unstripped: free format (comma-separated), large
    (``CARD*``: the name, then 16-character fields) or small (8-character fields)."""
    if "," in text:
        return text.split(",")
    if text[:8].strip().endswith("*"):
        return [text[:8]] + [text[8 + 16 * k:24 + 16 * k] for k in range(4)]
    return [text[8 * k:8 * k + 8] for k in range(9)]


def card_line(path, card: str, ident) -> tuple[str, int] | None:
    """(file, line number) of the bulk-data card ``card`` with id ``ident`` (its first field)
    in the deck or a file it INCLUDEs, in free (comma), small or large (``CARD*``) field
    format; None when not found. A plain scan for error messages, not a parser."""
    card, ident = str(card).upper(), str(int(ident))
    seen = []

    def scan(file: Path):
        if file in seen or not file.is_file():
            return None
        seen.append(file)
        with open(file, errors="replace") as handle:
            for number, text in enumerate(handle, start=1):
                fields = bulk_fields(text)
                name = fields[0].strip().upper().rstrip("*")
                if name == card and len(fields) > 1 and fields[1].strip() == ident:
                    return str(file), number
                include = _INCLUDE.match(text)
                if include:
                    found = scan(file.parent / include.group(1))
                    if found:
                        return found
        return None

    return scan(Path(path))


def first_lines(path, cards) -> dict:
    """{card: "file:line"} of the first line of each bulk-data card name in ``cards`` in the
    deck or the files it INCLUDEs (a plain scan, for messages); cards not found are left out."""
    wanted = {str(c).upper() for c in cards}
    found, seen = {}, []

    def scan(file: Path):
        if file in seen or not file.is_file() or len(found) == len(wanted):
            return
        seen.append(file)
        with open(file, errors="replace") as handle:
            for number, text in enumerate(handle, start=1):
                name = bulk_fields(text)[0].strip().upper().rstrip("*")
                if name in wanted and name not in found:
                    found[name] = f"{file}:{number}"
                include = _INCLUDE.match(text)
                if include:
                    scan(file.parent / include.group(1))

    scan(Path(path))
    return found


def card_where(path, card: str, ident) -> str:
    """"deck.bdf:1473: MAT1 1" (or "deck.bdf: MAT1 1" when the line is not found)."""
    found = card_line(path, card, ident)
    return (f"{found[0]}:{found[1]}: {card} {ident}" if found else f"{path}: {card} {ident}")
