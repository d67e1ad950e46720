r"""Write a `PanelMesh` as a Nastran bulk-data deck (the cards a trim engineer's deck has).

Used to check the deck path against the generator path on the same model (tests) and to give
users a deck of a generated panel. Large-field fixed format (``GRID*`` …, 16-character fields),
written in a consistent unit system (default ``mm-t-s``: mm, t, s, N, MPa).

=================== ====================================================================
cards               what
=================== ====================================================================
GRID                every mesh node, id = index + 1 (``grid_ids``)
CQUAD4 / CTRIA3     two triangles of one property that share an edge and are oriented
                    alike are written as one CQUAD4 (a, b, c, d) whose split (a, b, c),
                    (a, c, d) gives the same two triangles back; the rest as CTRIA3
PSHELL / MAT1       one per property (MID2 = MID1, 12I/T³ = 1: bending included)
RBE2 + CBUSH        a *rigid clip*: the clip's rim nodes hang on a spider (RBE2, CM 123456)
+ CONM2             from a centre GRID, which a stiff CBUSH ties to a grounded GRID; the
                    clip's own mass is a CONM2 on the centre GRID
SPC1                set 1: ground GRIDs of the clips and the nodes of `clamped` groups
SET1                one per node group named in `node_sets` (ids from 101, in order)
=================== ====================================================================

With a bush stiffness far above the panel's local stiffness, a clip written this way holds
its rim as a clamp does, so the deck and the generator model give the same response.
"""
from __future__ import annotations

import fnmatch
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from sarfe.mesh.formats.deck import UNIT_SYSTEMS
from sarfe.mesh.mesh import PanelMesh


@dataclass(frozen=True)
class ShellProperty:
    """A shell property of the element groups matching `group` ('*' = all; later entries
    win): E [Pa], ν, ρ [kg/m³], thickness [m] (SI; converted on writing)."""

    group: str
    young: float
    poisson: float
    density: float
    thickness: float


@dataclass(frozen=True)
class WrittenDeck:
    """What :func:`write_panel_deck` wrote: the file, the SET1 id of each named node group,
    the PSHELL id of each property (in `properties` order), the SPC set id and the ids of the
    clips' CBUSH elements {clip group: element id}."""

    path: Path
    set_ids: dict
    property_ids: list
    spc_set: int
    bush_ids: dict


def _field16(value) -> str:
    if value is None:
        return " " * 16
    if isinstance(value, str):
        return f"{value:<16}"
    if isinstance(value, (int, np.integer)):
        return f"{int(value):>16d}"
    value = float(value)
    if value == 0.0:
        return f"{'0.0':>16}"
    return f"{value:>16.9E}" if value < 0 else f"{value:>16.10E}"


def _card(name: str, fields) -> list[str]:
    """Lines of one large-field card: 4 fields on the first line, 4 per continuation."""
    fields = list(fields)
    lines, head = [], f"{name + '*':<8}"
    for start in range(0, max(len(fields), 1), 4):
        chunk = "".join(_field16(v) for v in fields[start:start + 4])
        lines.append((head if start == 0 else f"{'*':<8}") + chunk)
    return lines


def pair_triangles(triangles, owner):
    """Quads (q, 4), the triangle row that gives each quad its property (q,), and leftover
    triangle rows (r,) of a triangle mesh.

    Two triangles pair when they share an edge, have the same `owner` (property) and the
    same orientation (the edge runs opposite ways in them). The quad (a, b, c, d) is built so
    that (a, b, c) and (a, c, d) are the two triangles with their node order.
    """
    triangles = np.asarray(triangles, dtype=np.int64)
    used = np.zeros(len(triangles), dtype=bool)
    edge_of = {}
    for t, tri in enumerate(triangles):
        for k in range(3):
            edge_of[(int(tri[k]), int(tri[(k + 1) % 3]))] = (t, k)
    quads = []
    for t, tri in enumerate(triangles):
        if used[t]:
            continue
        for k in range(3):
            p, q = int(tri[k]), int(tri[(k + 1) % 3])
            other = edge_of.get((q, p))
            if other is None or used[other[0]] or other[0] == t or owner[other[0]] != owner[t]:
                continue
            s, j = other
            r = int(tri[(k + 2) % 3])                    # t = (p, q, r) ≡ (q, r, p)
            x = int(triangles[s][(j + 2) % 3])           # s = (q, p, x)
            quads.append((q, r, p, x, t))                # (a, b, c) = t, (a, c, d) = s
            used[t] = used[s] = True
            break
    quad_nodes = np.array([q[:4] for q in quads], dtype=np.int64).reshape(-1, 4)
    quad_owner = np.array([q[4] for q in quads], dtype=np.int64)
    return quad_nodes, quad_owner, np.flatnonzero(~used)


