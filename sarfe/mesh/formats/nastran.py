"""Nastran bulk data → `DeckModel`, read and cross-referenced by pyNastran.

pyNastran (BSD-3) parses the deck (free/small/large field, continuations, INCLUDE) and
cross-references it; this module turns its cards into the reader-neutral `DeckModel`:

* GRID in any CP system (CORD1/2 R, C, S, chained) → global coordinates; the CD system of
  each GRID → ``displacement_frames`` (cylindrical/spherical axes taken at the node);
  GRID/GRDSET PS → support set ``'permanent'``.
* CTRIA3/CQUAD4 (THETA/MCID → material axis; ZOFFS and PCOMP Z0 offsets honoured: the
  section is taken about the node plane; corner thicknesses T1–T4 different from the
  property's are refused with a DeckError) with
  PSHELL (T, MID1/MID2/MID3, 12I/T³, TS/T, NSM; MID4 refused) or PCOMP (classical lamination
  theory, `sarfe.mesh.laminate`; LAM = SYM mirrored) on MAT1 / MAT2 / MAT8.
  CTRIA6/CQUAD8 become 4/6 facet triangles through their midside nodes; CQUADR/CTRIAR (the
  shells with drilling stiffness) are read as CQUAD4/CTRIA3, whose membranes carry the drilling
  rotation here.
* CTETRA (4/10), CHEXA (8/20), CPENTA (6) with PSOLID on MAT1.
* CBAR/PBAR or PBARL, CBEAM/PBEAM or PBEAML (library shapes: `sarfe.mesh.formats.beam_library`;
  end stations equal to 0.1 %: their mean; a tapered beam is
  refused), CROD/PROD, CONROD;
  end offsets (WA/WB) and pin flags refused.
* CBUSH/PBUSH (K, B, GE), CELAS1/PELAS, CELAS2; CONM2 (offset, inertia, CID);
  RBE2; RBE3 (UM set refused). A spring's GE stays hysteretic (``structural_damping``)
  unless the deck gives PARAM,W4 > 0: then, as in Nastran's transient solutions, it becomes
  the viscous damping B += GE·K/W4 (noted), the one form sarfe's damping carries.
  Material GE and PARAM,G are not applied (the case's ``damping`` damps the structure; noted).
* SPC/SPC1/SPCADD → ``supports``; FORCE/MOMENT/DAREA/LOAD → ``loads`` (global frame);
  SET1 → ``node_sets['set_<id>']`` (and ``element_sets`` when its ids are elements);
  properties → ``element_sets['pid_<id>']``.
* Every other card is counted in ``unsupported`` (cards that cannot change K or M —
  analysis controls such as PARAM, EIGRL, and thermal materials — are listed in
  ``CONTROL_CARDS`` and not counted). PARAM,WTMASS is applied to every mass; PARAM,COUPMASS
  (> 0: coupled mass, else lumped) and PARAM,K6ROT (shell drilling penalty) reach the assembly.

The deck file is read by :func:`sarfe.mesh.formats.nastran_bdf.load_bdf`; the sections
(PSHELL, PCOMP, materials) are :mod:`sarfe.mesh.formats.nastran_sections`'s, the sets, supports
and loads :mod:`sarfe.mesh.formats.nastran_sets`'. Quantities stay in the deck's own units;
`read_nastran(path, units)` converts them to SI with `sarfe.mesh.formats.deck.to_si`.
"""
from __future__ import annotations

import os
from collections import defaultdict
from pathlib import Path

import numpy as np

from sarfe.mesh.formats.beam_library import section
from sarfe.mesh.formats.deck import (BeamElements, DeckError, DeckModel, InterpolationElements, PointMasses,
                                     RigidElements, SolidElements, SpringElements, to_si)
from sarfe.mesh.formats.nastran_bdf import card_where, first_lines, load_bdf
from sarfe.mesh.formats.nastran_sections import isotropic, shells
from sarfe.mesh.formats.nastran_sets import component_mask, loads, sets, supports

__all__ = ["read_nastran", "nastran_deck", "axes_at", "CONTROL_CARDS", "MODELLED_CARDS"]

