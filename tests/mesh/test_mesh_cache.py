"""The generated-mesh cache (sarfe.mesh.cache): checksummed, regenerated when damaged, written
atomically, its debris of killed runs cleaned, and used by `sarfe solve` / `validate`."""
import os
import subprocess
import sys
import time

import numpy as np

from sarfe.mesh.cache import cache_key, cached_mesh, clean_stale, file_sha256

PARAMS = {"gap": 1e-3}


def cache_files(directory):
    return sorted(p.name for p in directory.iterdir())


def dead_pid():
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def test_checksum_written_and_damaged_mesh_regenerated(tmp_path):
    fresh = cached_mesh("rattle_rig", 0.02, cache_dir=tmp_path, **PARAMS)
    name = f"rattle_rig-{cache_key('rattle_rig', 0.02, PARAMS)}"
    assert cache_files(tmp_path) == [f"{name}.msh", f"{name}.sha256"]
    msh = tmp_path / f"{name}.msh"
    assert (tmp_path / f"{name}.sha256").read_text().split()[0] == file_sha256(msh)
    good = msh.read_bytes()
    for damage in (lambda b: b[: len(b) // 2], lambda b: b[:100] + bytes([b[100] ^ 0xFF]) + b[101:], lambda b: b""):
        msh.write_bytes(damage(good))
        again = cached_mesh("rattle_rig", 0.02, cache_dir=tmp_path, **PARAMS)
        assert msh.read_bytes() == good                       # regenerated bit for bit
        assert again.points.tobytes() == fresh.points.tobytes()
        assert np.array_equal(again.triangles, fresh.triangles)
    (tmp_path / f"{name}.sha256").unlink()                  # a mesh without checksum: not trusted
    mtime = msh.stat().st_mtime_ns
    time.sleep(0.01)
    cached_mesh("rattle_rig", 0.02, cache_dir=tmp_path, **PARAMS)
    assert msh.stat().st_mtime_ns != mtime and (tmp_path / f"{name}.sha256").is_file()


def test_intact_cache_is_read_not_regenerated(tmp_path):
    cached_mesh("rattle_rig", 0.02, cache_dir=tmp_path, **PARAMS)
    stamps = {p.name: p.stat().st_mtime_ns for p in tmp_path.iterdir()}
    cached_mesh("rattle_rig", 0.02, cache_dir=tmp_path, **PARAMS)
    assert {p.name: p.stat().st_mtime_ns for p in tmp_path.iterdir()} == stamps


def test_debris_of_killed_runs_is_cleaned_only_when_stale(tmp_path):
    dead, alive = dead_pid(), os.getpid()
    stale = tmp_path / f".rattle_rig-0123.tmp-{dead}-abcd.msh"
    live = tmp_path / f".rattle_rig-0123.tmp-{alive}-abcd.msh"
    old_legacy, new_legacy = tmp_path / "tmpa1b2c3.msh", tmp_path / "tmpd4e5f6.msh"
    user = tmp_path / "my_mesh.msh"
    for path in (stale, live, old_legacy, new_legacy, user):
        path.write_bytes(b"")
    day_ago = time.time() - 2 * 86400
    os.utime(old_legacy, (day_ago, day_ago))
    os.utime(user, (day_ago, day_ago))
    removed = clean_stale(tmp_path)
    assert sorted(p.name for p in removed) == sorted([stale.name, old_legacy.name])
    assert live.exists() and new_legacy.exists() and user.exists()
    # the next cached_mesh call cleans too
    stale.write_bytes(b"")
    cached_mesh("rattle_rig", 0.02, cache_dir=tmp_path, **PARAMS)
    assert not stale.exists()


def test_solve_and_validate_use_the_cache(tmp_path, monkeypatch):
    from sarfe.pipeline import load_case
    from sarfe.pipeline.model.case_mesh import load_case_mesh

    monkeypatch.setenv("SARFE_MESH_CACHE", str(tmp_path))
    case = load_case({"name": "c", "model": {"fe": {
        "generator": {"name": "rattle_rig", "mesh_size_m": 0.02, "params": PARAMS},
        "materials": {"*": {"E_Pa": 2.1e11, "nu": 0.3, "rho_kg_m3": 7850}},
        "thickness_m": {"*": 1.5e-3}, "fixed": ["clamp_plate", "clamp_beam"]}},
        "excitation": {"forces": [{"group": "excite_beam", "direction": "z", "force_N": 0.05}],
                       "frequency_hz": 30.0}})
    first = load_case_mesh(case)
    assert [p.suffix for p in sorted(tmp_path.iterdir())] == [".msh", ".sha256"]
    second = load_case_mesh(case)
    assert second.points.tobytes() == first.points.tobytes()
