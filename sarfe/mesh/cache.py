"""On-demand generation of generated meshes with a file cache keyed by parameters (used by
``sarfe solve`` / ``validate`` for every ``model.fe.generator`` case).

`cached_mesh("door_trim", mesh_size=0.005)` returns the mesh from
``<cache_dir>/door_trim-<key>.msh`` if present and intact, otherwise generates it (binary Gmsh
4.1, exact doubles, so a cached mesh equals a freshly generated one bit for bit) and stores it.
The key hashes generator name, mesh size, parameters, `CACHE_VERSION` and the gmsh version.
Cache directory: argument, else $SARFE_MESH_CACHE, else ~/.cache/sarfe/meshes (no cache, only
generation, when it cannot be created).

Integrity: ``<name>.sha256`` beside each mesh holds the SHA-256 of its bytes; a mesh whose
checksum is missing or wrong, or that gmsh cannot read, is generated again. Both files are
written to temporary names ``.<name>.tmp-<pid>-<random>`` and renamed into place (the mesh first,
its checksum last), so a reader never sees half a file. Temporary files of killed runs (their PID
gone) are removed by the next call; so are the 0-byte ``tmp*.msh`` of older versions once a day old.
"""
from __future__ import annotations

import hashlib
import importlib
import json
import os
import re
import secrets
import time
from pathlib import Path

from sarfe.mesh.generators import GENERATORS
from sarfe.mesh.io import load_mesh
from sarfe.mesh.mesh import PanelMesh

CACHE_VERSION = 1  # bump when a generator's geometry changes
_TEMPORARY = re.compile(r"^\..+\.tmp-(?P<pid>\d+)-[0-9a-f]+(\.msh|\.sha256)$")
_LEGACY_TEMPORARY = re.compile(r"^tmp[A-Za-z0-9_]+\.msh$")
_LEGACY_AGE_S = 86400.0


def cache_key(generator: str, mesh_size: float, params: dict) -> str:
    """Hex key (16 chars) of everything the generated mesh depends on."""
    import gmsh

    payload = json.dumps({"generator": generator, "mesh_size": float(mesh_size),
                          "params": {k: params[k] for k in sorted(params)},
                          "version": CACHE_VERSION, "gmsh": gmsh.__version__},
                         sort_keys=True, default=float)
    return hashlib.sha256(payload.encode()).hexdigest()[:16]


def default_cache_dir() -> Path:
    env = os.environ.get("SARFE_MESH_CACHE")
    return Path(env) if env else Path.home() / ".cache" / "sarfe" / "meshes"


def file_sha256(path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def pid_alive(pid: int) -> bool:
    """True when a process ``pid`` exists on this machine (or we may not signal it)."""
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def clean_stale(directory) -> list:
    """Remove temporary files of killed cache writers in ``directory`` (module docstring)."""
    removed = []
    try:
        entries = list(Path(directory).iterdir())
    except OSError:
        return removed
    now = time.time()
    for entry in entries:
        match = _TEMPORARY.match(entry.name)
        try:
            if match:
                stale = not pid_alive(int(match["pid"]))
            elif _LEGACY_TEMPORARY.match(entry.name):
                info = entry.stat()
                stale = info.st_size == 0 and now - info.st_mtime > _LEGACY_AGE_S
            else:
                continue
            if stale and entry.is_file():
                entry.unlink()
                removed.append(entry)
        except OSError:
            continue
    return removed


def _intact(path: Path, checksum: Path) -> bool:
    try:
        return checksum.read_text().split()[0] == file_sha256(path)
    except (OSError, IndexError):
        return False


def cached_mesh(generator: str, mesh_size: float, cache_dir=None, **params) -> PanelMesh:
    """Mesh of `sarfe.mesh.generators.<generator>` for these parameters, generated at most once
    (again only when the cached file is damaged)."""
    if generator not in GENERATORS:
        raise ValueError(f"unknown generator {generator!r}; available: {', '.join(GENERATORS)}")
    module = importlib.import_module(f"sarfe.mesh.generators.{generator}")
    directory = Path(cache_dir) if cache_dir is not None else default_cache_dir()
    name = f"{generator}-{cache_key(generator, mesh_size, params)}"
    path, checksum = directory / f"{name}.msh", directory / f"{name}.sha256"
    if path.is_file() and _intact(path, checksum):
        try:
            return load_mesh(path)
        except Exception:  # noqa: BLE001 - unreadable despite its checksum: generate again
            pass
    try:
        directory.mkdir(parents=True, exist_ok=True)
        clean_stale(directory)
    except OSError:  # no cache possible here: generate only
        return module.generate(mesh_size=mesh_size, **params)
    token = f"tmp-{os.getpid()}-{secrets.token_hex(4)}"
    partial = directory / f".{name}.{token}.msh"
    partial_sum = directory / f".{name}.{token}.sha256"
    try:
        mesh = module.generate(mesh_size=mesh_size, path=partial, **params)
        partial_sum.write_text(f"{file_sha256(partial)}  {path.name}\n")
        os.replace(partial, path)          # atomic: concurrent workers never see half a file
        os.replace(partial_sum, checksum)  # last: a mesh without its checksum is not trusted
    finally:
        for leftover in (partial, partial_sum):
            if leftover.exists():
                leftover.unlink()
    return mesh