#: cards sarfe turns into the model
MODELLED_CARDS = frozenset({
    "GRID", "GRDSET", "CORD1R", "CORD1C", "CORD1S", "CORD2R", "CORD2C", "CORD2S",
    "CTRIA3", "CQUAD4", "CTRIA6", "CQUAD8", "CTRIAR", "CQUADR", "PSHELL", "PCOMP", "MAT1", "MAT2",
    "MAT8",
    "CTETRA", "CHEXA", "CPENTA", "PSOLID",
    "CBAR", "PBAR", "PBARL", "CBEAM", "PBEAM", "PBEAML", "CROD", "PROD", "CONROD",
    "CBUSH", "PBUSH", "CELAS1", "CELAS2", "PELAS", "CONM2", "RBE2", "RBE3",
    "SPC", "SPC1", "SPCADD", "FORCE", "MOMENT", "DAREA", "LOAD", "SET1",
})
#: cards without effect on stiffness, mass, supports or loads (solution control, output
#: requests, thermal materials): neither modelled nor counted as unsupported
CONTROL_CARDS = frozenset({"ENDDATA", "PARAM", "EIGRL", "EIGR", "MAT4", "MAT5", "DTI",
                           "INCLUDE", "ECHOON", "ECHOOFF"})
#: shear area factor K (A_s = K A) of library shapes, as the commercial solver takes it for a
#: ROD (0.9: pyNastran's beam_modes deck, MSC's modes within 0.2 % with it, +1.4 … +18 % without);
#: other shapes are taken rigid in shear (noted)
LIBRARY_SHEAR_FACTOR = {"ROD": 0.9}
_SOLID_KIND = {("CTETRA", 4): "tet4", ("CTETRA", 10): "tet10", ("CHEXA", 8): "hex8",
               ("CHEXA", 20): "hex20", ("CPENTA", 6): "wedge6"}



def read_nastran(path, units="SI") -> DeckModel:
    """Read a Nastran bulk-data deck (.bdf/.dat/.nas/.fem, INCLUDEs followed) into a
    `DeckModel` in SI units; ``units`` names the deck's unit system (see
    `sarfe.mesh.formats.deck.UNIT_SYSTEMS`). Raises `DeckError` (one line) naming file and card."""
    return to_si(nastran_deck(path), units)


def _one_line(error) -> str:
    return " ".join(str(error).split()) or type(error).__name__


def nastran_deck(path) -> DeckModel:
    """`DeckModel` of a Nastran deck in the deck's own units (see :func:`read_nastran`)."""
    path = Path(path)
    if not path.is_file():
        raise DeckError(f"Nastran deck not found: {path}")
    model = load_bdf(path)
    try:
        return _Converter(model, path).deck()
    except DeckError:
        raise
    except Exception as error:  # an unexpected card layout: still one line, with the file
        raise DeckError(f"{path}: {_one_line(error)}") from error


def axes_at(coord, points) -> np.ndarray:
    """Axes (k, 3, 3) (rows = local axes 1, 2, 3 in global coordinates) of a pyNastran
    coordinate system at global points (k, 3): constant for rectangular systems, (r, θ, z)
    for cylindrical and (R, θ, φ) for spherical ones."""
    points = np.atleast_2d(np.asarray(points, float))
    beta = np.asarray(coord.beta(), float)
    k = len(points)
    if coord.cid == 0 or coord.Type == "R":
        return np.broadcast_to(beta, (k, 3, 3)).copy()
    local = (points - np.asarray(coord.origin, float)) @ beta.T
    phi = np.arctan2(local[:, 1], local[:, 0])
    c, s = np.cos(phi), np.sin(phi)
    zero, one = np.zeros(k), np.ones(k)
    if coord.Type == "C":
        rows = np.stack([np.stack([c, s, zero], 1), np.stack([-s, c, zero], 1),
                         np.stack([zero, zero, one], 1)], axis=1)
    elif coord.Type == "S":
        theta = np.arctan2(np.hypot(local[:, 0], local[:, 1]), local[:, 2])
        ct, st = np.cos(theta), np.sin(theta)
        rows = np.stack([np.stack([st * c, st * s, ct], 1), np.stack([ct * c, ct * s, -st], 1),
                         np.stack([-s, c, zero], 1)], axis=1)
    else:
        raise DeckError(f"coordinate system {coord.cid}: type {coord.Type!r} not supported")
    return rows @ beta


