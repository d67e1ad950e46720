"""Inputs that act on held nodes only, for a mesh and a deck alike: nothing left to move, a force
that goes straight into the supports, a contact whose two sides cannot move.

    check_something_free(case, held, used, why)      CaseError: every node is held
    load_warnings(case, held, load_nodes, why)       CaseError: a force group all held; warnings
    contact_warnings(case, paired, held, why)   CaseError: a contact all held; warnings

``held`` (n,) bool: the node's three translations are held (a fixed group or a support set, or
the node is on no element); ``used`` (n,) bool: the node is on an element. ``why`` says what holds
nodes ("model.fe.fixed or on no triangle", "the supports or model.fe.fixed"), in the messages.

Before, ``fixed: ["*"]`` (the glob matches every node group) validated and then failed in solve
with "the structure is not held" (a singular factorization with no free boundary DOF), and a
contact between two held nodes or a force on held nodes was solved silently as doing nothing.
"""
from __future__ import annotations

import numpy as np

FIXED_KEY = ("model", "fe", "fixed")


def check_something_free(case, held, used, key=FIXED_KEY) -> None:
    """CaseError at ``key`` when every node on an element is held: nothing is left to move (a
    glob such as ``fixed: ["*"]`` matches every node group)."""
    used = np.asarray(used, dtype=bool)
    count = int(np.count_nonzero(used))
    if count and np.asarray(held, dtype=bool)[used].all():
        raise case.error(f"every node of the model is held ({count} of {count}): nothing is left "
                         "to move; list only the clamped node groups (a glob such as '*' matches "
                         "every group)", key)


def load_warnings(case, held, load_nodes, why) -> list:
    """Every force group of an FE case acts on a free DOF (``load_nodes``: the nodes of each
    ``excitation.forces`` group, in order; None for a deck load set). The force F of a group is
    split equally over its n nodes (F/n each) and a held node's share goes into the support, so a
    group whose nodes are all held is a CaseError naming it, and a partly held group gets a
    warning stating the share lost. Returns the warnings (one line each)."""
    held = np.asarray(held, dtype=bool)
    warnings = []
    for i, (load, nodes) in enumerate(zip(case.config.excitation.forces, load_nodes)):
        if nodes is None:
            continue
        path = ("excitation", "forces", i, "group")
        count = int(np.count_nonzero(held[nodes]))
        if count == len(nodes):
            raise case.error(f"the force on group {load.group} acts on no free DOF: all of its "
                             f"DOFs are fixed ({len(nodes)} node(s) held by {why})", path)
        if count:
            warnings.append(f"excitation.forces[{i}]: {count} of the {len(nodes)} nodes of group "
                            f"{load.group} are fixed: {100 * count / len(nodes):.3g} % of "
                            f"force_N = {load.force_N:g} N goes straight into the supports")
    return warnings


def contact_warnings(case, paired: dict, held, why, labels=None) -> list:
    """A contact pair whose two nodes are held (or one held node against ground) can never open,
    close or slide: its law does nothing. A contact with every pair so is a CaseError naming it,
    one with some pairs so a warning with their count. ``paired``: {contact name: (a (n_p,),
    b (n_p,) with −1 for ground, …)}; ``labels`` (n,): the node names in messages (a deck's GRID
    ids; default: 0-based node indices)."""
    held = np.asarray(held, dtype=bool)
    warnings = []
    for contact in case.config.contacts:
        if contact.name not in paired:
            continue
        a, b = (np.asarray(side, dtype=np.int64) for side in paired[contact.name][:2])
        if not a.size:
            continue
        inert = held[a] & np.where(b >= 0, held[np.maximum(b, 0)], True)
        count = int(np.count_nonzero(inert))
        first = int(np.flatnonzero(inert)[0]) if count else 0
        name = (lambda node: node) if labels is None else (lambda node: labels[node])
        pair = f"node pair {name(a[first])}–{'ground' if b[first] < 0 else name(b[first])}"
        if count == a.size:
            raise case.error(f"every node pair of this contact is held on both sides ({count} "
                             f"pair(s), e.g. {pair}, held by {why}): the contact can never move",
                             ("contacts", contact.index))
        if count:
            warnings.append(f"contacts[{contact.index}] ({contact.name}): {count} of {a.size} "
                            f"node pairs are held on both sides (e.g. {pair}, by {why}) and do "
                            "nothing")
    return warnings


__all__ = ["check_something_free", "load_warnings", "contact_warnings"]
