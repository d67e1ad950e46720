r"""Deck springs that become contacts: the CBUSH / CELAS elements a contact names in
``from_elements`` leave the linear model and give the contact its node pairs (one per element),
its normal (the spring axis) and its per-pair stiffness; what no contact law carries (rotational
stiffness K4–K6, structural damping GE) is refused with a one-line CaseError, a spring's viscous
damping B stays in the linear model as a parallel damper.

    springs_to_contacts(case, deck) -> (deck without the springs, {name: ElementContact}, warnings)
"""
from __future__ import annotations

import dataclasses

import numpy as np

from sarfe.case.read import Case
from sarfe.hbm import laws
from sarfe.mesh.contact_geometry import frames_from_normals


@dataclasses.dataclass(frozen=True)
class ElementContact:
    """A contact made of deck springs: one node pair per element (b = −1: ground), the spring
    axis as normal (frames rows [normal, t1, t2]) and its stiffness [N/m] along the axes."""

    element_ids: np.ndarray
    nodes_a: np.ndarray
    nodes_b: np.ndarray
    frames: np.ndarray
    normal_stiffness: np.ndarray
    tangential_stiffness: np.ndarray


def springs_to_contacts(case: Case, deck):
    """(deck without the springs named by ``from_elements``, {contact name: ElementContact},
    warnings: one line per contact whose law has no tangent element (rattle) but whose springs
    are stiff across their axis — that shear stiffness leaves the model, said, never silently).

    The contact normal is the spring axis ``element_axis`` (default: the translational axis of
    largest stiffness; a CELAS has one); the normal stiffness is the spring's along it and the
    tangential stiffness the mean of the other two translational ones (squeak).

    What the contact law has no place for is kept or refused, never dropped: the spring's
    viscous damping B (all six components, PARAM,W4's GE·K/W4 included) stays in the linear
    model as a damper between the same nodes (the element kept with its stiffness set to 0), a
    dashpot parallel to the contact whether it is open or closed; a nonzero rotational stiffness
    K4–K6 or structural damping GE is a one-line CaseError naming the element.
    """
    springs = deck.springs
    remove = np.zeros(len(springs.element_ids), dtype=bool)
    contacts, warnings = {}, []
    for contact in case.config.contacts:
        i, kind = contact.index, contact.kind
        if contact.from_elements is None:
            continue
        p = ("contacts", i, "from_elements")
        ids = np.asarray(contact.from_elements, dtype=np.int64)
        rows = np.array([np.flatnonzero(springs.element_ids == e)[:1] for e in ids], dtype=object)
        missing = [int(e) for e, r in zip(ids, rows) if len(r) == 0]
        if missing:
            raise case.error(f"element {missing[0]} is not a CBUSH/CELAS spring of the deck", p)
        rows = np.array([int(r[0]) for r in rows])
        if np.any(remove[rows]):
            raise case.error("an element is already used by another contact", p)
        refuse_what_a_contact_cannot_carry(case, springs, rows, p)
        remove[rows] = True
        k = springs.stiffness[rows, :3]
        if contact.element_axis is not None:
            axis = np.full(len(rows), contact.element_axis - 1)
        else:
            axis = np.argmax(k, axis=1)
            tied = np.sum(np.isclose(k, k.max(axis=1, keepdims=True), rtol=1e-12), axis=1) > 1
            if np.any(tied & (np.count_nonzero(k, axis=1) > 1)):
                raise case.error(f"element {int(ids[np.argmax(tied)])} is equally stiff along two "
                                 "axes; give element_axis: 1, 2 or 3", p)
        normal = springs.frames[rows, axis]
        k_n = k[np.arange(len(rows)), axis]
        if np.any(k_n <= 0):
            raise case.error(f"element {int(ids[np.argmax(k_n <= 0)])} has no stiffness along "
                             "its contact axis", p)
        others = np.ones((len(rows), 3), dtype=bool)
        others[np.arange(len(rows)), axis] = False
        k_t = k[others].reshape(len(rows), 2).mean(axis=1)
        if np.any(k_t > 0) and not laws.uses_tangent(laws.law(kind), contact.params):
            r = int(np.argmax(k_t))
            warnings.append(f"contacts[{i}] ({contact.name}): a {kind} contact has no "
                            f"tangential stiffness: the cross-axis stiffness of its springs "
                            f"(up to {float(k_t[r]):g} N/m, {spring_name(springs, rows[r])}) "
                            "leaves the model; type: squeak keeps it as the stick stiffness")
        contacts[contact.name] = ElementContact(ids, springs.node_a[rows], springs.node_b[rows],
                                                   frames_from_normals(normal), k_n, k_t)
    if not remove.any():
        return deck, contacts, warnings
    # a spring's dashpot B stays as a parallel linear damper between its nodes (stiffness 0)
    damper = remove & np.any(springs.viscous_damping != 0.0, axis=1)
    keep = ~remove | damper
    stiffness = np.where(damper[:, None], 0.0, springs.stiffness)
    fields = {f.name: getattr(springs, f.name) for f in dataclasses.fields(springs)}
    fields["stiffness"] = stiffness
    kept = dataclasses.replace(springs, **{name: value[keep] for name, value in fields.items()})
    return dataclasses.replace(deck, springs=kept), contacts, warnings


