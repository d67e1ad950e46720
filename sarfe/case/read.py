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
import dataclasses
import re
from dataclasses import dataclass, field
from pathlib import Path

import yaml

from sarfe.case.config import CaseConfig, ContactConfig, build_config
from sarfe.case.errors import CaseError, line_of
from sarfe.case.messages import validate_schema
from sarfe.case.normalize import normalize
from sarfe.case.plausibility import check_finite

#: contact keys with a typed field of their own in :class:`~sarfe.case.config.ContactConfig`
CONTACT_KEYS = frozenset(f.name for f in dataclasses.fields(ContactConfig)) - {
    "index", "name", "kind", "params"}

@dataclass(frozen=True)
class Case:
    """A validated case: ``config`` the typed configuration (:class:`sarfe.case.config.CaseConfig`,
    what the pipeline reads), ``data`` the normalized mapping with every default filled in (what
    is written out: summary.json ``case_data``, and hashed into the linear stage's key). SI units
    except mesh coordinates.

    ``source``: the YAML file (None for a dict), ``base_dir``: directory that relative file names in
    the case refer to, ``lines``: {key path tuple: line} for error messages. ``config`` is None only
    while :func:`load_case` normalizes ``data``. A changed setting is a new Case with the section
    replaced and ``data`` updated to match (:meth:`with_solver`, :meth:`with_reduction`,
    :meth:`with_contact`, :meth:`with_generator`), never an edited mapping loaded again.
    """

    name: str
    data: dict
    source: str | None = None
    base_dir: Path = Path(".")
    lines: dict = field(default_factory=dict, compare=False, repr=False)
    config: CaseConfig | None = field(default=None, compare=False, repr=False)

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

    # ----------------------------------------------------------------------- changed settings
    def with_solver(self, **changes) -> Case:
        """This case with :class:`~sarfe.case.config.SolverConfig` fields changed (``harmonics=H,
        samples_per_period=N, resolution='fixed'`` …). ValueError when N < 2H + 1."""
        solver = dataclasses.replace(self.config.solver, **changes)
        if solver.samples_per_period < 2 * solver.harmonics + 1:
            raise ValueError(f"samples_per_period = {solver.samples_per_period} must be >= 2H+1 "
                             f"= {2 * solver.harmonics + 1} for harmonics H = {solver.harmonics}")
        return self._changed(("solver",), changes, solver=solver)

    def with_reduction(self, **changes) -> Case:
        """This case (FE) with :class:`~sarfe.case.config.ReductionConfig` fields changed
        (``cutoff_hz=f``, or ``cutoff_hz=None, mode_count=m`` …; None removes a setting).
        ValueError when both a cutoff and a mode count remain."""
        reduction = dataclasses.replace(self.config.reduction, **changes)
        if reduction.cutoff_hz is not None and reduction.mode_count is not None:
            raise ValueError("give reduction.cutoff_hz or reduction.mode_count, not both")
        return self._changed(("reduction",), changes, reduction=reduction)

    def with_generator(self, **changes) -> Case:
        """This case (model.fe.generator) with :class:`~sarfe.case.config.GeneratorConfig` fields
        changed (``mesh_size_m=h`` …)."""
        fe = self.config.model.fe
        model = dataclasses.replace(self.config.model, fe=dataclasses.replace(
            fe, generator=dataclasses.replace(fe.generator, **changes)))
        return self._changed(("model", "fe", "generator"), changes, model=model)

    def with_contact(self, index: int, **changes) -> Case:
        """This case with keys of contacts[index] changed: its typed fields (``gap_m``,
        ``preload_N``, ``tolerance_m`` …) and law parameters (``normal_stiffness_N_m`` …, in
        ``params``); None removes a key. The law's own checks are not run again."""
        contact = self.config.contacts[index]
        params = {k: v for k, v in {**contact.params, **changes}.items() if v is not None}
        typed = {k: v for k, v in changes.items() if k in CONTACT_KEYS}
        contacts = list(self.config.contacts)
        contacts[index] = dataclasses.replace(contact, params=params, **typed)
        return self._changed(("contacts", index), changes, contacts=tuple(contacts))

    def _changed(self, path, changes, **sections) -> Case:
        """The case with ``sections`` of its config replaced and the mapping at ``path`` of
        ``data`` given the same ``changes`` (None: the key removed)."""
        data = copy.deepcopy(self.data)
        mapping = data
        for key in path:
            mapping = mapping[key] if isinstance(key, int) else mapping.setdefault(key, {})
        for key, value in changes.items():
            if value is None:
                mapping.pop(key, None)
            else:
                mapping[key] = copy.deepcopy(value)
        return dataclasses.replace(self, data=data,
                                   config=dataclasses.replace(self.config, **sections))


