"""Output safety: sarfe never deletes a user's file (sarfe.results.folder, `sarfe solve --output`,
`sarfe batch --output`). Each rule of issue 11 has its test: an existing user folder, the current
directory, the case's folder, an existing file, a read-only location, concurrent writers, a kill
during the final move, and debris of killed runs."""
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

import pytest

from sarfe.cli import main
from sarfe.case.errors import CaseError
from small_cases import TINY

from sarfe.results.folder import (MARKER, check_output_folder, clean_stale, is_sarfe_result,
                                    marker_info, replace_directory, write_result_folder)

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture
def case(tmp_path, monkeypatch):
    """A 2-DOF case (solves in well under a second) in tmp_path/case/, run from tmp_path."""
    folder = tmp_path / "case"
    folder.mkdir()
    path = folder / "tiny.yaml"
    path.write_text(TINY)
    monkeypatch.chdir(tmp_path)
    return path


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def snapshot(folder: Path) -> dict:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file()}


def assert_one_line_error(code, out, err, *words):
    assert code == 2, (out, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("sarfe: error: "), err
    assert "Traceback" not in err and "table" not in out.lower()
    for word in words:
        assert word in lines[0], lines[0]


def test_new_folder_gets_a_marked_result_and_is_replaced_by_the_next_run(case, capsys):
    code, out, err = run(capsys, "solve", case, "--output", "res", "--quiet")
    assert code == 0, err
    marker = json.loads((Path("res") / MARKER).read_text())
    assert marker["kind"] == "solve" and marker["case"] == "tiny" and "sarfe_version" in marker
    first = json.loads((Path("res") / "summary.json").read_text())["created_utc"]
    assert run(capsys, "solve", case, "--output", "res", "--quiet")[0] == 0
    assert (Path("res") / "summary.json").is_file() and is_sarfe_result(Path("res"))
    assert json.loads((Path("res") / "summary.json").read_text())["created_utc"] >= first
    assert sorted(p.name for p in Path(".").iterdir() if p.name.startswith(".")) == []


def test_existing_user_folder_is_refused_unless_forced(case, capsys):
    user = Path("mine")
    user.mkdir()
    (user / "report.docx").write_bytes(b"the user's work")
    (user / "summary.json").write_text('{"mine": true}')
    before = snapshot(user)
    code, out, err = run(capsys, "solve", case, "--output", user)
    assert_one_line_error(code, out, err, "mine", "not a sarfe result", "--force")
    assert snapshot(user) == before
    code, out, err = run(capsys, "validate", case, "--output", user)
    assert_one_line_error(code, out, err, "not a sarfe result")
    assert run(capsys, "solve", case, "--output", user, "--force", "--quiet")[0] == 0
    assert is_sarfe_result(user) and not (user / "report.docx").exists()


def test_empty_folder_is_used(case, capsys):
    Path("empty").mkdir()
    assert run(capsys, "solve", case, "--output", "empty", "--quiet")[0] == 0
    assert (Path("empty") / "summary.json").is_file()


@pytest.mark.parametrize("force", [False, True])
def test_current_directory_is_never_the_output(case, capsys, force):
    before = snapshot(Path("."))
    extra = ["--force"] if force else []
    for target in (".", str(Path.cwd()), ".."):
        code, out, err = run(capsys, "solve", case, "--output", target, *extra)
        assert_one_line_error(code, out, err, "current directory")
    assert snapshot(Path(".")) == before


@pytest.mark.parametrize("force", [False, True])
def test_case_folder_is_never_the_output(case, capsys, force):
    before = snapshot(case.parent)
    extra = ["--force"] if force else []
    code, out, err = run(capsys, "solve", case, "--output", case.parent, *extra)
    assert_one_line_error(code, out, err, "folder of", "tiny.yaml")
    assert snapshot(case.parent) == before


def test_existing_file_is_not_an_output_folder(case, capsys):
    Path("report.txt").write_text("keep me")
    for extra in ([], ["--force"]):
        code, out, err = run(capsys, "solve", case, "--output", "report.txt", *extra)
        assert_one_line_error(code, out, err, "report.txt", "existing file")
    assert Path("report.txt").read_text() == "keep me"
    assert [p.name for p in Path(".").iterdir() if p.name.startswith(".report")] == []


def test_read_only_location_fails_before_the_solve(case, capsys):
    """A folder nobody may write into: the check runs before the solve (no table printed).
    As root, permissions do not stop writes, so the CLI runs as 'nobody' in a subprocess."""
    base = Path(tempfile.mkdtemp(prefix="sarfe-ro-"))
    try:
        shutil.copy(case, base / "tiny.yaml")
        locked = base / "locked"
        locked.mkdir()
        os.chmod(base, 0o755)
        os.chmod(base / "tiny.yaml", 0o644)
        os.chmod(locked, 0o555)
        argv = ["solve", str(base / "tiny.yaml"), "--output", str(locked / "out")]
        if os.geteuid() != 0:
            code, out, err = run(capsys, *argv)
        else:
            setpriv = shutil.which("setpriv")
            if setpriv is None:
                pytest.skip("running as root without setpriv: cannot drop write permission")
            home = base / "home"
            home.mkdir()
            os.chmod(home, 0o777)
            env = dict(os.environ, PYTHONPATH=str(ROOT), HOME=str(home), MPLCONFIGDIR=str(home))
            proc = subprocess.run([setpriv, "--reuid=65534", "--regid=65534", "--clear-groups",
                                   sys.executable, "-m", "sarfe.cli", *argv], cwd=base, env=env,
                                  capture_output=True, text=True, timeout=120)
            code, out, err = proc.returncode, proc.stdout, proc.stderr
        assert_one_line_error(code, out, err, "not writable", "locked")
        assert "solving" not in out and list(locked.iterdir()) == []
    finally:
        os.chmod(locked, 0o755)
        shutil.rmtree(base)


def test_unwritable_output_found_by_validate(case, capsys, monkeypatch):
    """The writability probe creates a file; where that fails, validate says so (in-process)."""
    import sarfe.results.folder as rf

    def refuse(folder):
        raise PermissionError(13, "Permission denied")
    monkeypatch.setattr(rf, "_probe_writable", refuse)
    code, out, err = run(capsys, "validate", case, "--output", "somewhere")
    assert_one_line_error(code, out, err, "not writable", "Permission denied")


def write_files(tag):
    def write(folder):
        for name in ("a.txt", "b.txt", "c.txt"):
            (folder / name).write_text(tag)
    return write


def test_failed_final_move_restores_the_previous_result(tmp_path):
    """A kill during the final move, simulated by a rename that fails after the old result was
    set aside: the old result is renamed back, the new one is removed by the caller."""
    target = tmp_path / "res"
    write_result_folder(target, write_files("old"), marker_info("solve", "t"))
    temporary = tmp_path / ".res.tmp-1-x"
    temporary.mkdir()
    write_files("new")(temporary)
    calls = []

    def rename(src, dst):
        calls.append((Path(src).name, Path(dst).name))
        if len(calls) == 2:      # the second rename (new result into place) dies
            raise OSError("killed during the move")
        os.rename(src, dst)
    with pytest.raises(OSError, match="killed"):
        replace_directory(temporary, target, rename=rename)
    assert (target / "a.txt").read_text() == "old" and is_sarfe_result(target)
    assert [p.name for p in tmp_path.iterdir() if ".old-" in p.name] == []


def test_failed_write_leaves_the_previous_result(tmp_path):
    target = tmp_path / "res"
    write_result_folder(target, write_files("old"), marker_info("solve", "t"))

    def crash(folder):
        (folder / "a.txt").write_text("half")
        raise RuntimeError("disk full")
    with pytest.raises(RuntimeError):
        write_result_folder(target, crash, marker_info("solve", "t"))
    assert snapshot(target)["a.txt"] == b"old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["res"]


WRITER = textwrap.dedent("""
    import sys, time
    from pathlib import Path
    from sarfe.results.folder import marker_info, write_result_folder
    target, tag, rounds = Path(sys.argv[1]), sys.argv[2], int(sys.argv[3])
    def write(folder):
        for i in range(20):
            (folder / f"part{i}.txt").write_text(tag * 1000)
        time.sleep(float(sys.argv[4]))
    for _ in range(rounds):
        write_result_folder(target, write, marker_info("solve", tag))
""")


def spawn(*args):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.Popen([sys.executable, "-c", WRITER, *map(str, args)], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def test_concurrent_writers_leave_one_whole_result(tmp_path):
    target = tmp_path / "res"
    writers = [spawn(target, tag, 15, 0.0) for tag in "AB"]
    for proc in writers:
        out, err = proc.communicate(timeout=120)
        assert proc.returncode == 0, err
    files = snapshot(target)
    tags = {content[:1] for name, content in files.items() if name.startswith("part")}
    assert len(files) == 21 and len(tags) == 1                     # one writer's whole result
    assert json.loads(files[MARKER])["case"] == tags.pop().decode()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["res"]   # no temporaries left


def test_two_sarfe_solves_into_one_folder(case, tmp_path):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    procs = [subprocess.Popen([sys.executable, "-m", "sarfe.cli", "solve", str(case), "--output",
                               "res", "--quiet"], cwd=tmp_path, env=env, stderr=subprocess.PIPE,
                              text=True) for _ in range(2)]
    for proc in procs:
        assert proc.wait(timeout=300) == 0, proc.stderr.read()
    summary = json.loads((tmp_path / "res" / "summary.json").read_text())
    assert summary["case"] == "tiny" and is_sarfe_result(tmp_path / "res")
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".res.")]


