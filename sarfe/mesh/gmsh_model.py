"""The gmsh Python API as used by sarfe: a headless, deterministic session and the
conversion of the current gmsh model's mesh into a `PanelMesh`.

gmsh keeps global state and is not thread safe; every use goes through `gmsh_session`,
which holds a process-wide lock, starts gmsh if needed (no config files, no signal handler,
one thread, fixed random seed) and removes its model (and finalizes gmsh) afterwards.
"""
from __future__ import annotations

import itertools
import threading
from contextlib import contextmanager

import numpy as np

from sarfe.mesh.mesh import PanelMesh

_LOCK = threading.RLock()
_COUNTER = itertools.count()

# gmsh element type → (kind, number of corner nodes kept)
_TRIANGLE_TYPES = {2: 3, 9: 3, 21: 3}      # 3-, 6-, 10-node triangles → corners
_QUAD_TYPES = {3: 4, 10: 4, 16: 4}         # 4-, 9-, 8-node quadrangles → 2 triangles
_TET_TYPES = {4: 4, 11: 10}


def start_gmsh(gmsh, *args, **kwargs):
    """``gmsh.initialize(*args, **kwargs)``, then SIGPIPE back to ignored (Python's setting).

    gmsh's initialize sets SIGPIPE to its default action, for the whole process and beyond
    finalize: a later write to a closed pipe (the queue of a stopped worker process, ``sarfe …
    | head``) then kills the process without a word instead of raising BrokenPipeError (seen as
    ``make: *** Broken pipe`` at the end of the test suite)."""
    import signal

    gmsh.initialize(*args, **kwargs)
    if hasattr(signal, "SIGPIPE"):
        signal.signal(signal.SIGPIPE, signal.SIG_IGN)


@contextmanager
def gmsh_session(random_seed: int = 1):
    """Context with a fresh, empty gmsh model; yields the `gmsh` module."""
    import gmsh

    with _LOCK:
        started = not gmsh.isInitialized()
        if started:
            start_gmsh(gmsh, readConfigFiles=False, interruptible=False)
        previous = None if started else gmsh.model.getCurrent()
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("General.Verbosity", 1)
        gmsh.option.setNumber("General.NumThreads", 1)
        gmsh.option.setNumber("Mesh.RandomSeed", random_seed)
        gmsh.model.add(f"sarfe_{next(_COUNTER)}")
        try:
            yield gmsh
        finally:
            gmsh.model.remove()
            if started:
                gmsh.finalize()
            elif previous:
                gmsh.model.setCurrent(previous)


def assemble_mesh(points, triangle_blocks, tetra_blocks, node_groups, element_groups) -> PanelMesh:
    """`PanelMesh` from raw blocks, keeping only nodes used by a triangle or tetrahedron.

    points          (n, 3) coordinates
    triangle_blocks list of (m, 3|4) arrays of point rows (quads split into (0,1,2), (0,2,3))
    tetra_blocks    list of (k, 4|10) arrays
    node_groups     {name: point rows}, element_groups {name: rows into the concatenated
                    triangles after splitting}
    """
    triangles = []
    for block in triangle_blocks:
        block = np.asarray(block, dtype=np.int64)
        if block.shape[1] == 4:
            block = np.stack([block[:, [0, 1, 2]], block[:, [0, 2, 3]]], axis=1).reshape(-1, 3)
        triangles.append(block)
    triangles = np.concatenate(triangles) if triangles else np.zeros((0, 3), dtype=np.int64)
    tets = [np.asarray(b, dtype=np.int64) for b in tetra_blocks if len(b)]
    widths = {b.shape[1] for b in tets}
    tetrahedra = None
    if tets:
        if len(widths) > 1:  # mixed linear/quadratic: keep corners
            tets = [b[:, :4] for b in tets]
        tetrahedra = np.concatenate(tets)
    used = np.zeros(len(points), dtype=bool)
    used[triangles.ravel()] = True
    if tetrahedra is not None:
        used[tetrahedra.ravel()] = True
    node_map = np.full(len(points), -1, dtype=np.int64)
    node_map[used] = np.arange(used.sum())
    groups = {}
    for name, rows in node_groups.items():
        mapped = node_map[np.asarray(rows, dtype=np.int64)]
        groups[name] = np.unique(mapped[mapped >= 0])
    return PanelMesh(
        points=np.asarray(points, dtype=float)[used],
        triangles=node_map[triangles],
        node_groups=groups,
        element_groups={k: np.unique(np.asarray(v, dtype=np.int64)) for k, v in element_groups.items()},
        tetrahedra=None if tetrahedra is None else node_map[tetrahedra],
    )