def spring_name(springs, i) -> str:
    """'PBUSH 9 (CBUSH 7)' / 'PELAS 3 (CELAS1 5)' / 'CELAS2 5' of spring row i."""
    card, eid, pid = str(springs.card[i]), int(springs.element_ids[i]), int(springs.property_ids[i])
    return {"CBUSH": f"PBUSH {pid} (CBUSH {eid})", "CELAS1": f"PELAS {pid} (CELAS1 {eid})"}.get(
        card, f"{card} {eid}")


def refuse_what_a_contact_cannot_carry(case: Case, springs, rows, path):
    """One-line CaseError for the first spring of a contact whose rotational stiffness K4–K6 or
    structural damping GE no contact law carries (a contact acts on the translations of its node
    pair, and the HBM model has no hysteretic i·GE·K); a zero value is nothing lost."""
    rotational = springs.stiffness[rows, 3:]
    if np.any(rotational != 0.0):
        r = int(np.flatnonzero(np.any(rotational != 0.0, axis=1))[0])
        c = int(np.flatnonzero(rotational[r])[0])
        raise case.error(f"{spring_name(springs, rows[r])} has rotational stiffness K{c + 4} = "
                         f"{float(rotational[r, c]):g} N·m/rad, which a contact cannot carry: set "
                         "K4–K6 to 0 (or put them on a separate CBUSH between the same GRIDs, "
                         "kept linear)", path)
    ge = springs.structural_damping[rows]
    if np.any(ge != 0.0):
        r = int(np.flatnonzero(ge)[0])
        raise case.error(f"{spring_name(springs, rows[r])} has structural damping GE = "
                         f"{float(ge[r]):g}, which a contact cannot carry: add PARAM,W4 (GE·K/W4 "
                         "is then kept as a viscous damper parallel to the contact) or remove GE",
                         path)


def hysteretic_spring(springs) -> str:
    """One line naming the first spring with structural damping GE, which the HBM model (viscous
    D only, also in time integration) cannot carry; PARAM,W4 makes it viscous at reading."""
    i = int(np.flatnonzero(springs.structural_damping)[0])
    return (f"{spring_name(springs, i)} has structural damping GE = "
            f"{float(springs.structural_damping[i]):g}, "
            "which sarfe cannot apply as hysteretic i·GE·K: add PARAM,W4 (the frequency in rad "
            "per deck time unit at which GE·K/W4 becomes viscous, as in Nastran transient) or "
            "remove GE")

__all__ = ["ElementContact", "springs_to_contacts", "spring_name", "hysteretic_spring"]
