"""Result folders that never cost a user a file.

Rules (``sarfe solve --output``, ``sarfe batch --output``, the per-variant folders of a batch):

* sarfe writes into a folder only if it is absent, empty, or a previous sarfe result — a folder
  holding the marker file ``.sarfe-result`` (JSON: sarfe version, kind, case name, pid, host,
  and ``files``: every name the result holds) that sarfe writes into every result. Anything
  else is a one-line :class:`CaseError` before any work, unless ``force`` is given.
* A previous result is replaced only when every entry in it (top level and subfolders) is one
  sarfe wrote: a name in the marker's ``files``; for a marker without that list (an earlier
  sarfe version) or a batch folder (written in place, piece by piece), a name of sarfe's
  documented layout. A user's file in it (``notes.txt``, ``erp/mine.vtu``) makes it a refused
  folder like any other, named in the error; only ``force`` replaces it.
* Never the current directory, the home directory, the folder of the case file, or a folder
  containing one of them (even with ``force``); an existing file is never a result folder.
* Writability is probed (a file is created and removed) before the solve starts; ``os.access``
  is not enough (root passes it on read-only mounts).
* A mount point is never a solve's result folder (even with ``force``): the result could not be
  renamed onto it (EBUSY after the whole solve), and writing into it in place would leave half a
  result on a failure. A folder inside it is fine. (A batch folder, written in place, may be one.)
* An OS error met writing (a full disk, a read-only file system, no permission, EBUSY) is one
  line naming the result folder and the file (:func:`os_error`, exit 2); the temporary folder is
  removed, an earlier result stays.
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
import errno
import json
import os
import re
import secrets
import shutil
import socket
import tempfile
import time
from pathlib import Path

from sarfe import __version__
from sarfe.case.errors import CaseError
from sarfe.mesh.cache import pid_alive

MARKER = ".sarfe-result"
# files a sarfe result of a version before the marker consisted of (recognized as a result)
_LEGACY_RESULT_NAMES = {"summary.json", "table.txt", "response.h5", "erp_sweep.png",
                        "erp_spectrum.png", "contact_forces.png", "erp.vtu", "erp", "animation"}

# The layout of a solve result (docs/readme/outputs.md, docs/outputs.md), by which a result whose
# marker has no file list is judged: top-level names (folders end in "/") and, per folder, the
# pattern of the names inside it.
_SOLVE_TOP = {"summary.json", "table.txt", "response.h5", "report.html", "erp.vtu",
              "erp_sweep.png", "erp_spectrum.png", "third_octave.png", "contributions.png",
              "contact_forces.png", "friction.png", "erp/", "animation/"}
_SOLVE_INSIDE = {"erp/": re.compile(r"erp\.pvd|erp_\d+\.vtu"),
                 "animation/": re.compile(r"deflection\.pvd|deflection_\d+\.vtu")}
# The layout of a batch folder (sarfe.batch.store, sarfe.batch.batch_report): written in place and
# resumed, so judged by its layout; ``variant_outputs/<id>/`` are solve results judged by their
# own marker. ``store.atomic_write`` leaves ``.<name>.<8 random>.tmp`` when killed mid-write.
_BATCH_TOP = {"summary.json", "variants.csv", "results.csv", "results.parquet", "report.html",
              "erp_histogram.png", "erp_distribution.png", "rattle_probability_vs_gap.png",
              "rattle_probability.png", "erp_vs_parameters.png",
              "variants/", ".cache/", "variant_outputs/"}
_ATOMIC_TEMP = re.compile(r"\.(?P<name>.+)\.[a-z0-9_]{8}\.tmp|\.results\.[a-z0-9_]{8}\.parquet\.tmp")
_VARIANT_ID = r"v[0-9a-f]{12}"
_BATCH_INSIDE = {"variants/": re.compile(_VARIANT_ID + r"\.json"),
                 ".cache/": re.compile(r"[0-9A-Za-z_-]+\.npz")}

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


def _legacy_kind(folder: Path) -> str | None:
    """The kind of a result written before the marker existed: "batch" (a ``variants/`` folder
    of records), "solve" (sarfe's summary.json, with ``sarfe_version``), or None."""
    variants = folder / "variants"
    try:
        if variants.is_dir() and all(p.suffix == ".json" for p in variants.iterdir()):
            return "batch"
        summary = json.loads((folder / "summary.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return "solve" if isinstance(summary, dict) and "sarfe_version" in summary else None


def written_names(folder) -> list[str]:
    """Every entry under ``folder`` but the marker: relative POSIX paths, folders ending in "/",
    sorted top-down — the ``files`` list of the marker of a result sarfe just wrote."""
    names = []
    _judge(Path(folder), lambda name, path: names.append(name) or True)
    return names


def _judge(root: Path, rule, prefix: str = "") -> list[str]:
    """Walk ``root`` top-down (symlinks not followed); ``rule(name, path)`` says of each entry
    (``name`` relative to the result, folders ending in "/"): True = sarfe's (a folder is then
    walked), False = foreign, a list = the foreign names inside it (judged by the rule itself).
    Returns the foreign names; a folder that cannot be read is foreign (sarfe cannot vouch for
    what is inside it)."""
    foreign = []
    try:
        entries = sorted(os.scandir(root), key=lambda e: e.name)
    except OSError:
        return [prefix or "."]
    for entry in entries:
        if not prefix and entry.name == MARKER:
            continue
        is_dir = entry.is_dir(follow_symlinks=False)
        name = prefix + entry.name + ("/" if is_dir else "")
        verdict = rule(name, Path(entry.path))
        if verdict is True:
            if is_dir:
                foreign += _judge(Path(entry.path), rule, name)
        elif verdict is False:
            foreign.append(name)
        else:
            foreign += verdict
    return foreign


def _in_layout(name: str, top: set, inside: dict) -> bool:
    """``name`` is a top-level name of ``top`` or a file in one of its folders matching that
    folder's pattern in ``inside``."""
    parent, _, leaf = name.rstrip("/").rpartition("/")
    if not parent:
        return name in top
    pattern = inside.get(parent + "/")
    return pattern is not None and not name.endswith("/") and (
        pattern.fullmatch(leaf) is not None or _atomic_temp_of(leaf, pattern))


def _atomic_temp_of(leaf: str, pattern) -> bool:
    """``leaf`` is the temporary of an atomic write of a name matching ``pattern``."""
    match = _ATOMIC_TEMP.fullmatch(leaf)
    return bool(match and match["name"] and pattern.fullmatch(match["name"]))


def _solve_rule(name: str, path: Path) -> bool:
    return _in_layout(name, _SOLVE_TOP, _SOLVE_INSIDE)


def _batch_rule(name: str, path: Path):
    if _in_layout(name, _BATCH_TOP, _BATCH_INSIDE):
        return True
    parent, _, leaf = name.rstrip("/").rpartition("/")
    if not parent:     # an atomic write of a top-level file killed before its rename
        match = _ATOMIC_TEMP.fullmatch(leaf)
        return match is not None and (match["name"] is None or match["name"] in _BATCH_TOP)
    if parent != "variant_outputs" or not name.endswith("/"):
        return False
    if re.fullmatch(_VARIANT_ID, leaf):   # one variant's solve result, judged by its own marker
        inner = foreign_entries(path)
        return [name + entry for entry in (_top_names(path) if inner is None else inner)]
    # a variant result being written (or the backup of the one it replaces): sarfe's temporary
    return [] if _TEMP_NAME.fullmatch(leaf) and read_marker(path) is not None else False


def _top_names(folder: Path) -> list[str]:
    try:
        return sorted(e.name + ("/" if e.is_dir(follow_symlinks=False) else "")
                      for e in os.scandir(folder))
    except OSError:
        return ["."]


def _solve_rule_or_listed(folder: Path):
    """The rule for a solve result: its marker's file list, else the documented layout."""
    listed = (read_marker(folder) or {}).get("files")
    if isinstance(listed, list):
        listed = set(map(str, listed))
        return lambda name, path: name in listed
    return _solve_rule


def result_kind(folder) -> str | None:
    """"solve" or "batch" for a sarfe result folder (its marker's kind, or the kind of a result
    of a version before the marker), None for any other folder."""
    info = read_marker(Path(folder))
    if info is None:
        return _legacy_kind(Path(folder))
    return "batch" if info.get("kind") == "batch" else "solve"


def foreign_entries(folder) -> list[str] | None:
    """The entries of the sarfe result ``folder`` that sarfe did not write (relative POSIX paths,
    folders ending in "/", a foreign folder named once), or None when ``folder`` is not a sarfe
    result (no marker, and not a result of a version before the marker).

    Judged by the marker's ``files`` list; for a marker without one (earlier versions) by the
    documented layout of its kind; a batch folder by the batch layout."""
    folder = Path(folder)
    kind = result_kind(folder)
    if kind is None:
        return None
    if kind == "batch":
        return _judge(folder, _batch_rule)
    return _judge(folder, _solve_rule_or_listed(folder))


def is_sarfe_result(folder: Path) -> bool:
    """``folder`` is a sarfe result holding nothing but what sarfe wrote (replaceable)."""
    folder = Path(folder)
    return folder.is_dir() and foreign_entries(folder) == []


def _named(names: list[str]) -> str:
    """'a', 'b', 'c' and 4 more"""
    shown = ", ".join(repr(name) for name in names[:3])
    return shown + (f" and {len(names) - 3} more" if len(names) > 3 else "")


def _reason(folder: Path, what: str, write_inside: bool) -> str | None:
    """What is wrong with replacing (or, ``write_inside``, writing a batch into) the existing
    folder ``folder`` without ``force``, or None when nothing is."""
    entries = _top_names(folder)
    if not entries:
        return None
    foreign = foreign_entries(folder)
    if foreign is None:
        return f"the {what} holds files that are not a sarfe result ({_named(entries)})"
    if foreign:
        return (f"the {what} is an earlier sarfe result but holds files sarfe did not write "
                f"({_named(foreign)})")
    if write_inside and result_kind(folder) != "batch":
        return f"the {what} holds a sarfe solve result, not a batch folder"
    return None


def refusal(folder, what: str = "output folder", write_inside: bool = False) -> str | None:
    """One line saying why sarfe may not (re)place a result in the existing folder ``folder``
    without ``force`` (naming the first entries sarfe did not write), or None when it may."""
    reason = _reason(Path(folder), what, write_inside)
    if reason is None:
        return None
    action = ("add --force to write the batch into it anyway" if write_inside
              else "add --force to replace it and delete those files")
    return f"{reason}; choose another folder, or {action}"


def _contains(outer: Path, inner: Path) -> bool:
    return inner == outer or outer in inner.parents


def _locations(path) -> set:
    """Where the file ``path`` lives: its own name (its folder resolved) and, for a symbolic
    link, the file it points to — a folder containing either holds the input."""
    path = Path(path).expanduser().absolute()
    return {path.parent.resolve() / path.name, path.resolve()}


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
    labels = protected if isinstance(protected, dict) else dict.fromkeys(protected)
    for path, label in labels.items():
        if path is not None and any(_contains(target, p) for p in _locations(path)):
            named = f"{label}, {path}" if label else str(path)
            raise CaseError(f"the {what} would replace the folder of an input of the case "
                            f"({named}); choose a new or dedicated folder, e.g. --output "
                            "results/NAME (--force never deletes an input)", source=given)
    if target.exists() and not target.is_dir():
        raise CaseError(f"the {what} is an existing file, not a folder; give a folder name",
                        source=given)
    if not write_inside and target.is_dir() and os.path.ismount(target):
        raise CaseError(f"the {what} is a mount point: a result is written beside it and renamed "
                        "into place, which a mount point does not allow (EBUSY); give a folder "
                        f"inside it, e.g. --output {target / 'results'}", source=given)
    if target.is_dir():
        try:
            entries = sorted(p.name for p in target.iterdir())
        except OSError as exc:
            raise CaseError(f"cannot read the {what}: {exc.strerror or exc}", source=given) from None
        reason = None if (force or not entries) else refusal(target, what, write_inside)
        if reason is not None:
            raise CaseError(reason, source=given)
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
            reason = None if force else _reason(target, "output folder", False)
            if reason is not None:   # a file was put there during the run
                raise CaseError(f"{reason} (it changed during the run); the result is in "
                                f"{temporary}", source=str(target))
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
    try:
        temporary = new_temporary(target, info)
    except OSError as exc:
        raise os_error(exc, target) or exc from None
    try:
        write(temporary)
        write_marker(temporary, dict(info, files=written_names(temporary)))
        replace_directory(temporary, target, force=force)
    except BaseException as exc:
        shutil.rmtree(temporary, ignore_errors=True)
        error = os_error(exc, target) if isinstance(exc, OSError) else None
        if error is not None:
            raise error from None
        raise
    return target


# ------------------------------------------------------------------------------- OS errors
# what an OS error met writing a result means, and what the user can do: {errno: (what, advice)}
_OS_ERRORS = {
    errno.ENOSPC: ("the disk is full (no space left on device)",
                   "free space on it or choose another --output"),
    errno.EDQUOT: ("the disk quota is exceeded", "free space or choose another --output"),
    errno.EROFS: ("the file system is read-only", "choose a writable --output"),
    errno.EACCES: ("permission denied", "choose a folder you may write, or change its permissions"),
    errno.EPERM: ("operation not permitted", "choose a folder you may write"),
    errno.EBUSY: ("the folder is busy (a mount point, or in use by another program)",
                  "choose a folder inside it or another --output"),
    errno.EXDEV: ("the result cannot be moved across file systems", "choose another --output"),
    errno.EIO: ("an input/output error of the disk", "check the disk or choose another --output"),
}


def _in_result(path: Path) -> tuple:
    """(result folder, path inside it) of a path in a temporary sibling ``.<name>.tmp-…`` of a
    result being written (named by its final name), else (None, None)."""
    parts = path.parts
    for i, part in enumerate(parts):
        match = _TEMP_NAME.match(part)
        if match:
            return Path(*parts[:i], match["name"]), Path(*parts[i + 1:]) if parts[i + 1:] else None
    return None, None


def os_error(exc: OSError, target=None) -> CaseError | None:
    """One line for an OS error met reading or writing (a full disk, a read-only file system,
    no permission, a busy mount point …): a CaseError (exit 2) naming the path — ``target``
    (the result folder being written) or the error's own file, a file in a temporary result
    named by the result's final name — what happened and what to do; None for an errno not
    listed in ``_OS_ERRORS`` (an internal error)."""
    if not isinstance(exc, OSError) or exc.errno not in _OS_ERRORS:
        return None
    what, advice = _OS_ERRORS[exc.errno]
    file = Path(exc.filename) if isinstance(exc.filename, (str, os.PathLike)) else None
    folder, inside = _in_result(file) if file is not None else (None, None)
    if target is not None:
        folder = Path(target)
        inside = inside if inside is not None else file
    if folder is None:
        return CaseError(f"{what}; {advice}", source=str(file) if file else None)
    at = f" (at {inside})" if inside is not None else ""
    return CaseError(f"cannot write the result: {what}{at}; nothing of it was kept (an earlier "
                     f"result there is unchanged); {advice}", source=str(folder))


def claim_folder(target, info: dict, force: bool = False) -> Path:
    """Make ``target`` (checked by :func:`check_output_folder`) a sarfe folder written in place
    (a batch folder): create it and write the marker, keeping an existing marker's kind."""
    target = Path(target)
    with _lock_parent(_existing_parent(target)):
        reason = None if (force or not target.is_dir()) else refusal(
            target, "batch output folder", write_inside=True)
        if reason is not None:
            raise CaseError(reason, source=str(target))
        target.mkdir(parents=True, exist_ok=True)
        if read_marker(target) is None:
            write_marker(target, info)
    return target


def _existing_parent(path: Path) -> Path:
    parent = Path(path).resolve().parent
    while not parent.exists():
        parent = parent.parent
    return parent


__all__ = ["MARKER", "check_output_folder", "os_error", "clean_stale", "claim_folder", "foreign_entries",
           "is_sarfe_result", "marker_info", "pid_alive", "read_marker", "refusal", "result_kind",
           "replace_directory", "write_result_folder", "written_names"]
