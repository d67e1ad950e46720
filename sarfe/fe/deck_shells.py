r"""Element blocks (K_e, M_e, DOFs) of a deck's shells (`sarfe.mesh.formats.deck.ShellElements`).

The readers hand shells over as flat facet triangles (CQUAD4/S4 split in two, CTRIA6/CQUAD8 in
4/6 facets through their midside nodes); ``triangle_element`` says which element each came from.
Every triangle carries the bending (DKT, or DKMT where the section gives transverse shear),
the mass and the membrane–bending coupling of :func:`sarfe.fe.shell_section.
section_shell_element_matrices`. The membrane depends on ``membrane``:

- 'nastran' (what the commercial solver does, the deck default): a quadrilateral (2 facets)
  gets the incompatible-mode quad of :mod:`sarfe.fe.shell_quad` on its four corners (a concave
  or degenerate one, :func:`~sarfe.fe.shell_quad.regular_quads`, its two facets as triangles), a
  CTRIA3/S3 the constant-strain triangle, both with the weak drilling penalty
  α C₃₃ ∫ (θz − ω)² dA (Nastran: α = 1e-6 · K6ROT); the facets of 6/8-node elements, whose
  quadratic membrane a CST would lock, the optimal ANDES triangle.
- 'andes' | 'allman' | 'cst': that triangle membrane on every facet
  (:mod:`sarfe.fe.membrane`).

Measured against the commercial solver's stored modes (benchmarks/results/shell_decks.md): a
true drilling membrane (ANDES, Allman) ties a beam or a folded shell to the in-plane rotation
of the shell it meets, which the commercial elements do not — +18 … +20 % on a bar-and-plate
deck's fourth mode, +4.1 … +4.9 % on an exhaust's first; the quad reproduces the commercial
CQUAD4's static membrane response (plate.bdf) to 8e-6. The drilling rotations of the 'nastran'
elements carry no mass (as the commercial lumped mass): a penalty-held DOF with inertia would
give spurious low modes.
"""
from __future__ import annotations

import numpy as np

from sarfe.mesh.formats.deck import DeckError, DeckModel
from sarfe.mesh.laminate import rotate_plane_stress

from sarfe.fe.membrane import MEMBRANES
from sarfe.fe.shell_quad import quad_frames, quad_membrane_matrices, regular_quads
from sarfe.fe.shell_section import section_shell_element_matrices

__all__ = ["DECK_MEMBRANES", "DECK_MEMBRANE", "shell_blocks", "quadrilaterals"]

#: membrane choices for a deck's shells, and the default (the commercial solver's elements)
DECK_MEMBRANES = ("nastran",) + MEMBRANES
DECK_MEMBRANE = "nastran"

_BLOCK = 4096


def quadrilaterals(shells):
    """Facet pairs that are quadrilaterals: (first, second) triangle rows (n_q,) and the
    corners (n_q, 4) — the readers split corners [0, 1, 2, 3] into [0, 1, 2] and [0, 2, 3]."""
    te = shells.triangle_element
    counts = np.bincount(te, minlength=len(shells.element_ids)) if len(te) else np.zeros(0, int)
    rows = np.flatnonzero(counts[te] == 2) if len(te) else np.zeros(0, np.int64)
    order = rows[np.argsort(te[rows], kind="stable")]
    first, second = order[0::2], order[1::2]
    t1, t2 = shells.triangles[first], shells.triangles[second]
    if np.any(t1[:, 0] != t2[:, 0]) or np.any(t1[:, 2] != t2[:, 1]):
        raise ValueError("quadrilateral facets are not split along the diagonal 1–3")
    return first, second, np.column_stack([t1, t2[:, 2]])


def _triangles(deck, rows, formulation, drilling_penalty, membrane_scale=1.0,
               drilling_inertia=True):
    shells = deck.shells
    for start in range(0, len(rows), _BLOCK):
        part = rows[start:start + _BLOCK]
        offset = shells.offset[part]
        mass_area = shells.mass_per_area[part]
        k, m = section_shell_element_matrices(
            deck.points, shells.triangles[part], shells.membrane[part] * membrane_scale,
            shells.coupling[part], shells.bending[part], shells.material_axis[part], mass_area,
            shells.rotary_inertia_per_area[part] + mass_area * offset**2, drilling_penalty,
            first_moment_per_area=mass_area * offset,
            transverse_shear=shells.transverse_shear[part], formulation=formulation,
            drilling_inertia=drilling_inertia)
        tri = shells.triangles[part]
        yield k, m, (6 * tri[:, :, None] + np.arange(6)).reshape(len(tri), 18)


def _quads(deck, first, corners, drilling_penalty):  # corners: regular quads only
    """Membrane blocks (QM6 + drilling penalty) of the quadrilaterals."""
    shells = deck.shells
    for start in range(0, len(first), _BLOCK):
        part = slice(start, start + _BLOCK)
        quads, rows = corners[part], first[part]
        rotation, _, _ = quad_frames(deck.points, quads)
        axis = np.einsum("eij,ej->ei", rotation, shells.material_axis[rows])
        c = rotate_plane_stress(shells.membrane[rows], np.arctan2(axis[:, 1], axis[:, 0]))
        k = quad_membrane_matrices(deck.points, quads, c, drilling_penalty)
        yield k, np.zeros_like(k), (6 * quads[:, :, None] + np.arange(6)).reshape(len(quads), 24)


def shell_blocks(deck: DeckModel, membrane=DECK_MEMBRANE, drilling_penalty=1e-4):
    """Yield (K_e, M_e, dofs) blocks of the deck's shells (module docstring); DeckError names a
    degenerate element."""
    if membrane not in DECK_MEMBRANES:
        raise ValueError(f"membrane must be one of {DECK_MEMBRANES}, got {membrane!r}")
    shells = deck.shells
    if not shells.n_triangles:
        return
    x = deck.points[shells.triangles]
    twice_area = np.linalg.norm(np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]), axis=1)
    edge = np.linalg.norm(x[:, 1] - x[:, 0], axis=1)
    bad = np.flatnonzero(twice_area <= 1e-12 * np.maximum(edge, 1e-300) ** 2)
    if bad.size:
        eid = int(shells.element_ids[shells.triangle_element[bad[0]]])
        raise DeckError(f"{deck.source}: shell element {eid} has zero area "
                        f"({bad.size} degenerate triangle(s))")
    every = np.arange(shells.n_triangles)
    if membrane != "nastran":
        yield from _triangles(deck, every, membrane, drilling_penalty)
        return
    first, second, corners = quadrilaterals(shells)
    regular = regular_quads(deck.points, corners) if len(corners) else np.zeros(0, bool)
    counts = np.bincount(shells.triangle_element, minlength=len(shells.element_ids))
    # CTRIA3 and the facets of quads too distorted for the bilinear map: constant strain
    alone = np.concatenate([np.flatnonzero(counts[shells.triangle_element] == 1),
                            first[~regular], second[~regular]])
    facets = np.flatnonzero(counts[shells.triangle_element] > 2)
    # quadrilaterals: bending (DKT/DKMT), coupling and mass on the two facets, membrane on the quad
    yield from _triangles(deck, np.concatenate([first[regular], second[regular]]), "cst", 0.0,
                          membrane_scale=0.0, drilling_inertia=False)
    yield from _quads(deck, first[regular], corners[regular], drilling_penalty)
    yield from _triangles(deck, alone, "cst", drilling_penalty, drilling_inertia=False)
    yield from _triangles(deck, facets, "andes", drilling_penalty)