def test_killed_writer_debris_is_cleaned_by_the_next_run(tmp_path):
    target = tmp_path / "res"
    proc = spawn(target, "K", 1, 60.0)           # writes, then sleeps inside the temporary folder
    deadline = time.time() + 60
    while not any(p.name.startswith(".res.tmp-") and (p / "part19.txt").exists()
                  for p in tmp_path.iterdir()):
        assert time.time() < deadline and proc.poll() is None
        time.sleep(0.05)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    stale = [p for p in tmp_path.iterdir() if p.name.startswith(".res.tmp-")]
    assert len(stale) == 1 and str(proc.pid) in stale[0].name
    # not sarfe's (no marker) or of a live process: kept
    foreign = tmp_path / ".res.tmp-1-abcd"
    foreign.mkdir()
    live = tmp_path / f".res.tmp-{os.getpid()}-beef"
    live.mkdir()
    (live / MARKER).write_text(json.dumps(marker_info("solve", "x")))
    write_result_folder(tmp_path / "other", write_files("next"), marker_info("solve", "t"))
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == sorted(["other", foreign.name, live.name])   # any target's debris


def test_backup_of_a_run_killed_between_its_renames_is_put_back(tmp_path):
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    backup = tmp_path / f".res.old-{dead.pid}-0a0b"
    backup.mkdir()
    write_files("previous")(backup)
    (backup / MARKER).write_text(json.dumps(dict(marker_info("solve", "t"), pid=dead.pid)))
    clean_stale(tmp_path, "res")
    assert (tmp_path / "res" / "a.txt").read_text() == "previous"