def split_quads(elements: np.ndarray) -> np.ndarray:
    """Row indices of the triangles produced by `assemble_mesh` for a block of quads."""
    return np.stack([2 * elements, 2 * elements + 1], axis=1).ravel()


def mesh_from_gmsh() -> PanelMesh:
    """`PanelMesh` of the current gmsh model's mesh.

    Triangles of all surfaces (quads split, higher-order elements reduced to corners) and
    tetrahedra of all volumes, ordered by gmsh element tag; nodes ordered by gmsh node tag.
    Every named physical group becomes a node group (all nodes of its entities, boundaries
    included); physical groups of surfaces are also element groups.
    """
    import gmsh

    tags, coords, _ = gmsh.model.mesh.getNodes(returnParametricCoord=False)
    tags = np.asarray(tags, dtype=np.int64)
    coords = np.asarray(coords, dtype=float).reshape(-1, 3)
    order = np.argsort(tags)
    tags, coords = tags[order], coords[order]
    row_of = np.full(int(tags.max(initial=0)) + 1, -1, dtype=np.int64)
    row_of[tags] = np.arange(len(tags))

    # surface elements, remembering their entity
    element_tags, blocks, entities = [], [], []
    for _, surface in gmsh.model.getEntities(2):
        types, etags, enodes = gmsh.model.mesh.getElements(2, surface)
        for etype, et, en in zip(types, etags, enodes):
            et = np.asarray(et, dtype=np.int64)
            if etype in _TRIANGLE_TYPES or etype in _QUAD_TYPES:
                n_per = len(en) // len(et)
                keep = 3 if etype in _TRIANGLE_TYPES else 4
                nodes = row_of[np.asarray(en, dtype=np.int64).reshape(-1, n_per)[:, :keep]]
                if keep == 4:
                    nodes = np.stack([nodes[:, [0, 1, 2]], nodes[:, [0, 2, 3]]], axis=1).reshape(-1, 3)
                    et = np.repeat(et, 2)
                element_tags.append(et)
                blocks.append(nodes)
                entities.append(np.full(len(et), surface, dtype=np.int64))
    if blocks:
        element_tags = np.concatenate(element_tags)
        triangles = np.concatenate(blocks)
        entity = np.concatenate(entities)
        order = np.argsort(element_tags, kind="stable")
        triangles, entity = triangles[order], entity[order]
    else:
        triangles = np.zeros((0, 3), dtype=np.int64)
        entity = np.zeros(0, dtype=np.int64)

    tet_blocks = []
    for _, volume in gmsh.model.getEntities(3):
        types, etags, enodes = gmsh.model.mesh.getElements(3, volume)
        for etype, et, en in zip(types, etags, enodes):
            if etype in _TET_TYPES:
                n_per = _TET_TYPES[etype]
                tet_blocks.append(row_of[np.asarray(en, dtype=np.int64).reshape(-1, n_per)])

    node_groups, element_groups = {}, {}
    for dim, ptag in gmsh.model.getPhysicalGroups():
        name = gmsh.model.getPhysicalName(dim, ptag) or f"physical_{dim}_{ptag}"
        ntags, _ = gmsh.model.mesh.getNodesForPhysicalGroup(dim, ptag)
        rows = row_of[np.asarray(ntags, dtype=np.int64)]
        node_groups[name] = np.union1d(node_groups.get(name, []), rows).astype(np.int64)
        if dim == 2:
            members = gmsh.model.getEntitiesForPhysicalGroup(dim, ptag)
            idx = np.flatnonzero(np.isin(entity, members))
            element_groups[name] = np.union1d(element_groups.get(name, []), idx).astype(np.int64)
    return assemble_mesh(coords, [triangles], tet_blocks, node_groups, element_groups)