# ----------------------------------------------------------------------------------- YAML reading
# Safety limits of the YAML reader (not performance targets): a case file is a few kB, 6 levels
# deep, with a few anchors (a shared material); these bounds are far above that and keep a hostile
# or broken file ("billion laughs": 2 kB of nested aliases that expand to 10⁹ values) from taking
# minutes and gigabytes. Each refusal is a one-line CaseError naming the file and the limit.
MAX_CASE_FILE_BYTES = 2 ** 20       # 1 MiB: ≈ 5 s of PyYAML (4 MiB took 19 s); matrices → .npz/.mtx
MAX_YAML_DEPTH = 32                 # nesting levels (a case has 6; generator params a few more)
MAX_YAML_ALIASES = 100              # *alias uses in one file
MAX_ALIAS_EXPANSION = 100_000       # values the aliases add when expanded (a copy per use)


class YamlLimitError(yaml.YAMLError):
    """A case file beyond one of the reader's safety limits; ``line`` (1-based) where seen."""

    def __init__(self, problem: str, mark=None):
        super().__init__(problem)
        self.problem = problem
        self.line = None if mark is None else mark.line + 1


class CaseLoader(yaml.SafeLoader):
    """SafeLoader that also reads 2.1e9 / 1e-3 as numbers (YAML 1.1 wants '2.1e+9', '1.0e-3'),
    and refuses documents beyond the safety limits above: nesting deeper than
    :data:`MAX_YAML_DEPTH`, more than :data:`MAX_YAML_ALIASES` aliases, an alias inside its own
    anchor, or aliases that expand to more than :data:`MAX_ALIAS_EXPANSION` extra values
    (counted on the composed node graph, where an alias is a shared node, before anything is
    expanded). Raises :class:`YamlLimitError`."""

    def __init__(self, stream):
        super().__init__(stream)
        self.depth = 0
        self.alias_count = 0

    def compose_node(self, parent, index):
        if self.check_event(yaml.AliasEvent):
            self.alias_count += 1
            if self.alias_count > MAX_YAML_ALIASES:
                raise YamlLimitError(f"more than {MAX_YAML_ALIASES} aliases (*name); a case file "
                                     "needs a few at most", self.peek_event().start_mark)
            return super().compose_node(parent, index)
        self.depth += 1
        if self.depth > MAX_YAML_DEPTH:
            raise YamlLimitError(f"nested more than {MAX_YAML_DEPTH} levels deep",
                                 self.peek_event().start_mark)
        try:
            return super().compose_node(parent, index)
        finally:
            self.depth -= 1

    def compose_document(self):
        node = super().compose_document()
        if node is not None:
            check_alias_expansion(node)
        return node


CaseLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"""^(?:[-+]?(?:[0-9][0-9_]*)\.[0-9_]*(?:[eE][-+]?[0-9]+)?
                  |[-+]?(?:[0-9][0-9_]*)(?:[eE][-+]?[0-9]+)
                  |\.[0-9_]+(?:[eE][-+]?[0-9]+)?
                  |[-+]?\.(?:inf|Inf|INF)
                  |\.(?:nan|NaN|NAN))$""", re.X),
    list("-+0123456789."))


def _children(node) -> list:
    if isinstance(node, yaml.MappingNode):
        return [n for pair in node.value for n in pair]
    return list(node.value) if isinstance(node, yaml.SequenceNode) else []