def test_home_directory_is_never_the_output(tmp_path, monkeypatch):
    home = tmp_path / "users" / "home"
    home.mkdir(parents=True)
    (home / "thesis.tex").write_text("years of work")
    monkeypatch.setenv("HOME", str(home))
    (tmp_path / "work").mkdir()
    monkeypatch.chdir(tmp_path / "work")
    for target in (home, tmp_path / "users"):
        with pytest.raises(CaseError, match="home directory"):
            check_output_folder(target, force=True)
    assert (home / "thesis.tex").read_text() == "years of work"


def test_check_is_silent_on_disk(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    target = check_output_folder("a/b/c")
    assert target == tmp_path / "a" / "b" / "c" and list(tmp_path.iterdir()) == []
    with pytest.raises(CaseError, match="current directory"):
        check_output_folder(tmp_path / "x" / "..")


# ------------------------------------------------------------------------------------- batch
def test_batch_never_overwrites_the_users_summary(case, capsys):
    from sarfe.batch.cli import main as batch_main

    user = Path("mine")
    user.mkdir()
    (user / "summary.json").write_text('{"mine": true}')
    (user / "results.csv").write_text("a,b\n1,2\n")
    before = snapshot(user)
    code = batch_main(["--workers", "0", "--output", str(user), str(case)])
    err = capsys.readouterr().err
    assert code == 2 and "not a sarfe result" in err and len(err.strip().splitlines()) == 1
    assert snapshot(user) == before
    code = batch_main(["--workers", "0", "--output", ".", str(case)])
    assert code == 2 and "current directory" in capsys.readouterr().err
    code = batch_main(["--workers", "0", "--output", "out", str(case)])
    assert code == 0, capsys.readouterr().err
    assert json.loads((Path("out") / MARKER).read_text())["kind"] == "batch"
    assert batch_main(["--workers", "0", "--output", "out", str(case)]) == 0   # resumes there


def test_debris_of_versions_before_the_marker(tmp_path):
    """`.res.tmp-xxxxxxxx` (mkdtemp) a day old with only result files, and `.res.old-<dead pid>`:
    removed; a fresh one, or one holding anything else, kept."""
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    (tmp_path / "res").mkdir()
    old_tmp, new_tmp, foreign = (tmp_path / f".res.tmp-{s}" for s in ("ab12cd34", "ef56gh78",
                                                                       "ij90kl12"))
    backup = tmp_path / f".res.old-{dead.pid}"
    for folder in (old_tmp, new_tmp, foreign, backup):
        folder.mkdir()
        (folder / "summary.json").write_text("{}")
    (foreign / "thesis.tex").write_text("mine")
    day_ago = time.time() - 2 * 86400
    for folder in (old_tmp, foreign):
        os.utime(folder, (day_ago, day_ago))
    clean_stale(tmp_path, "res")
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(["res", new_tmp.name, foreign.name])


# ------------------------------------------------------------- a re-run keeps the user's own files
def fe_case(folder: Path) -> Path:
    """The rattle rig (FE, generated mesh) coarsened to 2 frequencies: a result with the erp/ and
    animation/ subfolders in a few seconds."""
    import yaml

    data = yaml.safe_load((ROOT / "cases" / "rattle_rig.yaml").read_text())
    data["model"]["fe"]["generator"]["mesh_size_m"] = 0.02
    data["excitation"].pop("sweep")
    data["excitation"]["frequency_hz"] = [31.0, 26.0]
    data["solver"].update(harmonics=3, error_estimate=False, stability=False)
    data["output"] = {"files": ["summary", "table", "erp_vtu", "animation"], "maps": {"every": 1}}
    folder.mkdir()
    path = folder / "rig.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def test_user_files_in_an_earlier_result_survive_a_rerun(tmp_path, monkeypatch, capsys):
    """Finding 1 of review8: a note at the top level and one in sarfe's own erp/ folder are
    refused by solve and validate with the same line (folder untouched, byte for byte); --force
    replaces the folder and deletes them."""
    from sarfe.results.folder import _solve_rule

    case = fe_case(tmp_path / "case")
    monkeypatch.chdir(tmp_path)
    assert run(capsys, "solve", case, "--output", "res", "--quiet")[0] == 0
    listed = json.loads((Path("res") / MARKER).read_text())["files"]
    on_disk = sorted(str(p.relative_to("res")) + ("/" if p.is_dir() else "")
                     for p in Path("res").rglob("*") if p.name != MARKER)
    assert sorted(listed) == on_disk and {"erp/", "animation/", "summary.json"} <= set(listed)
    # the documented layout (by which markers without a file list are judged) covers the writer
    assert all(_solve_rule(name, None) for name in listed)
    (Path("res") / "notes.txt").write_text("my notes")
    (Path("res") / "erp" / "notes.txt").write_text("which map is which")
    before = snapshot(Path("res"))
    code, out, err = run(capsys, "solve", case, "--output", "res", "--quiet")
    assert_one_line_error(code, out, err, "res", "'erp/notes.txt', 'notes.txt'",
                          "did not write", "--force", "delete those files")
    assert snapshot(Path("res")) == before
    code, out, err2 = run(capsys, "validate", case, "--output", "res")
    assert_one_line_error(code, out, err2)
    assert err2 == err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["case", "res"]   # nothing written
    assert run(capsys, "solve", case, "--output", "res", "--quiet", "--force")[0] == 0
    assert not (Path("res") / "notes.txt").exists() and not (Path("res") / "erp" / "notes.txt").exists()
    assert is_sarfe_result(Path("res"))


def test_a_clean_rerun_replaces_and_a_foreign_folder_inside_is_named_once(case, capsys):
    assert run(capsys, "solve", case, "--output", "res", "--quiet")[0] == 0
    (Path("res") / "table.txt").write_text("edited")            # sarfe's name: still sarfe's
    assert run(capsys, "solve", case, "--output", "res", "--quiet")[0] == 0   # clean: replaced
    assert (Path("res") / "table.txt").read_text() != "edited"
    assert json.loads((Path("res") / MARKER).read_text())["files"] == ["summary.json", "table.txt"]
    (Path("res") / "mine").mkdir()
    for name in ("a.txt", "b.txt"):
        (Path("res") / "mine" / name).write_text(name)
    for name in ("z1.txt", "z2.txt", "z3.txt"):
        (Path("res") / name).write_text(name)
    before = snapshot(Path("res"))
    code, out, err = run(capsys, "solve", case, "--output", "res")
    assert_one_line_error(code, out, err, "'mine/', 'z1.txt', 'z2.txt' and 1 more")
    assert snapshot(Path("res")) == before


def test_a_marker_without_a_file_list_is_judged_by_the_documented_layout(case, capsys):
    """Results of sarfe versions whose marker had no file list, or no marker at all: sarfe's
    documented names (erp/erp_NNNN.vtu, animation/deflection_NNN.vtu, …) are replaceable,
    anything else is foreign."""
    old = Path("old")
    (old / "erp").mkdir(parents=True)
    (old / "animation").mkdir()
    (old / MARKER).write_text(json.dumps({"sarfe_version": "0.0.9", "kind": "solve", "case": "t"}))
    for name in ("summary.json", "table.txt", "report.html", "erp/erp.pvd", "erp/erp_0000.vtu",
                 "erp/erp_0001.vtu", "animation/deflection.pvd", "animation/deflection_000.vtu"):
        (old / name).write_text("{}")
    premarker = Path("premarker")
    premarker.mkdir()
    (premarker / "summary.json").write_text(json.dumps({"sarfe_version": "0.0.1", "case": "t"}))
    (premarker / "table.txt").write_text("table")
    assert is_sarfe_result(old) and is_sarfe_result(premarker)
    (old / "animation" / "deflection.png").write_text("my screenshot")
    (premarker / "notes.txt").write_text("mine")
    for folder, foreign in ((old, "'animation/deflection.png'"), (premarker, "'notes.txt'")):
        before = snapshot(folder)
        code, out, err = run(capsys, "solve", case, "--output", folder)
        assert_one_line_error(code, out, err, foreign, "did not write")
        assert snapshot(folder) == before
    (old / "animation" / "deflection.png").unlink()
    assert run(capsys, "solve", case, "--output", old, "--quiet")[0] == 0
    assert sorted(p.name for p in old.iterdir()) == sorted([MARKER, "summary.json", "table.txt"])


def test_a_file_put_into_the_result_during_the_run_is_kept(tmp_path):
    target = tmp_path / "res"
    write_result_folder(target, write_files("old"), marker_info("solve", "t"))

    def write(folder):
        write_files("new")(folder)
        (target / "notes.txt").write_text("written while sarfe ran")
    with pytest.raises(CaseError, match="changed during the run.*notes.txt|notes.txt.*changed during"):
        write_result_folder(target, write, marker_info("solve", "t"))
    assert (target / "notes.txt").read_text() == "written while sarfe ran"
    assert (target / "a.txt").read_text() == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["res"]


def test_batch_folder_with_a_user_file_is_refused_and_a_clean_one_resumes(case, capsys):
    """The batch folder (written in place) and its variant_outputs/<id>/ results follow the same
    rule; a batch never writes into a solve result."""
    from sarfe.batch.cli import main as batch_main

    argv = ["--workers", "0", "--write-variant-outputs", "--output", "out", str(case)]
    assert batch_main(argv) == 0, capsys.readouterr().err
    (variant,) = list((Path("out") / "variant_outputs").iterdir())
    assert is_sarfe_result(Path("out")) and is_sarfe_result(variant)
    assert batch_main(argv) == 0, capsys.readouterr().err                  # resumes there
    capsys.readouterr()
    (variant / "mine.txt").write_text("notes")
    (Path("out") / "notes.txt").write_text("notes")
    before = snapshot(Path("out"))
    assert batch_main(argv) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1, err
    assert f"'notes.txt', 'variant_outputs/{variant.name}/mine.txt'" in err and "--force" in err
    assert snapshot(Path("out")) == before
    (variant / "mine.txt").unlink()
    (Path("out") / "notes.txt").unlink()
    assert batch_main(argv) == 0, capsys.readouterr().err
    assert run(capsys, "solve", case, "--output", "res", "--quiet")[0] == 0
    assert batch_main(["--workers", "0", "--output", "res", str(case)]) == 2
    assert "not a batch folder" in capsys.readouterr().err
