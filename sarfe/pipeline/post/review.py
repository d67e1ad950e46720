r"""The answers a design review asks at the loudest point, for summary.json ``worst`` and the first
screen of the report and the console: is it audible (the occupant verdict), how much of the sound
the contacts make against the panel's own structure-borne response, which contact leads, and
which change of one contact parameter lowers the level most.

Shares are the coherent A-weighted shares of :mod:`sarfe.erp.contributions` (they sum to 1): the
structure-borne share is the part of the 'excitation' source — the panel's response to the
excitation with every contact force removed, i.e. sound the contacts do not make — and the
contacts' share is 1 minus it (the sum of the contacts' own shares).
"""
from __future__ import annotations

import math

from sarfe.pipeline.post.margin_records import best_change

EXCITATION = "excitation"


def _share(source) -> float:
    value = (source or {}).get("share_a")
    return float(value) if value is not None and math.isfinite(value) else float("nan")


def loudest_review(point) -> dict:
    """The review keys of ``worst`` from the loudest point's record (module docstring):
    ``audibility`` (the point's verdict, with ``contacts`` {name: verdict of its sound alone}),
    ``structure_share_a``, ``contacts_share_a``, ``top_contact`` {name, share_a,
    part_level_dba, level_dba}, ``best_change`` (:func:`sarfe.pipeline.post.margin_records.
    best_change`) and per contact name ``onset``, ``sensitivities`` and ``linear_risk``
    (dynamic tolerance d = g − t − |ŵ1| [m] of the linear baseline, rattle_risk d < 0)."""
    contributions = point.get("contributions") or {}
    sources = contributions.get("sources", []) if contributions.get("available") else []
    structure = next((s for s in sources if s["name"] == EXCITATION), None)
    contacts = [s for s in sources if s["name"] != EXCITATION]
    top = max(contacts, key=lambda s: _share(s) if math.isfinite(_share(s)) else -math.inf,
              default=None)
    audibility = dict(point.get("audibility") or {})
    alone = {s["name"]: s for s in audibility.pop("sources", [])}
    audibility["structure_borne"] = alone.get(EXCITATION)
    audibility["contacts"] = {c["name"]: alone.get(c["name"]) for c in point.get("contacts", [])}
    linear = {c["name"]: c for c in (point.get("linear") or {}).get("contacts", [])}
    return {
        "audibility": audibility,
        "structure_share_a": _share(structure),
        "contacts_share_a": math.fsum(_share(s) for s in contacts) if contacts
        and structure is not None else float("nan"),
        "top_contact": None if top is None else {
            "name": top["name"], "share_a": _share(top),
            "part_level_dba": top.get("part_level_dba"), "level_dba": top.get("level_dba")},
        "best_change": best_change(point.get("contacts", [])),
        "onset": {c["name"]: c.get("onset") for c in point.get("contacts", [])},
        "sensitivities": {c["name"]: c.get("sensitivities") for c in point.get("contacts", [])},
        "linear_risk": {name: {"dynamic_tolerance_m": c.get("dynamic_tolerance_m"),
                               "rattle_risk": c.get("rattle_risk"),
                               "normal_amplitude_m": c.get("normal_amplitude_m")}
                        for name, c in linear.items()},
    }


def target_check(target_dba, worst) -> dict | None:
    """summary.json ``target`` of ``output.target_dba`` [dB(A)] (None without one): the loudest
    point's level, ``exceeded`` (level > target: exit code 4, sarfe.case.errors), the difference
    and whether the target lies within the level's error bound ± (the verdict could flip)."""
    if target_dba is None:
        return None
    level = (worst or {}).get("erp_level_dba")
    known = level is not None and math.isfinite(level)
    error = (worst or {}).get("erp_error_db")
    margin = float(level - target_dba) if known else float("nan")
    return {"target_dba": float(target_dba), "level_dba": level if known else float("nan"),
            "exceeded": bool(known and level > target_dba), "exceeded_by_db": margin,
            "within_error_bound": bool(known and error is not None and abs(margin) <= error)}