def write_panel_deck(path, mesh: PanelMesh, properties, *, clips=(), clamped=(), node_sets=(),
                     clip_stiffness_N_m: float = 1e10, clip_rotational_stiffness_Nm_rad: float = 1e8,
                     clip_mass_kg: float = 0.002, units: str = "mm-t-s") -> WrittenDeck:
    """Write `mesh` as a Nastran deck (module docstring) and return :class:`WrittenDeck`.

    properties: [ShellProperty, …] (every triangle must match one); clips: node-group names or
    patterns written as rigid clips (RBE2 + CBUSH + CONM2); clamped: node groups held in all six
    DOFs by SPC1; node_sets: node groups written as SET1 cards (contacts, excitation).
    """
    system = UNIT_SYSTEMS[units]
    length, modulus = 1 / system.factor(1), 1 / system.factor(-1, 1, -2)
    density, mass_unit = 1 / system.factor(-3, 1), 1 / system.factor(0, 1)
    k_unit, kr_unit = 1 / system.factor(0, 1, -2), 1 / system.factor(2, 1, -2)

    def match(names, pattern):
        return [g for g in names if fnmatch.fnmatchcase(g, pattern)]

    owner = np.full(mesh.n_triangles, -1)
    for j, prop in enumerate(properties):
        groups = ["*"] if prop.group == "*" else match(mesh.element_groups, prop.group)
        if not groups:
            raise ValueError(f"no element group matches {prop.group!r}")
        for g in groups:
            owner[slice(None) if g == "*" else mesh.element_groups[g]] = j
    if np.any(owner < 0):
        raise ValueError(f"{np.count_nonzero(owner < 0)} triangles have no property")

    lines = ["$ written by sarfe.mesh.formats.nastran_writer from a sarfe PanelMesh",
             f"$ units: {units}", "SOL 103", "CEND", "SPC = 1", "BEGIN BULK"]
    grid = np.arange(mesh.n_nodes) + 1
    for i, x in enumerate(mesh.points * length):
        lines += _card("GRID", [int(grid[i]), None, *x])
    quads, quad_owner, single = pair_triangles(mesh.triangles, owner)
    eid = 0
    for nodes, o in zip(quads, quad_owner):
        eid += 1
        lines += _card("CQUAD4", [eid, int(owner[o]) + 1, *(grid[nodes].tolist())])
    for t in single:
        eid += 1
        lines += _card("CTRIA3", [eid, int(owner[t]) + 1, *(grid[mesh.triangles[t]].tolist())])
    for j, prop in enumerate(properties):
        lines += _card("PSHELL", [j + 1, j + 1, prop.thickness * length, j + 1, 1.0])
        lines += _card("MAT1", [j + 1, prop.young * modulus, None, prop.poisson,
                                prop.density * density])

    next_grid = mesh.n_nodes + 1
    spc_nodes, bush_ids = [], {}
    clip_groups = [g for pattern in clips for g in match(mesh.node_groups, pattern)]
    for k, name in enumerate(clip_groups):
        rim = mesh.node_groups[name]
        centre = mesh.points[rim].mean(axis=0) * length
        hub, ground = next_grid, next_grid + 1
        next_grid += 2
        lines += [f"$ clip {name}: spider {hub}, ground {ground}"]
        lines += _card("GRID", [hub, None, *centre])
        lines += _card("GRID", [ground, None, *centre])
        eid += 1
        lines += _card("RBE2", [eid, hub, 123456, *(grid[rim].tolist())])
        eid += 1
        bush_ids[name] = eid
        lines += _card("CBUSH", [eid, 9001, hub, ground, None, None, None, 0])
        eid += 1
        lines += _card("CONM2", [eid, hub, 0, clip_mass_kg * mass_unit])
        spc_nodes.append(ground)
    if clip_groups:
        lines += _card("PBUSH", [9001, "K", *([clip_stiffness_N_m * k_unit] * 3),
                                 *([clip_rotational_stiffness_Nm_rad * kr_unit] * 3)])
    for pattern in clamped:
        for name in match(mesh.node_groups, pattern):
            spc_nodes += grid[mesh.node_groups[name]].tolist()
    if spc_nodes:
        lines += _card("SPC1", [1, 123456, *sorted(set(spc_nodes))])
    set_ids = {}
    for name in node_sets:
        set_ids[name] = 101 + len(set_ids)
        lines += [f"$ SET1 {set_ids[name]} = {name}"]
        lines += _card("SET1", [set_ids[name], *grid[mesh.node_group(name)].tolist()])
    lines.append("ENDDATA")
    path = Path(path)
    path.write_text("\n".join(lines) + "\n", encoding="ascii")
    return WrittenDeck(path, set_ids, list(range(1, len(properties) + 1)), 1, bush_ids)

