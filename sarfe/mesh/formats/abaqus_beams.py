r"""Abaqus / CalculiX beams (B31, B32, B32R with ``*BEAM SECTION``) → :class:`BeamElements`.

Each beam is the 12-DOF Timoshenko beam of :mod:`sarfe.fe.line_elements` on its section's
constants; a 3-node B32/B32R (end, middle, end) is two such beams through its middle node (no
node dropped). The local 1-direction n₁ (second data line of ``*BEAM SECTION``; default
(0, 0, −1), as Abaqus and CalculiX) is the element's y axis (its component along the beam is
removed), so I1 = ∫ x₁² dA, I2 = ∫ x₂² dA (x₁ along n₁, x₂ along n₂ = t × n₁).

=========  ==================  ==========================================================
SECTION    data line 1         A, I1, I2, J; Timoshenko shear factor k (Cowper 1966)
=========  ==================  ==========================================================
RECT       a (along n₁), b     A = a b, I1 = b a³/12, I2 = a b³/12, J of the rectangle
                               (Roark, :mod:`sarfe.mesh.formats.beam_library` BAR);
                               k = 10 (1 + ν)/(12 + 11 ν)
CIRC       d₁, d₂ (diameters)  ellipse: A = π d₁ d₂/4, I1 = π d₁³ d₂/64, I2 = π d₁ d₂³/64,
                               J = π d₁³ d₂³/(16 (d₁² + d₂²)); k = 6 (1 + ν)/(7 + 6 ν)
PIPE       R (outer radius), t A = π (R² − r²), I1 = I2 = π (R⁴ − r⁴)/4, J = 2 I1 (r = R − t);
                               k = 6 (1 + ν)(1 + m²)² / ((7 + 6 ν)(1 + m²)² + (20 + 12 ν) m²),
                               m = r/R
=========  ==================  ==========================================================

CalculiX solves these beams as expanded 3D C3D20R/C3D8I elements (PIPE, BOX: a square section
with integration points on the wall); what that gives against beam theory is measured in
docs/decks.md. Other sections (BOX, GENERAL, …), beam offsets (OFFSET1/2) and a beam's
``*NODAL THICKNESS`` are refused with a one-line DeckError naming the line.
"""
from __future__ import annotations

import numpy as np

from sarfe.mesh.formats.beam_library import section as library_section
from sarfe.mesh.formats.deck import BeamElements, DeckError

__all__ = ["BEAM_NODES", "BEAM_SECTIONS", "DEFAULT_DIRECTION_1", "beam_section_constants",
           "beam_table"]

#: nodes per element of the beam types read (3-node: end, middle, end)
BEAM_NODES = {"B31": 2, "B32": 3, "B32R": 3}
#: section types with closed forms here, and their number of dimensions
BEAM_SECTIONS = {"RECT": 2, "CIRC": 2, "PIPE": 2}
#: the local 1-direction when *BEAM SECTION gives none (Abaqus, CalculiX)
DEFAULT_DIRECTION_1 = (0.0, 0.0, -1.0)


def beam_section_constants(kind: str, dims, poisson: float):
    """(A, I1, I2, J, k) of a ``*BEAM SECTION`` (module table) in the file's units; ValueError
    names a shape without closed form here or impossible dimensions."""
    kind = str(kind).upper()
    if kind not in BEAM_SECTIONS:
        raise ValueError(f"SECTION={kind} is not modelled (modelled: {', '.join(BEAM_SECTIONS)})")
    d = [float(x) for x in dims][:BEAM_SECTIONS[kind]]
    if len(d) != BEAM_SECTIONS[kind] or min(d) <= 0.0:
        raise ValueError(f"SECTION={kind} needs {BEAM_SECTIONS[kind]} positive dimensions, "
                         f"got {list(dims)}")
    nu = float(poisson)
    if kind == "RECT":
        area, i1, i2, _, j = library_section("BAR", [d[1], d[0]])   # BAR(w along z, h along y)
        return area, i1, i2, j, 10.0 * (1 + nu) / (12 + 11 * nu)
    if kind == "CIRC":
        a, b = d
        return (np.pi * a * b / 4, np.pi * a**3 * b / 64, np.pi * a * b**3 / 64,
                np.pi * a**3 * b**3 / (16 * (a**2 + b**2)), 6 * (1 + nu) / (7 + 6 * nu))
    outer, wall = d
    if wall > outer:
        raise ValueError(f"SECTION=PIPE wall {wall:g} thicker than the radius {outer:g}")
    inner = outer - wall
    area, i1, i2, _, j = (library_section("TUBE", [outer, inner]) if inner > 0.0
                          else library_section("ROD", [outer]))
    m2 = (inner / outer) ** 2
    k = 6 * (1 + nu) * (1 + m2) ** 2 / ((7 + 6 * nu) * (1 + m2) ** 2 + (20 + 12 * nu) * m2)
    return area, i1, i2, j, k


def beam_table(rows) -> BeamElements:
    """BeamElements of rows (element id, type, node indices, section) with section =
    (E, ν, ρ, kind, dims, direction 1, where); a B32/B32R gives two rows (module docstring)."""
    if not rows:
        return BeamElements()
    columns = {key: [] for key in ("card", "element_ids", "nodes", "orientation", "area", "i1",
                                   "i2", "torsion", "shear_factor", "young", "shear_modulus",
                                   "density")}
    for element_id, kind, nodes, (young, nu, rho, section, dims, direction, where) in rows:
        try:
            area, i1, i2, torsion, k = beam_section_constants(section, dims, nu)
        except ValueError as exc:
            raise DeckError(f"{where}: {exc}") from None
        pieces = [nodes] if len(nodes) == 2 else [nodes[:2], nodes[1:]]
        for pair in pieces:
            for key, value in (("card", kind), ("element_ids", element_id), ("nodes", pair),
                               ("orientation", direction), ("area", area), ("i1", i1),
                               ("i2", i2), ("torsion", torsion), ("shear_factor", k),
                               ("young", young), ("shear_modulus", young / (2 * (1 + nu))),
                               ("density", rho)):
                columns[key].append(value)
    n = len(columns["card"])
    factor = np.array(columns.pop("shear_factor"), dtype=float)
    return BeamElements(
        card=np.array(columns.pop("card")), element_ids=np.array(columns.pop("element_ids"), np.int64),
        property_ids=np.zeros(n, np.int64), nodes=np.array(columns.pop("nodes"), np.int64),
        orientation=np.array(columns.pop("orientation"), dtype=float), i12=np.zeros(n),
        shear_factor_1=factor, shear_factor_2=factor.copy(), mass_per_length=np.zeros(n),
        **{key: np.array(value, dtype=float) for key, value in columns.items()})
