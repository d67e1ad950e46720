"""Nastran supports, loads and sets → `DeckModel` fields (part of `sarfe.mesh.formats.nastran`).

SPC/SPC1 (+ SPCADD unions) → ``supports[str(sid)]`` (`SupportSet`, CD-frame components; an
enforced nonzero value is noted, the DOF held); GRID/GRDSET PS → ``supports['permanent']``.
FORCE/MOMENT (in their CID, axes taken at the node), DAREA (in the node's CD frame) and LOAD
combinations (S · Sᵢ · Lᵢ) → ``loads[str(sid)]``, (n, 6) global. SET1 → node/element sets;
property ids → ``element_sets['pid_<id>']``. Other load cards (PLOAD4, GRAV, …) are not in a
load set: the reader's census lists them in ``unsupported``.
"""
from __future__ import annotations

from collections import defaultdict

import numpy as np

from sarfe.mesh.formats.deck import SupportSet

__all__ = ["supports", "loads", "sets", "component_mask"]


def component_mask(components) -> np.ndarray:
    """Nastran component string/int ('123456', 0 = scalar) → (6,) bool."""
    mask = np.zeros(6, dtype=bool)
    for char in str(components if components is not None else "").strip():
        if char in "123456":
            mask[int(char) - 1] = True
    return mask


def supports(reader) -> dict:
    model = reader.model
    sets = defaultdict(list)
    for sid, cards in model.spcs.items():
        for card in cards:
            if card.type == "SPC1":
                mask = component_mask(card.components)
                for n in card.node_ids:
                    sets[sid].append((reader.node(n, "SPC1", sid), mask))
            elif card.type == "SPC":
                for n, comp, value in zip(card.node_ids, card.components, card.enforced):
                    if value not in (None, 0.0):
                        reader.notes.append(f"SPC {sid} node {n}: enforced value {value:g} "
                                          "read as a held DOF (value not applied)")
                    sets[sid].append((reader.node(n, "SPC", sid), component_mask(comp)))
            else:
                reader.fail(card.type, sid, "is not supported")

    def expand(sid, seen=()):
        if sid in seen:
            reader.fail("SPCADD", sid, "refers to itself")
        out = list(sets.get(sid, []))
        for card in model.spcadds.get(sid, []):
            for child in card.sets:
                if child not in sets and child not in model.spcadds:
                    reader.fail("SPCADD", sid, f"set {child} does not exist")
                out += expand(child, seen + (sid,))
        return out

    result = {}
    for sid in sorted(set(sets) | set(model.spcadds)):
        result[str(sid)] = _support(expand(sid))
    permanent = [(i, component_mask(model.nodes[int(n)].ps)) for i, n in enumerate(reader.node_ids)
                 if model.nodes[int(n)].ps]
    if permanent:
        result["permanent"] = _support(permanent)
    return result

def loads(reader) -> dict:
    model = reader.model
    n = len(reader.node_ids)
    base = {}
    for sid, cards in model.loads.items():
        vector = np.zeros((n, 6))
        for card in cards:
            if card.type in ("FORCE", "MOMENT"):
                i = reader.node(card.node, card.type, sid)
                local = float(card.mag) * np.asarray(card.xyz, float)
                axes = reader.coord_axes(card.cid, reader.points[i]) if card.cid else np.eye(3)
                part = slice(0, 3) if card.type == "FORCE" else slice(3, 6)
                vector[i, part] += axes.T @ local
            # other load cards (PLOAD4, GRAV, ...) are listed in ``unsupported``
        base[sid] = vector
    for sid, cards in model.dareas.items():
        vector = base.setdefault(sid, np.zeros((n, 6)))
        for card in cards if isinstance(cards, list) else [cards]:
            for node, comp, scale in zip(card.node_ids, card.components, card.scales):
                i = reader.node(node, "DAREA", sid)
                local = np.zeros(6)
                local[component_mask(comp)] = float(scale)
                vector[i, :3] += reader.frames[i].T @ local[:3]
                vector[i, 3:] += reader.frames[i].T @ local[3:]
    result = {str(sid): v for sid, v in base.items()}
    for sid, cards in model.load_combinations.items():
        total = np.zeros((n, 6))
        for card in cards:
            if card.type != "LOAD":   # LSEQ (dynamic loads) etc.: listed in ``unsupported``
                continue
            for scale, lid in zip(card.scale_factors, card.load_ids):
                if lid not in base:
                    reader.fail("LOAD", sid, f"load set {lid} does not exist")
                total += float(card.scale) * float(scale) * base[lid]
        if any(card.type == "LOAD" for card in cards):
            result[str(sid)] = total
    return result

def sets(reader):
    node_sets, element_sets = {}, {}
    for sid, card in reader.model.sets.items():
        ids = [int(i) for i in card.ids]
        if all(i in reader.index for i in ids):
            node_sets[f"set_{sid}"] = np.array([reader.index[i] for i in ids], np.int64)
        if all(i in reader.model.elements for i in ids):
            element_sets[f"set_{sid}"] = np.array(ids, np.int64)
    by_pid = defaultdict(list)
    for eid, el in reader.model.elements.items():
        pid = getattr(el, "pid", None)
        if isinstance(pid, int):
            by_pid[pid].append(eid)
    for pid, eids in sorted(by_pid.items()):
        element_sets[f"pid_{pid}"] = np.array(sorted(eids), np.int64)
    return node_sets, element_sets


def _support(entries) -> SupportSet:
    """Merge (node, mask) pairs into one `SupportSet` (union of components per node)."""
    merged = {}
    for node, mask in entries:
        merged[node] = merged.get(node, np.zeros(6, bool)) | mask
    nodes = np.array(sorted(merged), dtype=np.int64)
    return SupportSet(nodes, np.array([merged[n] for n in nodes], dtype=bool).reshape(-1, 6))