class _Converter:
    """One pass over the cross-referenced pyNastran model (a reading step, not a hot path)."""

    def __init__(self, model, path: Path):
        self.model, self.path = model, path
        self.notes: list[str] = []
        self.apply_grdset()
        nids = np.array(sorted(model.nodes), dtype=np.int64)
        self.node_ids = nids
        self.index = {int(n): i for i, n in enumerate(nids)}
        # GRIDs only (pyNastran's get_xyz_in_coord adds a zero row per SPOINT, shifting rows)
        self.points = (np.array([model.nodes[int(n)].get_position() for n in nids], float)
                       if len(nids) else np.zeros((0, 3)))
        self.frames = np.tile(np.eye(3), (len(nids), 1, 1))
        cds = np.array([model.nodes[int(n)].cd for n in nids], dtype=np.int64)
        for cd in np.unique(cds[cds != 0]):
            rows = np.flatnonzero(cds == cd)
            self.frames[rows] = axes_at(model.coords[int(cd)], self.points[rows])
        self.wtmass = 1.0
        if "WTMASS" in model.params:
            self.wtmass = float(model.params["WTMASS"].values[0])
            self.notes.append(f"PARAM,WTMASS,{self.wtmass:g} applied to every mass")
        #: PARAM,W4 [rad per deck time unit]: element GE → viscous GE·K/W4 (0: GE kept hysteretic)
        self.w4 = float(model.params["W4"].values[0]) if "W4" in model.params else 0.0
        #: PARAM,COUPMASS > 0: coupled element mass (default lumped); PARAM,K6ROT: shell drilling
        self.coupled_mass = ("COUPMASS" in model.params
                             and float(model.params["COUPMASS"].values[0] or 0) > 0)
        k6rot = float(model.params["K6ROT"].values[0]) if "K6ROT" in model.params else 100.0
        self.drilling_penalty = 1e-6 * k6rot
        self.note_structural_damping()
        self.library_noted: set = set()

    def note_structural_damping(self):
        """Material GE and PARAM,G are the structure's loss factor in Nastran; sarfe takes the
        structure's damping from the case (modal ζ or Rayleigh), so they are listed, not applied."""
        damped = sorted(int(mid) for mid, mat in self.model.materials.items()
                        if float(getattr(mat, "ge", 0.0) or 0.0) != 0.0)
        if damped:
            shown = ", ".join(map(str, damped[:5])) + (" …" if len(damped) > 5 else "")
            self.notes.append(f"material GE of MAT {shown} not applied (the case's damping "
                              "section damps the structure)")
        if "G" in self.model.params and float(self.model.params["G"].values[0] or 0.0) != 0.0:
            self.notes.append(f"PARAM,G,{float(self.model.params['G'].values[0]):g} not applied "
                              "(the case's damping section damps the structure)")

    def apply_grdset(self):
        """GRDSET CP/CD/PS defaults for GRIDs that leave those fields blank.

        pyNastran 1.4 reads GRDSET but does not apply its CP or PS; a blank and an explicit 0
        CP/CD read alike, so GRDSET's nonzero CP/CD go to every GRID whose CP/CD is 0 (noted)."""
        grdset = getattr(self.model, "grdset", None)
        if grdset is None:
            return
        cp, cd, ps = int(grdset.cp or 0), int(grdset.cd or 0), grdset.ps or ""
        for node in self.model.nodes.values():
            if cp and not node.cp:
                node.cp = cp
                node.cp_ref = self.model.Coord(cp)
            if cd and not node.cd:
                node.cd = cd
                node.cd_ref = self.model.Coord(cd)
            if ps and not node.ps:
                node.ps = str(ps)
        if cp or cd:
            self.notes.append(f"GRDSET CP {cp} / CD {cd} applied to every GRID with CP/CD 0 or blank")

    # ------------------------------------------------------------------ helpers
    def fail(self, card, ident, why):
        raise DeckError(f"{card_where(self.path, card, ident)}: {why}")

    def node(self, nid, card, eid) -> int:
        try:
            return self.index[int(nid)]
        except (KeyError, TypeError):
            self.fail(card, eid, f"node {nid} is not a GRID of the deck")

    def coord_axes(self, cid, point):
        return axes_at(self.model.coords[int(cid)], point)[0]

    # ------------------------------------------------------------------ solids
    def solids(self) -> dict:
        blocks = defaultdict(lambda: defaultdict(list))
        for eid, el in sorted(self.model.elements.items()):
            if el.type not in ("CTETRA", "CHEXA", "CPENTA"):
                continue
            node_ids = list(el.node_ids)
            if any(n is None for n in node_ids):
                self.fail(el.type, eid, "midside nodes partly given: not modelled")
            kind = _SOLID_KIND.get((el.type, len(node_ids)))
            if kind is None:
                self.fail(el.type, eid, f"{len(node_ids)}-node {el.type} is not modelled")
            prop = el.pid_ref
            if prop.type != "PSOLID":
                self.fail(el.type, eid, f"property {prop.type} {prop.pid} is not supported")
            e, nu, _, rho = isotropic(self, prop.mid, "PSOLID", prop.pid)
            block = blocks[kind]
            block["element_ids"].append(eid)
            block["property_ids"].append(prop.pid)
            block["connectivity"].append([self.node(n, el.type, eid) for n in node_ids])
            block["young"].append(e)
            block["poisson"].append(nu)
            block["density"].append(rho * self.wtmass)
        return {kind: SolidElements(
            kind, np.array(b["element_ids"], np.int64), np.array(b["property_ids"], np.int64),
            np.array(b["connectivity"], np.int64), np.array(b["young"]),
            np.array(b["poisson"]), np.array(b["density"])) for kind, b in blocks.items()}

    # ------------------------------------------------------------------ beams and rods
    def orientation(self, el, a):
        if el.g0 not in (None, 0):
            return self.points[self.node(el.g0, el.type, el.eid)] - self.points[a]
        x = np.asarray(el.x, float)
        return self.frames[a].T @ x  # X is given in the CD system of GA

    def beams(self) -> BeamElements:
        rows = defaultdict(list)
        for eid, el in sorted(self.model.elements.items()):
            if el.type not in ("CBAR", "CBEAM", "CROD", "CONROD"):
                continue
            a, b = (self.node(n, el.type, eid) for n in el.node_ids)
            if el.type in ("CBAR", "CBEAM"):
                if el.pa or el.pb:
                    self.fail(el.type, eid, "pin flags PA/PB are not modelled")
                if np.any(np.asarray(el.wa, float) != 0) or np.any(np.asarray(el.wb, float) != 0):
                    self.fail(el.type, eid, "end offsets WA/WB are not modelled")
                prop = el.pid_ref
                if prop.type in ("PBARL", "PBEAML"):   # the beam library's shapes
                    area, i1, i2, i12, j, nsm = self.library_section(prop)
                    k1 = k2 = LIBRARY_SHEAR_FACTOR.get(str(prop.beam_type).upper(), 0.0)
                elif el.type == "CBAR":
                    if prop.type != "PBAR":
                        self.fail("CBAR", eid, f"property {prop.type} is not supported")
                    area, i1, i2, i12, j, nsm = prop.A, prop.i1, prop.i2, prop.i12, prop.j, prop.nsm
                    k1, k2 = _shear_factor(prop.k1), _shear_factor(prop.k2)
                else:
                    if prop.type != "PBEAM":
                        self.fail("CBEAM", eid, f"property {prop.type} is not supported")
                    values = [np.asarray(v, float) for v in
                              (prop.A, prop.i1, prop.i2, prop.i12, prop.j, prop.nsm)]
                    area, i1, i2, i12, j, nsm = self.uniform("PBEAM", prop.pid, values)
                    k1, k2 = _shear_factor(prop.k1), _shear_factor(prop.k2)
                mid, v = prop.mid, self.orientation(el, a)
            else:
                prop = el if el.type == "CONROD" else el.pid_ref
                area, j, nsm = prop.A, prop.j, prop.nsm
                i1 = i2 = i12 = k1 = k2 = 0.0
                mid, v = prop.mid, np.zeros(3)
            e, _, g, rho = isotropic(self, mid, el.type, eid)
            for key, value in (("card", el.type), ("element_ids", eid),
                               ("property_ids", getattr(prop, "pid", 0)), ("nodes", [a, b]),
                               ("orientation", v), ("area", area), ("i1", i1), ("i2", i2),
                               ("i12", i12), ("torsion", j), ("shear_factor_1", k1),
                               ("shear_factor_2", k2), ("young", e),
                               ("shear_modulus", g), ("density", rho * self.wtmass),
                               ("mass_per_length", float(nsm or 0.0) * self.wtmass)):
                rows[key].append(value)
        if not rows:
            return BeamElements()
        return BeamElements(**{k: np.array(v, dtype=None if k == "card" else
                                            (np.int64 if k in ("element_ids", "property_ids",
                                                               "nodes") else float))
                               for k, v in rows.items()})

    def uniform(self, card, pid, values):
        """The stations' values of a beam property when equal to the deck's printed precision
        (their mean); a tapered beam is refused."""
        if any(np.ptp(v) > 1e-3 * max(abs(v).max(), 1e-300) for v in values):
            self.fail(card, pid, "tapered sections are not modelled")
        return tuple(float(np.mean(v)) for v in values)

    def library_section(self, prop):
        """(A, I1, I2, I12, J, NSM) of a PBARL / PBEAML from its shape and dimensions
        (:mod:`sarfe.mesh.formats.beam_library`; PBEAML: every station, equal ones only)."""
        stations = np.atleast_2d(np.asarray(prop.dim, float))
        try:
            rows = np.array([section(prop.beam_type, dims) for dims in stations])
        except ValueError as error:
            self.fail(prop.type, prop.pid, str(error))
        nsm = np.atleast_1d(np.asarray(prop.nsm if prop.nsm is not None else 0.0, float))
        values = [rows[:, k] for k in range(5)] + [nsm]
        if prop.pid not in self.library_noted:
            self.library_noted.add(prop.pid)
            if len(self.library_noted) == 1:
                self.notes.append("PBARL/PBEAML sections from the beam library's closed forms "
                                  "(shear flexibility for ROD only)")
        return self.uniform(prop.type, prop.pid, values)

    # ------------------------------------------------------------------ springs
    def springs(self) -> SpringElements:
        rows = defaultdict(list)
        converted = []

        def add(card, eid, pid, a, b, k6, frame, ge, b6, location=np.nan):
            if ge != 0.0 and self.w4 > 0.0:   # Nastran transient: B_e = GE_e K_e / W4
                b6, ge = b6 + ge * k6 / self.w4, 0.0
                converted.append(eid)
            for key, value in (("card", card), ("element_ids", eid), ("property_ids", pid),
                               ("node_a", a), ("node_b", b), ("stiffness", k6),
                               ("frames", frame), ("structural_damping", ge),
                               ("viscous_damping", b6), ("location", location)):
                rows[key].append(value)

        for eid, el in sorted(self.model.elements.items()):
            if el.type == "CBUSH":
                prop = el.pid_ref
                if prop.type != "PBUSH":
                    self.fail("CBUSH", eid, f"property {prop.type} is not supported")
                nids = el.node_ids
                a = self.node(nids[0], "CBUSH", eid)
                b = -1 if nids[1] in (None, 0) else self.node(nids[1], "CBUSH", eid)
                if el.cid is not None and el.cid >= 0:
                    frame = self.coord_axes(el.cid, self.points[a])
                else:
                    if b < 0 or np.linalg.norm(self.points[b] - self.points[a]) < 1e-4:
                        self.fail("CBUSH", eid, "grounded or coincident CBUSH needs a CID")
                    ex = self.points[b] - self.points[a]
                    ex /= np.linalg.norm(ex)
                    v = self.orientation(el, a)
                    ez = np.cross(ex, v)
                    if np.linalg.norm(ez) < 1e-12:
                        self.fail("CBUSH", eid, "orientation vector parallel to GA→GB")
                    ez /= np.linalg.norm(ez)
                    frame = np.array([ex, np.cross(ez, ex), ez])
                k6 = np.array([float(k or 0.0) for k in (list(prop.Ki) + [0] * 6)[:6]])
                b6 = np.array([float(c or 0.0) for c in (list(prop.Bi) + [0] * 6)[:6]])
                # GE1 alone applies to all six components; differing GEi are refused
                given = {float(g) for g in (prop.GEi or []) if g is not None}
                if len(given) > 1:
                    self.fail("PBUSH", prop.pid, "GE per component differs: not modelled")
                ge = given.pop() if given else 0.0
                location = 0.5 if el.s is None else float(el.s)
                add("CBUSH", eid, prop.pid, a, b, k6, frame, ge, b6, location)
            elif el.type in ("CELAS1", "CELAS2"):
                if el.type == "CELAS1":
                    k, ge, pid = float(el.pid_ref.k), float(el.pid_ref.ge or 0.0), el.pid
                else:
                    k, ge, pid = float(el.k), float(el.ge or 0.0), 0
                ends = [(n, c) for n, c in zip(el.node_ids, (el.c1, el.c2)) if n not in (None, 0)]
                if not ends or any(c in (None, 0) for _, c in ends):
                    self.fail(el.type, eid, "scalar points / component 0 are not modelled")
                if len(ends) == 2 and ends[0][1] != ends[1][1]:
                    self.fail(el.type, eid, f"joins component {ends[0][1]} to {ends[1][1]}: "
                              "only springs between equal components are modelled")
                a = self.node(ends[0][0], el.type, eid)
                b = self.node(ends[1][0], el.type, eid) if len(ends) == 2 else -1
                if b >= 0 and not np.allclose(self.frames[a], self.frames[b], atol=1e-9):
                    self.fail(el.type, eid, "its nodes have different CD systems")
                k6 = np.zeros(6)
                k6[int(ends[0][1]) - 1] = k
                add(el.type, eid, pid, a, b, k6, self.frames[a], ge, np.zeros(6))
        if converted:
            self.notes.append(f"PARAM,W4,{self.w4:g}: structural damping GE of {len(converted)} "
                              "spring(s) applied as the viscous damping GE·K/W4 (Nastran's "
                              "transient rule; equal to the hysteretic i·GE·K at ω = W4)")
        if not rows:
            return SpringElements()
        ints = ("element_ids", "property_ids", "node_a", "node_b")
        return SpringElements(**{k: np.array(v, dtype=np.int64 if k in ints else None)
                                 for k, v in rows.items()})

    # ------------------------------------------------------------------ masses
    def point_masses(self) -> PointMasses:
        rows = defaultdict(list)
        for eid, el in sorted(self.model.masses.items()):
            if el.type != "CONM2":
                continue  # counted as unsupported by the card census
            n = self.node(el.nid, "CONM2", eid)
            i = el.I
            inertia = np.array([[i[0], -i[1], -i[3]], [-i[1], i[2], -i[4]],
                                [-i[3], -i[4], i[5]]], float)
            x = np.asarray(el.X, float)
            cid = el.Cid()
            if cid == -1:
                offset = x - self.points[n]
            else:
                axes = self.coord_axes(cid, self.points[n]) if cid else np.eye(3)
                offset = axes.T @ x
                inertia = axes.T @ inertia @ axes
            rows["element_ids"].append(eid)
            rows["node"].append(n)
            rows["mass"].append(float(el.mass) * self.wtmass)
            rows["offset"].append(offset)
            rows["inertia"].append(inertia * self.wtmass)
        if not rows:
            return PointMasses()
        return PointMasses(np.array(rows["element_ids"], np.int64), np.array(rows["node"], np.int64),
                           np.array(rows["mass"]), np.array(rows["offset"]),
                           np.array(rows["inertia"]))

    # ------------------------------------------------------------------ rigid elements
    def frame_free_mask(self, mask, nodes, card, eid):
        """A partial component mask is only frame-independent where the CD frame is global."""
        partial = not (mask.all() or (mask[:3].all() and not mask[3:].any())
                       or (mask[3:].all() and not mask[:3].any()))
        if partial and not np.allclose(self.frames[nodes], np.eye(3), atol=1e-12):
            self.fail(card, eid, "partial components on nodes with a CD system are not modelled")

    def rigid(self):
        rbe2 = defaultdict(list)
        rbe3 = defaultdict(list)
        for eid, el in sorted(self.model.rigid_elements.items()):
            if el.type == "RBE2":
                gn = self.node(el.gn, "RBE2", eid)
                dep = [self.node(n, "RBE2", eid) for n in el.Gmi_node_ids]
                mask = component_mask(el.cm)
                self.frame_free_mask(mask, dep + [gn], "RBE2", eid)
                rbe2["element_ids"].append(eid)
                rbe2["independent"].append(gn)
                rbe2["components"].append(mask)
                rbe2["dependent"] += dep
                rbe2["dependent_element"] += [len(rbe2["element_ids"]) - 1] * len(dep)
            elif el.type == "RBE3":
                if el.Gmi:
                    self.fail("RBE3", eid, "UM (user-chosen dependent DOFs) is not modelled")
                ref = self.node(el.ref_grid_id, "RBE3", eid)
                refc = component_mask(el.refc)
                self.frame_free_mask(refc, [ref], "RBE3", eid)
                row = len(rbe3["element_ids"])
                rbe3["element_ids"].append(eid)
                rbe3["reference"].append(ref)
                rbe3["reference_components"].append(refc)
                for weight, comp, group in zip(el.weights, el.comps, el.Gijs_node_ids):
                    nodes = [self.node(n, "RBE3", eid) for n in group]
                    mask = component_mask(comp)
                    self.frame_free_mask(mask, nodes, "RBE3", eid)
                    rbe3["independent"] += nodes
                    rbe3["independent_element"] += [row] * len(nodes)
                    rbe3["weights"] += [float(weight)] * len(nodes)
                    rbe3["independent_components"] += [mask] * len(nodes)
        two = RigidElements(**{k: np.array(v, dtype=bool if k == "components" else np.int64)
                               for k, v in rbe2.items()}) if rbe2 else RigidElements()
        three = InterpolationElements(**{
            k: np.array(v, dtype=bool if "components" in k else
                        (float if k == "weights" else np.int64))
            for k, v in rbe3.items()}) if rbe3 else InterpolationElements()
        return two, three

    def census(self) -> dict:
        counts = dict(self.model.card_count)
        unsupported = {card: int(count) for card, count in sorted(counts.items())
                       if card not in MODELLED_CARDS and card not in CONTROL_CARDS}
        return unsupported

    def deck(self) -> DeckModel:
        unsupported = self.census()
        rbe2, rbe3 = self.rigid()
        node_sets, element_sets = sets(self)
        return DeckModel(
            source=os.fspath(self.path), node_ids=self.node_ids, points=self.points,
            displacement_frames=self.frames, shells=shells(self), solids=self.solids(),
            beams=self.beams(), springs=self.springs(), point_masses=self.point_masses(),
            rbe2=rbe2, rbe3=rbe3, supports=supports(self), loads=loads(self),
            node_sets=node_sets, element_sets=element_sets, unsupported=unsupported,
            ignored={}, unsupported_where=first_lines(self.path, unsupported) if unsupported else {},
            coupled_mass=self.coupled_mass,
            drilling_penalty=self.drilling_penalty, notes=tuple(self.notes))


def _shear_factor(value) -> float:
    """Nastran K1/K2 → shear area factor; blank or ≥ 1e8 (pyNastran's blank) = rigid in shear (0)."""
    value = float(value or 0.0)
    return 0.0 if value >= 1e8 else value
