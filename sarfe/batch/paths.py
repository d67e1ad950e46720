"""Parameter paths into a case: ``contacts[0].gap_m``, ``contacts[name=pocket_1].friction_coefficient``,
``excitation.force_N``, ``contacts[*].normal_stiffness_N_m``.

A path is a dot-separated list of keys; a key may carry one selector in brackets:
``[i]`` (list index, negative allowed), ``[*]`` (every list item) or ``[field=value]`` (the list
items whose ``field`` equals ``value`` as text). Setting a path writes the last key of every matched
mapping; every earlier step must already exist in the case.
"""
from __future__ import annotations

import copy
import re
from dataclasses import dataclass

_STEP = re.compile(r"^(?P<key>[A-Za-z_][A-Za-z0-9_\-]*)(?:\[(?P<selector>[^\[\]]+)\])?$")


class PathError(ValueError):
    """A parameter path that is malformed or matches nothing in the case."""


@dataclass(frozen=True)
class Step:
    key: str
    selector: str | None  # None, "*", "3", "-1" or "name=pocket_1"


def parse_path(path: str) -> tuple[Step, ...]:
    """Split ``a.b[0].c`` into steps; raises PathError naming the bad part."""
    if not isinstance(path, str) or not path:
        raise PathError(f"parameter path must be a non-empty string, got {path!r}")
    steps = []
    for part in path.split("."):
        match = _STEP.match(part)
        if match is None:
            raise PathError(f"parameter path {path!r}: cannot parse {part!r} "
                            "(expected key, key[index], key[*] or key[field=value])")
        steps.append(Step(match["key"], match["selector"]))
    return tuple(steps)


def _select(items, selector: str, path: str):
    if not isinstance(items, list):
        raise PathError(f"parameter path {path!r}: [{selector}] applied to a {type(items).__name__}, not a list")
    if selector == "*":
        return list(items)
    if "=" in selector:
        field, value = (s.strip() for s in selector.split("=", 1))
        chosen = [item for item in items if isinstance(item, dict) and str(item.get(field)) == value]
        if not chosen:
            raise PathError(f"parameter path {path!r}: no list item with {field} = {value}")
        return chosen
    try:
        index = int(selector)
    except ValueError:
        raise PathError(f"parameter path {path!r}: bad selector [{selector}]") from None
    if not -len(items) <= index < len(items):
        raise PathError(f"parameter path {path!r}: index {index} out of range (list has {len(items)} items)")
    return [items[index]]


def _parents(data: dict, steps: tuple[Step, ...], path: str) -> list[dict]:
    """The mappings that hold the last key of ``steps``."""
    nodes = [data]
    for depth, step in enumerate(steps):
        last = depth == len(steps) - 1
        following = []
        for node in nodes:
            if not isinstance(node, dict):
                raise PathError(f"parameter path {path!r}: {step.key!r} looked up in a {type(node).__name__}")
            if last and step.selector is None:
                following.append(node)
                continue
            if step.key not in node:
                raise PathError(f"parameter path {path!r}: the case has no key {step.key!r} here")
            value = node[step.key]
            following.extend(_select(value, step.selector, path) if step.selector else [value])
        nodes = following
    return nodes


def count_matches(data: dict, path: str) -> int:
    """Number of places ``path`` would be written (0: a selector matches no list item)."""
    steps = parse_path(path)
    return len(_parents(data, steps, path)) if steps[-1].selector is None else 0


def set_path(data: dict, path: str, value) -> dict:
    """Copy of ``data`` with ``value`` written at every place ``path`` matches (``None`` removes
    the key, e.g. ``excitation.sweep: null`` to give ``excitation.frequency_hz`` instead)."""
    steps = parse_path(path)
    if steps[-1].selector is not None:
        raise PathError(f"parameter path {path!r}: the last step must be a plain key")
    out = copy.deepcopy(data)
    for node in _parents(out, steps, path):
        if value is None:
            node.pop(steps[-1].key, None)
        else:
            node[steps[-1].key] = value
    return out


def apply_parameters(data: dict, parameters: dict) -> dict:
    """Copy of the case ``data`` with every ``{path: value}`` written in order."""
    out = data
    for path, value in parameters.items():
        out = set_path(out, path, value)
    return out
