"""Reading shell meshes from files into `PanelMesh`.

* Gmsh ``.msh`` (v2 / v4) through the gmsh API (keeps z; scikit-fem's loader drops it):
  named physical groups → node groups (all dims) and element groups (surface groups).
* Nastran ``.bdf`` / ``.nas`` / ``.dat`` through meshio: one element group and node group per
  shell property id, named ``pid_<n>``.
* A Nastran/Abaqus file holding anything meshio would drop (springs, masses, rigid elements,
  midside nodes, GRID coordinate systems, parts and instances, supports, loads …) is refused
  with a MeshError naming the cards: such a file is read as a deck (``model.fe.deck``,
  :mod:`sarfe.pipeline.model.deck_model`) with its own properties.
* Abaqus ``.inp`` through meshio: ``*NSET`` → node groups, ``*ELSET`` → element groups
  (element sets of non-shell elements keep only their nodes as a node group).

Only shell triangles (quadrilaterals split in two, higher-order elements reduced to their
corners) and optional tetrahedra are kept; nodes used by no kept element are dropped and all
indices remapped.  Coordinates are scaled from `length_unit` to metres.
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from sarfe.mesh.gmsh_model import assemble_mesh, gmsh_session, mesh_from_gmsh, split_quads
from sarfe.mesh.mesh import PanelMesh
from sarfe.mesh.formats.nastran_bdf import bulk_fields

LENGTH_UNITS = {"m": 1.0, "mm": 1e-3, "cm": 1e-2, "in": 0.0254}

_FORMATS = {".msh": "gmsh", ".bdf": "nastran", ".nas": "nastran", ".dat": "nastran",
            ".fem": "nastran", ".inp": "abaqus"}
_MESHIO_TRIANGLES = ("triangle", "triangle6", "triangle7")
_MESHIO_QUADS = ("quad", "quad8", "quad9")
_MESHIO_TETS = ("tetra", "tetra10")


class MeshError(ValueError):
    """A mesh file is missing, of unknown type or unreadable (one-line message)."""


def load_mesh(path, length_unit: str = "m") -> PanelMesh:
    """Read a shell mesh (`.msh`, `.bdf`/`.nas`/`.dat`, `.inp`) into a `PanelMesh` in metres.

    length_unit: unit of the file's coordinates, one of 'm', 'mm', 'cm', 'in'.
    Raises `MeshError` for a missing, unreadable or element-less file or an unknown unit.
    """
    path = Path(path)
    if length_unit not in LENGTH_UNITS:
        raise MeshError(f"unknown length unit {length_unit!r}; use one of {', '.join(LENGTH_UNITS)}")
    if not path.is_file():
        raise MeshError(f"mesh file not found: {path}")
    fmt = _FORMATS.get(path.suffix.lower())
    if fmt is None:
        raise MeshError(f"unknown mesh file type {path.suffix!r} of {path}; "
                        f"use one of {', '.join(sorted(_FORMATS))}")
    if fmt != "gmsh":
        _refuse_model_cards(path, fmt)
    try:
        mesh = _read_gmsh(path) if fmt == "gmsh" else _read_meshio(path, fmt)
    except MeshError:
        raise
    except (Exception, SystemExit) as error:  # reader exceptions (meshio even exits) → one line
        message = " ".join(str(error).split()) or type(error).__name__
        raise MeshError(f"cannot read {fmt} mesh {path}: {message}") from error
    if mesh.n_triangles == 0 and mesh.tetrahedra is None:
        raise MeshError(f"no shell triangles/quadrilaterals or tetrahedra in {path}")
    scale = LENGTH_UNITS[length_unit]
    return mesh if scale == 1.0 else mesh.scaled(scale)


# what the mesh path reads from a deck (geometry; materials come from the case): anything
# else would be dropped by meshio without a word, so it is refused (use model.fe.deck)
_MESH_CARDS = {"GRID", "CTRIA3", "CQUAD4", "CTETRA", "PSHELL", "PSOLID", "MAT1", "ENDDATA",
               "PARAM", "EIGRL", "BEGIN", "CEND", "SOL", "$"}
_MESH_KEYWORDS = {"NODE", "ELEMENT", "NSET", "ELSET", "HEADING", "PREPRINT", "STEP", "END STEP",
                  "STATIC", "FREQUENCY", "OUTPUT", "NODE OUTPUT", "ELEMENT OUTPUT"}
_MESH_ELEMENTS = {"S3", "S3R", "S4", "S4R", "STRI3", "C3D4", "C3D10", "CPS3", "CPS4", "M3D3",
                  "M3D4", "R3D3", "R3D4", "CAX3", "CAX4P"}   # the last four: as meshio writes


def _refuse_model_cards(path: Path, fmt: str):
    """MeshError naming the first card/keyword a mesh file holds that the mesh path would lose
    (springs, masses, rigid elements, midside nodes, GRID coordinate systems, instances …)."""
    found = {}
    in_bulk = fmt != "nastran"
    with open(path, encoding="utf-8", errors="replace") as handle:
        for number, line in enumerate(handle, start=1):
            text = line.rstrip("\n")
            if fmt == "nastran":
                head = text[:8].split(",")[0].strip().upper().rstrip("*")
                if head.startswith("BEGIN"):
                    in_bulk = True
                    continue
                if not in_bulk or not head or head.startswith(("$", "+", "*")) or text[:1] in " \t+*":
                    continue
                if head == "GRID":
                    fields = bulk_fields(text)
                    cp = fields[2].strip() if len(fields) > 2 else ""
                    if cp not in ("", "0"):
                        raise MeshError(f"{path}:{number}: GRID in coordinate system CP={cp}: the "
                                        "mesh reader keeps raw coordinates; read the file as "
                                        "model.fe.deck")
                if head not in _MESH_CARDS:
                    found.setdefault(head, [0, number])[0] += 1
            elif text.startswith("*") and not text.startswith("**"):
                parts = [p.strip() for p in text[1:].split(",")]
                keyword = " ".join(parts[0].split()).upper()
                if keyword == "ELEMENT":
                    kind = next((p.split("=", 1)[1].strip().upper() for p in parts[1:]
                                 if p.upper().replace(" ", "").startswith("TYPE=")), "")
                    if kind not in _MESH_ELEMENTS:
                        found.setdefault(f"*ELEMENT, TYPE={kind}", [0, number])[0] += 1
                elif keyword not in _MESH_KEYWORDS:
                    found.setdefault(f"*{keyword}", [0, number])[0] += 1
    if found:
        listing = ", ".join(f"{card} ({count}, first at line {line})"
                            for card, (count, line) in sorted(found.items()))
        raise MeshError(f"{path}: the mesh reader keeps only nodes, shells/tetrahedra and sets; "
                        f"it would drop {listing}: read the file as model.fe.deck")


def _read_gmsh(path: Path) -> PanelMesh:
    with gmsh_session() as gmsh:
        gmsh.merge(os.fspath(path))
        mesh = mesh_from_gmsh()
    return merge_repeated_elements(mesh) if _msh_major_version(path) == 2 else mesh


def _msh_major_version(path: Path) -> int | None:
    """Major version of a Gmsh file from its ``$MeshFormat`` header (None if absent)."""
    with open(path, "rb") as handle:
        head = handle.read(256).split()
    if len(head) >= 2 and head[0] == b"$MeshFormat":
        try:
            return int(float(head[1]))
        except ValueError:
            return None
    return None


def merge_repeated_elements(mesh: PanelMesh) -> PanelMesh:
    """The mesh with each repeated element (same node list) kept once, its groups merged.

    MSH 2.2 writes an element once per physical group it belongs to (the format has one
    physical tag per element line), so gmsh reads a triangle in ``skin`` and ``part_carrier``
    as two coincident triangles: twice the stiffness, mass and radiating area.  The copies
    are merged here; an element group then names the one kept element.
    """
    triangles = mesh.triangles
    _, first, owner = np.unique(triangles, axis=0, return_index=True, return_inverse=True)
    owner = np.asarray(owner).reshape(-1)
    tets = mesh.tetrahedra
    if tets is not None:
        _, tet_first = np.unique(tets, axis=0, return_index=True)
        tets = tets[np.sort(tet_first)]
    if len(first) == len(triangles) and (tets is None or len(tets) == len(mesh.tetrahedra)):
        return mesh
    keep = np.sort(first)                       # first copies, in file order
    new_index = np.empty(len(first), dtype=np.int64)
    new_index[np.argsort(first)] = np.arange(len(first))   # unique row → position in `keep`
    element_map = new_index[owner]              # every element (copy or not) → kept element
    groups = {name: np.unique(element_map[rows]) for name, rows in mesh.element_groups.items()}
    return PanelMesh(mesh.points, triangles[keep], mesh.node_groups, groups, tets)


def _read_meshio(path: Path, fmt: str) -> PanelMesh:
    import meshio.abaqus
    import meshio.nastran

    # the format's own reader raises meshio.ReadError; meshio.read() would print it and exit
    reader = meshio.abaqus.read if fmt == "abaqus" else meshio.nastran.read
    data = reader(os.fspath(path))
    triangle_blocks, tetra_blocks = [], []
    # per meshio cell block: rows of its kept elements in the concatenated triangle list
    block_rows, offset = [], 0
    for block in data.cells:
        if block.type in _MESHIO_TRIANGLES:
            triangle_blocks.append(block.data[:, :3])
            block_rows.append(offset + np.arange(len(block.data))[:, None])
            offset += len(block.data)
        elif block.type in _MESHIO_QUADS:
            triangle_blocks.append(block.data[:, :4])
            block_rows.append(offset + split_quads(np.arange(len(block.data))).reshape(-1, 2))
            offset += 2 * len(block.data)
        else:
            if block.type in _MESHIO_TETS:
                tetra_blocks.append(block.data)
            block_rows.append(None)

    node_groups, element_groups = {}, {}
    for name, rows in data.point_sets.items():
        node_groups[name] = np.asarray(rows, dtype=np.int64)

    def add_cells(name, per_block):
        rows, nodes = [], []
        for block, index, kept in zip(data.cells, per_block, block_rows):
            index = np.asarray(index, dtype=np.int64)
            if index.size == 0:
                continue
            nodes.append(np.asarray(block.data)[index].ravel())
            if kept is not None:
                rows.append(kept[index].ravel())
        if rows:
            element_groups[name] = np.concatenate(rows)
        if nodes and name not in node_groups:
            node_groups[name] = np.unique(np.concatenate(nodes))

    for name, per_block in data.cell_sets.items():
        if name.startswith("gmsh:"):
            continue
        add_cells(name, per_block)
    if fmt == "nastran" and "nastran:ref" in data.cell_data:
        refs = [np.asarray(r, dtype=np.int64) for r in data.cell_data["nastran:ref"]]
        pids = np.unique(np.concatenate([r for r, k in zip(refs, block_rows) if k is not None]
                                        or [np.zeros(0, dtype=np.int64)]))
        for pid in pids:
            add_cells(f"pid_{pid}", [np.flatnonzero(r == pid) if k is not None else []
                                     for r, k in zip(refs, block_rows)])
    return assemble_mesh(data.points, triangle_blocks, tetra_blocks, node_groups, element_groups)
