"""Case files: read YAML (line numbers kept), validate against the JSON schema, apply defaults.

    load_case(path_or_dict) -> Case      # raises CaseError with one line: file: key.path: problem
    read_yaml(path) -> (data, lines)     # the mapping and {key path: line}

The steps: YAML (:class:`CaseLoader`, duplicate keys refused) → non-finite numbers
(:func:`sarfe.case.plausibility.check_finite`) → the schema (:func:`sarfe.case.messages.
validate_schema`) → cross-key rules and defaults (:func:`sarfe.case.normalize.normalize`) → the typed
configuration (:func:`sarfe.case.config.build_config`). The reference of every key is
docs/case-file.md. Checks that need the mesh (node groups, contact pairing) live in
:mod:`sarfe.pipeline`.
"""
from __future__ import annotations

import copy
import re
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import yaml

from sarfe.case.config import build_config
from sarfe.case.errors import CaseError, line_of
from sarfe.case.messages import validate_schema
from sarfe.case.normalize import normalize
from sarfe.case.plausibility import check_finite


@dataclass(frozen=True)
class Case:
    """A validated case with every default filled in (``data``), SI units except mesh coordinates.

    ``source``: the YAML file (None for a dict), ``base_dir``: directory that relative file names in
    the case refer to, ``lines``: {key path tuple: line} for error messages.
    """

    name: str
    data: dict
    source: str | None = None
    base_dir: Path = Path(".")
    lines: dict = field(default_factory=dict, compare=False, repr=False)

    @cached_property
    def config(self):
        """The typed configuration (:class:`sarfe.case.config.CaseConfig`), built once from the
        normalized ``data``."""
        return build_config(self.data)

    @property
    def is_fe(self) -> bool:
        return "fe" in self.data["model"]

    def error(self, message, key_path=()) -> CaseError:
        """A CaseError located in this case file (with the line of the deepest known key)."""
        path = tuple(key_path) if not isinstance(key_path, str) else ()
        return CaseError(message, key_path, self.source, line_of(self.lines, path))

    def resolve(self, file_name) -> Path:
        """A file named in the case, relative to the case file's directory."""
        path = Path(file_name).expanduser()
        return path if path.is_absolute() else self.base_dir / path


# ----------------------------------------------------------------------------------- YAML reading
class CaseLoader(yaml.SafeLoader):
    """SafeLoader that also reads 2.1e9 / 1e-3 as numbers (YAML 1.1 wants '2.1e+9', '1.0e-3')."""


CaseLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"""^(?:[-+]?(?:[0-9][0-9_]*)\.[0-9_]*(?:[eE][-+]?[0-9]+)?
                  |[-+]?(?:[0-9][0-9_]*)(?:[eE][-+]?[0-9]+)
                  |\.[0-9_]+(?:[eE][-+]?[0-9]+)?
                  |[-+]?\.(?:inf|Inf|INF)
                  |\.(?:nan|NaN|NAN))$""", re.X),
    list("-+0123456789."))


def _node_lines(node, path=(), lines=None, source=None):
    """Walk a composed YAML node: {key path: 1-based line}; duplicate keys are errors."""
    lines = {} if lines is None else lines
    lines[path] = node.start_mark.line + 1
    if isinstance(node, yaml.MappingNode):
        seen = set()
        for key_node, value_node in node.value:
            key = key_node.value
            if key in seen:
                raise CaseError(f"duplicate key '{key}'", path + (key,), source,
                                key_node.start_mark.line + 1)
            seen.add(key)
            _node_lines(value_node, path + (key,), lines, source)
            lines[path + (key,)] = key_node.start_mark.line + 1
    elif isinstance(node, yaml.SequenceNode):
        for index, item in enumerate(node.value):
            _node_lines(item, path + (index,), lines, source)
    return lines


def line_of(lines, path):
    path = tuple(path)
    while path and path not in lines:
        path = path[:-1]
    return lines.get(path) if path else None


def read_yaml(path):
    """Parse a YAML case file → (data, lines). Malformed YAML → CaseError with line and column."""
    source = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8")
    except FileNotFoundError:
        raise CaseError("case file not found", source=source) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise CaseError(f"cannot read case file: {exc}", source=source) from None
    try:
        node = yaml.compose(text, Loader=CaseLoader)
        data = yaml.load(text, Loader=CaseLoader)  # noqa: S506 (a SafeLoader)
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        problem = exc.problem or exc.context or "syntax error"
        raise CaseError(f"malformed YAML{where}: {problem}", source=source) from None
    except yaml.YAMLError as exc:
        raise CaseError(f"malformed YAML: {exc}", source=source) from None
    if node is None:
        raise CaseError("the case file is empty", source=source)
    lines = _node_lines(node, source=source)
    return data, lines


def load_case(path_or_dict, base_dir=None) -> Case:
    """Read (a YAML file) or take (a dict), validate and fill defaults → :class:`Case`.

    Raises CaseError (a ValueError) with one line ``file: key.path: problem (line n)``.
    """
    if isinstance(path_or_dict, Case):
        return path_or_dict
    if isinstance(path_or_dict, dict):
        data, lines, source = copy.deepcopy(path_or_dict), {}, None
        base = Path(base_dir) if base_dir else Path.cwd()
    else:
        source = str(path_or_dict)
        data, lines = read_yaml(path_or_dict)
        base = Path(base_dir) if base_dir else Path(path_or_dict).resolve().parent
    check_finite(data, source, lines)
    validate_schema(data, source, lines)
    case = Case(name=data["name"], data=data, source=source, base_dir=base, lines=lines)
    return normalize(case)


__all__ = ["Case", "CaseLoader", "load_case", "read_yaml"]
