"""Result folders that never cost a user a file.

Rules (``sarfe solve --output``, ``sarfe batch --output``, the per-variant folders of a batch):

* sarfe writes into a folder only if it is absent, empty, or a previous sarfe result — a folder
  holding the marker file ``.sarfe-result`` (JSON: sarfe version, kind, case name, pid, host)
  that sarfe writes into every result. Anything else is a one-line :class:`CaseError` before any
  work, unless ``force`` is given.
* Never the current directory, the home directory, the folder of the case file, or a folder
  containing one of them (even with ``force``); an existing file is never a result folder.
* Writability is probed (a file is created and removed) before the solve starts; ``os.access``
  is not enough (root passes it on read-only mounts).
* A result is written into a temporary sibling ``.<name>.tmp-<pid>-<random>`` and moved into
  place at the end under an exclusive lock on the parent folder (``flock``), so concurrent writers
  of the same target never interleave: the last one to finish wins and every result is whole.
  The previous result is first renamed to ``.<name>.old-<pid>-<random>``; if the final rename
  fails it is renamed back.
* Temporary folders of killed runs (sarfe's marker inside, owning PID gone on this host) are
  removed by the next run writing next to them; a backup left by a run killed between its two
  renames is put back when the target is missing.
"""
from __future__ import annotations

import contextlib
import datetime as _dt
import json
import os
import re
import secrets
import shutil
import socket
import tempfile
import time
from pathlib import Path

from sarfe.io.errors import CaseError
from sarfe.mesh.cache import pid_alive

MARKER = ".sarfe-result"
# files a sarfe result of a version before the marker consisted of (recognized as a result)
_LEGACY_RESULT_NAMES = {"summary.json", "table.txt", "response.h5", "erp_sweep.png",
                        "erp_spectrum.png", "contact_forces.png", "erp.vtu", "erp", "animation"}


def _lock_parent(parent: Path):
    """Context manager: exclusive ``flock`` on the folder ``parent`` (no lock file left behind)."""
    try:
        import fcntl
    except ImportError:  # not POSIX: no cross-process lock
        return contextlib.nullcontext()

    @contextlib.contextmanager
    def held():
        handle = os.open(parent, os.O_RDONLY)
        try:
            fcntl.flock(handle, fcntl.LOCK_EX)
            yield
        finally:
            os.close(handle)   # releases the lock
    return held()


