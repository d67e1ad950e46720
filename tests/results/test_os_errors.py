"""OS errors say what happened in one line, exit 2 (issue 32, item 7; sarfe.results.folder.os_error).

Real file systems, made for the test in a private mount namespace (``unshare --user
--map-root-user --mount``: no root needed, nothing visible outside; skipped where the kernel
does not allow it):

- a full disk (a small tmpfs): before, "internal error: OSError: VTK could not write …" after 20
  lines of VTK log (exit 1); now one line naming the output folder and the file, exit 2, and
  nothing left on the disk;
- a read-only file system: refused by validate and solve before any work;
- an output folder that is a mount point: before, valid for validate, then "internal error:
  OSError: [Errno 16] Device or resource busy" after the whole solve; now refused by validate and
  solve before any work (the result is renamed into place, which a mount point does not allow;
  a folder inside it is fine).
"""
from __future__ import annotations

import errno
import os
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from small_cases import coarse_rig

from sarfe.case.errors import CaseError
from sarfe.results.folder import check_output_folder, os_error

ROOT = Path(__file__).resolve().parents[2]
ENV = dict(os.environ, PYTHONPATH=str(ROOT), OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1",
           MKL_NUM_THREADS="1", MPLBACKEND="Agg")

SMALL_RIG = coarse_rig([30, 32], "{harmonics: 3, samples_per_period: 32, workers: 1, "
                      "stability: false, error_estimate: false}",
                      "output: {files: [summary, erp_vtu, animation]}")


def _namespaces_work() -> bool:
    try:
        return subprocess.run(["unshare", "--user", "--map-root-user", "--mount", "true"],
                              capture_output=True, timeout=30).returncode == 0
    except (OSError, subprocess.TimeoutExpired):
        return False


needs_mounts = pytest.mark.skipif(not _namespaces_work(),
                                  reason="no user + mount namespaces (unshare) here")


def in_namespace(mount: Path, options: str, *commands) -> list:
    """Run each sarfe command line with a fresh tmpfs (``options``) mounted at ``mount``, in one
    private user + mount namespace; [(exit code, stderr)] per command, and the listing of the
    mount after them (last)."""
    script = [f"mount -t tmpfs -o {options} tmpfs {shlex.quote(str(mount))} || exit 99"]
    for i, command in enumerate(commands):
        line = " ".join(shlex.quote(str(c)) for c in [sys.executable, "-m", "sarfe", *command])
        script.append(f"{line} >/dev/null 2>{mount.parent}/err{i}; echo $? >{mount.parent}/rc{i}")
    script.append(f"ls -A {shlex.quote(str(mount))} >{mount.parent}/listing")
    proc = subprocess.run(["unshare", "--user", "--map-root-user", "--mount", "sh", "-c",
                           "\n".join(script)], env=ENV, capture_output=True, text=True,
                          timeout=600)
    assert proc.returncode != 99, proc.stderr
    out = [(int((mount.parent / f"rc{i}").read_text()), (mount.parent / f"err{i}").read_text())
           for i in range(len(commands))]
    return out + [(mount.parent / "listing").read_text().split()]


@pytest.fixture
def small_rig(tmp_path):
    case = tmp_path / "small_rig.yaml"
    case.write_text(SMALL_RIG)
    return case


def one_line(code, err, *words):
    lines = [line for line in err.strip().splitlines() if not line.endswith(" …")]
    assert code == 2, err
    assert len(lines) == 1 and lines[0].startswith("sarfe: error: "), err
    assert "Traceback" not in err and "vtk" not in err.lower().replace(".vtu", "")
    for word in words:
        assert word in lines[0], lines[0]


@needs_mounts
def test_full_disk_is_one_line_and_leaves_nothing(tmp_path, small_rig):
    case = small_rig
    mount = tmp_path / "disk"
    mount.mkdir()
    ENV["SARFE_MESH_CACHE"] = str(tmp_path / "cache")
    try:
        *runs, listing = in_namespace(mount, "size=60k", ["solve", case, "--output",
                                                          mount / "out", "--quiet"])
    finally:
        ENV.pop("SARFE_MESH_CACHE")
    code, err = runs[0]
    one_line(code, err, f"{mount / 'out'}: cannot write the result: the disk is full", "(at ",
             "free space on it or choose another --output")    # (at animation/deflection_….vtu)
    assert listing == []          # the temporary result was removed; no half result


@needs_mounts
def test_read_only_file_system_is_refused_before_the_solve(tmp_path, small_rig):
    case = small_rig
    mount = tmp_path / "ro"
    mount.mkdir()
    *runs, _ = in_namespace(mount, "size=1m,ro", *[[command, case, "--output", mount / "out"]
                                                  for command in ("validate", "solve")])
    for code, err in runs:
        one_line(code, err, "the output folder is not writable", "Read-only file system")


@needs_mounts
def test_a_mount_point_is_refused_by_validate_and_solve(tmp_path, small_rig):
    case = small_rig
    mount = tmp_path / "mnt"
    mount.mkdir()
    *runs, listing = in_namespace(mount, "size=4m", *[
        [command, case, "--output", mount, *force] for command in ("validate", "solve")
        for force in ([], ["--force"])])
    for code, err in runs:
        one_line(code, err, "the output folder is a mount point", f"--output {mount}/results")
    assert listing == []


def test_a_mount_point_in_check_output_folder(tmp_path, monkeypatch):
    """The rule itself, on a folder the test declares a mount point (no namespace needed); a
    batch folder, written in place, may be one."""
    target = tmp_path / "mnt"
    target.mkdir()
    monkeypatch.setattr(os.path, "ismount", lambda path: Path(path) == target)
    with pytest.raises(CaseError, match="is a mount point"):
        check_output_folder(target, force=True)
    assert check_output_folder(target, write_inside=True) == target.resolve()
    assert check_output_folder(target / "inside") == (target / "inside").resolve()


@pytest.mark.parametrize("number, words", [
    (errno.ENOSPC, "the disk is full"), (errno.EROFS, "read-only"),
    (errno.EACCES, "permission denied"), (errno.EBUSY, "busy (a mount point")])
def test_os_error_names_the_result_and_the_file(tmp_path, number, words):
    """A file in the temporary result ``.<name>.tmp-<pid>-<hex>`` is named inside the result."""
    inside = tmp_path / ".out.tmp-123-abcd" / "erp" / "erp_0003.vtu"
    error = os_error(OSError(number, os.strerror(number), str(inside)))
    assert isinstance(error, CaseError) and "\n" not in str(error)
    assert str(error).startswith(f"{tmp_path / 'out'}: cannot write the result: ")
    assert words in str(error)
    assert "(at erp/erp_0003.vtu)" in str(error)
    plain = os_error(OSError(number, os.strerror(number), "/data/mesh.msh"))
    assert str(plain).startswith("/data/mesh.msh: ") and words in str(plain)
    assert os_error(OSError(errno.ENOENT, "No such file")) is None     # not the system's