def check_alias_expansion(root) -> int:
    """The number of values (nodes) of the composed document ``root`` once every alias is
    expanded, computed without expanding: size(n) = 1 + Σ size(children), memoized per node, so
    an alias (a node met again) costs one addition. YamlLimitError when an alias sits inside its
    own anchor (a recursive document) or the aliases add more than :data:`MAX_ALIAS_EXPANSION`
    values to the distinct ones."""
    size, state = {}, {}            # id → expanded size; id → 1 on the path, 2 done
    stack = [(root, False)]
    while stack:
        node, children_done = stack.pop()
        key = id(node)
        if children_done:
            size[key] = 1 + sum(size[id(child)] for child in _children(node))
            state[key] = 2
            continue
        if state.get(key) == 2:
            continue
        state[key] = 1
        stack.append((node, True))
        for child in _children(node):
            if state.get(id(child)) == 1:
                raise YamlLimitError("an alias inside its own anchor (a recursive document)",
                                     child.start_mark)
            if state.get(id(child)) != 2:
                stack.append((child, False))
    expanded = size[id(root)]
    if expanded - len(size) > MAX_ALIAS_EXPANSION:
        raise YamlLimitError(f"aliases expand to {expanded:.3g} values (the file holds "
                             f"{len(size)}); at most {MAX_ALIAS_EXPANSION:,} more than written "
                             "are accepted (nested aliases, a 'billion laughs'?)")
    return expanded


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


def read_case_text(path) -> str:
    """The text of the case file ``path``: CaseError (naming it) when it is missing, not a
    regular file (a folder, a device such as /dev/zero, a pipe), larger than
    :data:`MAX_CASE_FILE_BYTES`, unreadable or not UTF-8. At most that many bytes are read."""
    source = str(path)
    path = Path(path)
    try:
        if not path.exists():
            raise CaseError("case file not found", source=source)
        if not path.is_file():
            raise CaseError("the case file is not a regular file (a folder, device or pipe); "
                            "give a YAML file", source=source)
        with open(path, "rb") as stream:
            raw = stream.read(MAX_CASE_FILE_BYTES + 1)
    except OSError as exc:
        raise CaseError(f"cannot read case file: {exc.strerror or exc}", source=source) from None
    if len(raw) > MAX_CASE_FILE_BYTES:
        raise CaseError(f"the case file is larger than {MAX_CASE_FILE_BYTES // 2 ** 20} MiB, the "
                        "limit of a case file (a safety limit); give large matrices as .npz, "
                        ".npy or .mtx files", source=source)
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise CaseError(f"cannot read case file: {exc}", source=source) from None


def read_yaml(path):
    """Parse a YAML case file → (data, lines). Malformed YAML, or YAML beyond the reader's
    safety limits (:class:`CaseLoader`), → CaseError with the line."""
    source = str(path)
    text = read_case_text(path)
    loader = CaseLoader(text)
    try:
        node = loader.get_single_node()
        if node is None:
            raise CaseError("the case file is empty", source=source)
        lines = _node_lines(node, source=source)   # before merge keys (<<) are flattened into it
        data = loader.construct_document(node)
    except YamlLimitError as exc:
        raise CaseError(f"YAML beyond the reader's safety limits: {exc.problem}", source=source,
                        line=exc.line) from None
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        problem = exc.problem or exc.context or "syntax error"
        raise CaseError(f"malformed YAML{where}: {problem}", source=source) from None
    except yaml.YAMLError as exc:
        raise CaseError(f"malformed YAML: {exc}", source=source) from None
    finally:
        loader.dispose()
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
    case = normalize(Case(name=data["name"], data=data, source=source, base_dir=base, lines=lines))
    return dataclasses.replace(case, config=build_config(case.data))


__all__ = ["Case", "CaseLoader", "YamlLimitError", "check_alias_expansion", "load_case",
           "read_case_text", "read_yaml", "MAX_CASE_FILE_BYTES", "MAX_YAML_DEPTH",
           "MAX_YAML_ALIASES", "MAX_ALIAS_EXPANSION"]