def marker_info(kind: str, case: str | None = None) -> dict:
    from sarfe import __version__

    return {"sarfe_version": __version__, "kind": kind, "case": case, "pid": os.getpid(),
            "host": socket.gethostname(),
            "created_utc": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")}


def write_marker(folder: Path, info: dict) -> None:
    (Path(folder) / MARKER).write_text(json.dumps(info, indent=1) + "\n", encoding="utf-8")


def read_marker(folder: Path) -> dict | None:
    """The marker of a sarfe result folder, or None (absent, unreadable, not sarfe's)."""
    try:
        info = json.loads((Path(folder) / MARKER).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return info if isinstance(info, dict) and "sarfe_version" in info else None


_LEGACY_BATCH_NAMES = {"variants", ".cache", "variant_outputs", "results.csv", "results.parquet",
                       "summary.json", "variants.csv", "erp_histogram.png",
                       "rattle_probability_vs_gap.png"}


def _legacy_result(folder: Path) -> bool:
    """A result written before the marker existed: only sarfe's file names, and sarfe's
    summary.json (a case result) or a ``variants/`` folder of records (a batch folder)."""
    try:
        names = {p.name for p in folder.iterdir()}
    except OSError:
        return False
    if "variants" in names and names <= _LEGACY_BATCH_NAMES and (folder / "variants").is_dir():
        return all(p.suffix == ".json" for p in (folder / "variants").iterdir())
    try:
        summary = json.loads((folder / "summary.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return False
    return isinstance(summary, dict) and "sarfe_version" in summary and names <= _LEGACY_RESULT_NAMES


def is_sarfe_result(folder: Path) -> bool:
    folder = Path(folder)
    return folder.is_dir() and (read_marker(folder) is not None or _legacy_result(folder))


def _contains(outer: Path, inner: Path) -> bool:
    return inner == outer or outer in inner.parents


def _probe_writable(folder: Path) -> None:
    handle, name = tempfile.mkstemp(prefix=".sarfe-probe-", dir=folder)
    os.close(handle)
    os.remove(name)


def check_output_folder(target, *, force: bool = False, protected=(), what: str = "output folder",
                        write_inside: bool = False) -> Path:
    """Raise CaseError unless sarfe may (re)place a result at ``target``; returns it resolved.

    ``protected``: files (the case file, study files) whose folder, and any folder containing it,
    is never a result folder; the current directory never is either. ``write_inside``: the
    result is written into ``target`` itself (a batch folder) rather than swapped in from a
    sibling, so ``target`` must be writable too. Creates nothing.
    """
    given = str(target)
    target = Path(target).expanduser().resolve()
    cwd = Path.cwd().resolve()
    if _contains(target, cwd):
        raise CaseError(f"the {what} would replace the current directory{'' if target == cwd else ' (it contains it)'};"
                        " choose a new or dedicated folder, e.g. --output results/NAME", source=given)
    home = Path.home().resolve()
    if _contains(target, home):
        raise CaseError(f"the {what} would replace the home directory{'' if target == home else ' (it contains it)'};"
                        " choose a new or dedicated folder, e.g. --output results/NAME", source=given)
    for path in protected:
        if path is None:
            continue
        folder = Path(path).expanduser().resolve().parent
        if _contains(target, folder):
            raise CaseError(f"the {what} would replace the folder of {path}; choose a new or "
                            "dedicated folder, e.g. --output results/NAME", source=given)
    if target.exists() and not target.is_dir():
        raise CaseError(f"the {what} is an existing file, not a folder; give a folder name",
                        source=given)
    if target.is_dir():
        try:
            entries = sorted(p.name for p in target.iterdir())
        except OSError as exc:
            raise CaseError(f"cannot read the {what}: {exc.strerror or exc}", source=given) from None
        if entries and not force and not is_sarfe_result(target):
            shown = ", ".join(repr(e) for e in entries[:3]) + (", …" if len(entries) > 3 else "")
            raise CaseError(f"the {what} holds files that are not a sarfe result ({shown}); "
                            "choose another folder, or add --force to replace it", source=given)
    # writability: the nearest existing folder on the way (nothing is created here)
    probe = target if (write_inside and target.is_dir()) else target.parent
    while not probe.exists():
        probe = probe.parent
    if not probe.is_dir():
        raise CaseError(f"cannot create the {what}: {probe} is a file", source=given)
    try:
        _probe_writable(probe)
    except OSError as exc:
        raise CaseError(f"the {what} is not writable ({probe}: {exc.strerror or exc})",
                        source=given) from None
    return target


# ------------------------------------------------------------------------------- stale debris
_TEMP_NAME = re.compile(r"^\.(?P<name>.+)\.(?P<kind>tmp|old)-(?P<pid>\d+)-[0-9a-z]+$")


def _stale(entry: Path) -> bool:
    """A sarfe temporary folder whose writing process is gone (name, marker, pid and host agree)."""
    match = _TEMP_NAME.match(entry.name)
    if not match or not entry.is_dir() or entry.is_symlink():
        return False
    info = read_marker(entry)
    if info is None or str(info.get("pid")) != match["pid"]:
        return False
    if info.get("host") not in (None, socket.gethostname()):
        return False
    return not pid_alive(int(match["pid"]))


# sarfe before the marker: ``tempfile.mkdtemp(prefix=".<name>.tmp-")`` and ``.<name>.old-<pid>``
_LEGACY_TEMP = re.compile(r"^\.(?P<name>.+)\.(?P<kind>tmp)-[a-z0-9_]{8}$|"
                          r"^\.(?P<name2>.+)\.(?P<kind2>old)-(?P<pid>\d+)$")
_LEGACY_AGE_S = 86400.0


def _legacy_stale(entry: Path, match) -> bool:
    """A temporary folder of a sarfe version without the marker: only sarfe's result file names
    inside, and (tmp) a day old or (old) its PID gone."""
    try:
        if not entry.is_dir() or entry.is_symlink():
            return False
        if not {p.name for p in entry.iterdir()} <= _LEGACY_RESULT_NAMES:
            return False
        if match["kind"] == "tmp":
            return time.time() - entry.stat().st_mtime > _LEGACY_AGE_S
        return not pid_alive(int(match["pid"]))
    except OSError:
        return False


def clean_stale(parent, name: str | None = None) -> list:
    """Remove temporary folders of killed sarfe runs in ``parent`` (all, or those of target
    ``name``); a backup ``.old-`` whose target is missing is renamed back instead. Returns what
    was removed or restored."""
    parent = Path(parent)
    done = []
    try:
        entries = list(parent.iterdir())
    except OSError:
        return done
    for entry in entries:
        match = _TEMP_NAME.match(entry.name)
        if match is None:
            legacy = _LEGACY_TEMP.match(entry.name)
            if legacy is not None and _legacy_stale(entry, {
                    "kind": legacy["kind"] or legacy["kind2"], "pid": legacy["pid"]}):
                match = {"name": legacy["name"] or legacy["name2"],
                         "kind": legacy["kind"] or legacy["kind2"]}
            if match is None or (name is not None and match["name"] != name):
                continue
        elif (name is not None and match["name"] != name) or not _stale(entry):
            continue
        target = parent / match["name"]
        if match["kind"] == "old" and not target.exists():
            with contextlib.suppress(OSError):
                os.rename(entry, target)
                done.append(target)
                continue
        shutil.rmtree(entry, ignore_errors=True)
        done.append(entry)
    return done


# ---------------------------------------------------------------------------- writing a result
def _sibling(target: Path, kind: str) -> Path:
    return target.with_name(f".{target.name}.{kind}-{os.getpid()}-{secrets.token_hex(4)}")


def new_temporary(target: Path, info: dict) -> Path:
    """An empty sibling folder of ``target`` holding only sarfe's marker (with this PID)."""
    target = Path(target)
    target.parent.mkdir(parents=True, exist_ok=True)
    clean_stale(target.parent)   # every stale sarfe temporary in this folder, of any target
    temporary = _sibling(target, "tmp")
    temporary.mkdir()
    write_marker(temporary, dict(info, pid=os.getpid()))
    return temporary


def replace_directory(temporary: Path, target: Path, force: bool = False, rename=os.rename):
    """Move the finished folder ``temporary`` onto ``target`` (module docstring).

    Under an exclusive lock on the parent: re-check ``target`` (absent, empty or a sarfe result,
    unless ``force``), rename it to a backup, rename ``temporary`` to ``target``; if that fails
    the backup is renamed back and the error raised. ``rename`` is a test seam.
    """
    temporary, target = Path(temporary), Path(target)
    with _lock_parent(target.parent):
        backup = None
        if target.is_symlink() or (target.exists() and not target.is_dir()):
            raise CaseError("the output folder became a file during the run; the result is in "
                            f"{temporary}", source=str(target))
        if target.exists():
            if any(target.iterdir()) and not force and not is_sarfe_result(target):
                raise CaseError("the output folder received files that are not a sarfe result "
                                f"during the run; the result is in {temporary}", source=str(target))
            backup = _sibling(target, "old")
            rename(target, backup)
        try:
            rename(temporary, target)
        except BaseException:
            if backup is not None:
                rename(backup, target)   # the previous result stays where it was
            raise
    if backup is not None:
        shutil.rmtree(backup, ignore_errors=True)


def write_result_folder(target, write, info: dict, force: bool = False) -> Path:
    """``write(folder)`` into a new temporary sibling of ``target``, then move it into place.
    On any failure the temporary folder is removed and ``target`` is left as it was."""
    target = Path(target)
    temporary = new_temporary(target, info)
    try:
        write(temporary)
        write_marker(temporary, info)
        replace_directory(temporary, target, force=force)
    except BaseException:
        shutil.rmtree(temporary, ignore_errors=True)
        raise
    return target


def claim_folder(target, info: dict, force: bool = False) -> Path:
    """Make ``target`` (checked by :func:`check_output_folder`) a sarfe folder written in place
    (a batch folder): create it and write the marker, keeping an existing marker's kind."""
    target = Path(target)
    with _lock_parent(_existing_parent(target)):
        if target.is_dir() and any(target.iterdir()) and not force and not is_sarfe_result(target):
            raise CaseError("the output folder holds files that are not a sarfe result; choose "
                            "another folder, or add --force", source=str(target))
        target.mkdir(parents=True, exist_ok=True)
        if read_marker(target) is None:
            write_marker(target, info)
    return target


def _existing_parent(path: Path) -> Path:
    parent = Path(path).resolve().parent
    while not parent.exists():
        parent = parent.parent
    return parent


__all__ = ["MARKER", "check_output_folder", "clean_stale", "claim_folder", "is_sarfe_result",
           "marker_info", "read_marker", "replace_directory", "write_result_folder", "pid_alive"]
