r"""Abaqus ``.inp`` input files (the common shell subset) → :class:`sarfe.mesh.formats.deck.DeckModel`.

meshio's Abaqus reader keeps nodes, connectivity and sets only (no sections, materials,
boundary conditions, loads, springs), drops ``*Instance`` positions and fails on repeated
``*NODE`` blocks, sets made of sets and repeated ``ELSET=``; this small reader covers:

=========================== ===============================================================
keyword                      read as
=========================== ===============================================================
``*NODE`` (repeated)         nodes (``NSET=`` adds them to a node set); ``SYSTEM=R`` only
``*ELEMENT``                 S3, S4, S4R, S8R shells (S8R: split into six linear triangles on
                             its corner and midside nodes, no node dropped); SPRING1/SPRING2;
                             MASS; ``ELSET=`` adds the elements to an element set
``*NSET`` / ``*ELSET``       ids, names of earlier sets (sets of sets), ``GENERATE``;
                             a repeated name appends; ``INSTANCE=`` in an assembly
``*SHELL SECTION``           ``ELSET``, ``MATERIAL``, first data value = thickness (no offset)
``*MATERIAL``                ``*ELASTIC`` (isotropic E, ν) and ``*DENSITY`` (ρ)
``*SPRING``                  stiffness of SPRING1/SPRING2 elements (same DOF at both ends)
``*MASS``                    point mass of MASS elements
``*BOUNDARY``                zero displacements (DOF ranges, ENCASTRE, PINNED, X/Y/ZSYMM,
                             X/Y/ZASYMM) → support set ``boundary`` (model level and steps
                             together; OP=NEW refused)
``*CLOAD``                   nodal forces/moments → load set ``cload`` (or the step's name)
``*PART`` … ``*ASSEMBLY``    parts placed by ``*INSTANCE`` (translation line, then rotation
                             line a, b, angle°: x' = a + R_ab(θ)(x + t − a))
``*INCLUDE, INPUT=``         followed (relative to the including file)
=========================== ===============================================================

Analysis-control keywords (``*STEP``, ``*STATIC``, ``*FREQUENCY``, ``*OUTPUT`` …, ``*HEADING``)
define no part of the model and are skipped. Any other keyword, element type or option is
counted in ``DeckModel.unsupported`` {``*KEYWORD`` or element type: count} — never dropped
silently: the case must name it in ``ignore_cards`` — and options that would change what is
read (a nonzero ``*BOUNDARY`` value, a shell offset, a cylindrical ``*NODE`` system) raise
:class:`~sarfe.mesh.formats.deck.DeckError` naming the file, line and keyword.

Ids: without parts the file's node and element labels are kept. With an assembly, instance k
(k = 0, 1, … in file order) numbers its nodes and elements ``k·10^d + label`` (10^d > every
label of the file) and assembly-level nodes follow the last instance; sets of a part are
named ``<instance>.<set>``. Quantities are in the file's units (apply
:func:`sarfe.mesh.formats.deck.to_si`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from sarfe.mesh.formats.deck import DeckError, DeckModel, PointMasses, ShellElements, SpringElements, SupportSet

# keywords that only steer an analysis (no stiffness, mass, support or load): skipped
_CONTROL = {"HEADING", "PREPRINT", "STEP", "END STEP", "STATIC", "FREQUENCY", "OUTPUT",
            "NODE OUTPUT", "ELEMENT OUTPUT", "NODE PRINT", "EL PRINT", "NODE FILE", "EL FILE",
            "RESTART", "MONITOR", "PHYSICAL CONSTANTS", "END PART", "END INSTANCE",
            "END ASSEMBLY", "ENERGY PRINT", "ENERGY FILE", "CONTACT OUTPUT", "FIELD OUTPUT",
            "HISTORY OUTPUT", "DIAGNOSTICS", "CONTROLS"}
_SHELLS = {"S3": 3, "S3R": 3, "S4": 4, "S4R": 4, "S8R": 8}
_POINT_ELEMENTS = {"SPRING1": 1, "SPRING2": 2, "MASS": 1}
# S8R (corners 0-3, midsides 4-7 on edges 01, 12, 23, 30) → six linear triangles
_S8R_TRIANGLES = np.array([[0, 4, 7], [4, 1, 5], [5, 2, 6], [7, 6, 3], [4, 5, 6], [4, 6, 7]])
_BOUNDARY_TYPES = {"ENCASTRE": (1, 2, 3, 4, 5, 6), "PINNED": (1, 2, 3), "XSYMM": (1, 5, 6),
                   "YSYMM": (2, 4, 6), "ZSYMM": (3, 4, 5), "XASYMM": (2, 3, 4),
                   "YASYMM": (1, 3, 5), "ZASYMM": (1, 2, 6)}


@dataclass(frozen=True)
class _Block:
    """One keyword with its options and data lines: data = [(fields, file, line), …]."""

    keyword: str                 # upper case, single spaces, no '*'
    options: dict                # {OPTION: value or True}
    data: list
    file: str
    line: int

    def where(self, line=None) -> str:
        return f"{self.file}:{line or self.line}: *{self.keyword}"


@dataclass
class _Scope:
    """Labels and sets of one part (or of the whole file / the assembly level)."""

    name: str
    nodes: dict = field(default_factory=dict)          # label → (x, y, z)
    elements: list = field(default_factory=list)       # (label, type, node refs, where)
    nsets: dict = field(default_factory=dict)          # NAME → (name, [labels])
    elsets: dict = field(default_factory=dict)
    sections: list = field(default_factory=list)       # (elset, material, thickness, where)
    springs: list = field(default_factory=list)        # (elset, dof a, dof b, k, where)
    masses: list = field(default_factory=list)         # (elset, mass, where)


@dataclass
class _Instance:
    name: str
    scope: _Scope
    rotation: np.ndarray = field(default_factory=lambda: np.eye(3))
    translation: np.ndarray = field(default_factory=lambda: np.zeros(3))
    offset: int = 0


# ------------------------------------------------------------------------------------ lexing
def _read_lines(path: Path, stack=()):
    """(file, line number, text) of every line, ``*INCLUDE, INPUT=`` files inlined."""
    path = Path(path)
    if path.resolve() in stack:
        raise DeckError(f"{path}: *INCLUDE of itself (include loop)")
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError as exc:
        raise DeckError(f"cannot read {path}: {exc.strerror or exc}") from None
    for number, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        if stripped.upper().startswith("*INCLUDE"):
            options = _options(stripped[1:].split(",")[1:])
            name = options.get("INPUT")
            if not isinstance(name, str):
                raise DeckError(f"{path}:{number}: *INCLUDE needs INPUT=<file>")
            target = Path(name.strip("'\"")) if Path(name).is_absolute() else path.parent / name.strip("'\"")
            if not target.is_file():
                raise DeckError(f"{path}:{number}: *INCLUDE file not found: {target}")
            yield from _read_lines(target, stack + (path.resolve(),))
        else:
            yield str(path), number, line


def _options(parts) -> dict:
    options = {}
    for part in parts:
        part = part.strip()
        if not part:
            continue
        key, _, value = part.partition("=")
        options[" ".join(key.split()).upper()] = value.strip() if value else True
    return options


def _blocks(path: Path):
    """Keyword blocks of a file; keyword and data lines ending in ',' continue."""
    block, pending = None, None
    for file, number, line in _read_lines(path):
        text = line.strip()
        if not text or text.startswith("**"):
            continue
        if pending is not None:                     # continued keyword line
            pending = (pending[0] + text, pending[1], pending[2])
        elif text.startswith("*"):
            if block is not None:
                yield block
            block = None
            pending = (text, file, number)
        else:
            if block is None:
                raise DeckError(f"{file}:{number}: data line before any keyword: {text[:40]!r}")
            fields = [f.strip() for f in text.split(",")]
            if block.data and block.data[-1][0] and block.data[-1][0][-1] == "" \
                    and block.keyword == "ELEMENT":     # element line continued after ','
                block.data[-1] = (block.data[-1][0][:-1] + fields, block.data[-1][1],
                                  block.data[-1][2])
            else:
                block.data.append((fields, file, number))
            continue
        if pending[0].endswith(","):
            continue
        text, file, number = pending
        pending = None
        head, *rest = text[1:].split(",")
        block = _Block(" ".join(head.split()).upper(), _options(rest), [], file, number)
    if block is not None:
        yield block


def _trimmed(fields):
    return fields[:-1] if fields and fields[-1] == "" else fields


def _number(text, block, line, what="value"):
    try:
        return float(text.replace("d", "e").replace("D", "E"))
    except ValueError:
        raise DeckError(f"{block.where(line)}: {what} {text!r} is not a number") from None


def _label(text, block, line):
    try:
        return int(text)
    except ValueError:
        raise DeckError(f"{block.where(line)}: {text!r} is not an integer id") from None


# ------------------------------------------------------------------------------------ reader
class _Reader:
    def __init__(self, path: Path, ignore_cards=()):
        self.path = Path(path)
        self.ignore = {str(c).upper().lstrip("*") for c in ignore_cards}
        self.model = _Scope("")
        self.parts: dict = {}
        self.scope = self.model            # where *NODE/*ELEMENT/sets go
        self.in_assembly = False
        self.assembly = _Scope("assembly")
        self.instances: list = []
        self.materials: dict = {}          # NAME → {"E": , "nu": , "rho": }
        self.material = None
        self.step = None
        self.boundary: list = []           # (reference, components, where)
        self.cloads: list = []             # (load set, reference, component, value, where)
        self.unsupported: dict = {}
        self.ignored: dict = {}

    # bookkeeping ---------------------------------------------------------------------------
    def skip(self, name: str, count: int = 1):
        table = self.ignored if name.upper().lstrip("*") in self.ignore else self.unsupported
        table[name] = table.get(name, 0) + count

    def run(self):
        for block in _blocks(self.path):
            handler = getattr(self, "k_" + block.keyword.replace(" ", "_").lower(), None)
            if handler is not None:
                handler(block)
            elif block.keyword in _CONTROL:
                if block.keyword == "STEP":
                    self.step = block.options.get("NAME", f"step_{block.line}")
                elif block.keyword == "END STEP":
                    self.step = None
                elif block.keyword == "END PART":
                    self.scope = self.model
                elif block.keyword == "END ASSEMBLY":
                    self.in_assembly = False
                    self.scope = self.model
            else:
                self.skip("*" + block.keyword)
                self.material = None if block.keyword in ("MATERIAL",) else self.material
        return self

    # geometry --------------------------------------------------------------------------------
    def k_node(self, block):
        system = str(block.options.get("SYSTEM", "R")).upper()
        if system != "R":
            raise DeckError(f"{block.where()}: SYSTEM={system} (cylindrical/spherical node "
                            "coordinates) is not supported; write rectangular coordinates")
        labels = []
        for fields, _, line in block.data:
            fields = _trimmed(fields)
            label = _label(fields[0], block, line)
            xyz = [_number(v, block, line, "coordinate") if v else 0.0 for v in fields[1:4]]
            if label in self.scope.nodes:
                raise DeckError(f"{block.where(line)}: node {label} defined twice")
            self.scope.nodes[label] = tuple(xyz + [0.0] * (3 - len(xyz)))
            labels.append(label)
        if "NSET" in block.options:
            if self.scope is self.assembly:
                labels = [(None, label) for label in labels]
            self._add_set(self.scope.nsets, block.options["NSET"], labels)

    def k_element(self, block):
        kind = str(block.options.get("TYPE", "")).upper()
        if kind not in _SHELLS and kind not in _POINT_ELEMENTS:
            self.skip(kind or "*ELEMENT without TYPE", len(block.data))
            return
        size = _SHELLS.get(kind) or _POINT_ELEMENTS[kind]
        labels = []
        for fields, _, line in block.data:
            fields = _trimmed(fields)
            if len(fields) != size + 1:
                raise DeckError(f"{block.where(line)}: TYPE={kind} needs {size} nodes, got "
                                f"{len(fields) - 1}")
            label = _label(fields[0], block, line)
            self.scope.elements.append((label, kind, fields[1:], block.where(line)))
            labels.append(label)
        if "ELSET" in block.options:
            if self.scope is self.assembly:
                labels = [(None, label) for label in labels]
            self._add_set(self.scope.elsets, block.options["ELSET"], labels)

    # sets ------------------------------------------------------------------------------------
    def _add_set(self, table, name, labels):
        key = str(name).upper()
        entry = table.setdefault(key, (str(name), []))
        entry[1].extend(labels)

    def _set_members(self, block, table, name_key):
        name = block.options.get(name_key)
        if not isinstance(name, str):
            raise DeckError(f"{block.where()}: needs {name_key}=<name>")
        scope = self.scope
        instance = block.options.get("INSTANCE")
        labels = []
        for fields, _, line in block.data:
            fields = _trimmed(fields)
            if block.options.get("GENERATE"):
                values = [_label(v, block, line) for v in fields]
                start, stop, step = (values + [1])[:3]
                if step <= 0 or stop < start:
                    raise DeckError(f"{block.where(line)}: GENERATE needs start <= end, step > 0")
                labels.extend(range(start, stop + 1, step))
                continue
            for item in fields:
                try:
                    labels.append(int(item))
                except ValueError:            # the name of an earlier set of this kind
                    member = table.get(item.upper())
                    if member is None:
                        raise DeckError(f"{block.where(line)}: {name_key}={name}: no set "
                                        f"{item!r} defined before this line") from None
                    labels.extend(member[1])
        if scope is self.assembly:   # (instance or None for assembly level, label)
            inst = self._instance(instance, block).name.upper() if instance is not None else None
            labels = [label if isinstance(label, tuple) else (inst, label) for label in labels]
        elif instance is not None:
            raise DeckError(f"{block.where()}: INSTANCE= outside *ASSEMBLY")
        self._add_set(table, name, labels)

    def k_nset(self, block):
        self._set_members(block, self.scope.nsets, "NSET")

    def k_elset(self, block):
        self._set_members(block, self.scope.elsets, "ELSET")

    # properties ------------------------------------------------------------------------------
    def k_shell_section(self, block):
        for option in block.options:
            if option not in ("ELSET", "MATERIAL", "SECTION INTEGRATION", "OFFSET", "NAME"):
                raise DeckError(f"{block.where()}: option {option} is not supported")
        offset = block.options.get("OFFSET", "0")
        if str(offset).upper() not in ("0", "0.", "0.0", "MIDDLE", "SMID"):
            raise DeckError(f"{block.where()}: OFFSET={offset} (shell offset) is not supported; "
                            "model the mid-surface")
        if not block.data:
            raise DeckError(f"{block.where()}: the thickness data line is missing")
        fields, _, line = block.data[0]
        thickness = _number(_trimmed(fields)[0], block, line, "thickness")
        self.scope.sections.append((str(block.options.get("ELSET", "")),
                                    str(block.options.get("MATERIAL", "")).upper(),
                                    thickness, block.where(line)))

    def k_material(self, block):
        name = block.options.get("NAME")
        if not isinstance(name, str):
            raise DeckError(f"{block.where()}: needs NAME=<material>")
        self.material = self.materials.setdefault(name.upper(), {"where": block.where()})

    def k_elastic(self, block):
        kind = str(block.options.get("TYPE", "ISOTROPIC")).upper()
        if self.material is None:
            raise DeckError(f"{block.where()}: *ELASTIC outside a *MATERIAL")
        if kind != "ISOTROPIC" or len(block.data) != 1:
            self.skip(f"*ELASTIC, TYPE={kind}" if kind != "ISOTROPIC"
                      else "*ELASTIC (temperature table)")
            return
        fields, _, line = block.data[0]
        values = [_number(v, block, line) for v in _trimmed(fields)[:2]]
        self.material["E"], self.material["nu"] = values[0], values[1]

    def k_density(self, block):
        if self.material is None:
            raise DeckError(f"{block.where()}: *DENSITY outside a *MATERIAL")
        if len(block.data) != 1:
            raise DeckError(f"{block.where()}: a temperature table of densities is not supported "
                            "(one density line)")
        fields, _, line = block.data[0]
        self.material["rho"] = _number(_trimmed(fields)[0], block, line, "density")

    def k_spring(self, block):
        elset = block.options.get("ELSET")
        if not isinstance(elset, str):
            raise DeckError(f"{block.where()}: needs ELSET=<springs>")
        if "ORIENTATION" in block.options or "NONLINEAR" in block.options:
            raise DeckError(f"{block.where()}: ORIENTATION/NONLINEAR springs are not supported")
        if len(block.data) < 2:
            raise DeckError(f"{block.where()}: needs a DOF line and a stiffness line")
        (dofs, _, line), (values, _, kline) = block.data[0], block.data[1]
        dofs = [_label(v, block, line) for v in _trimmed(dofs)]
        k = _number(_trimmed(values)[0], block, kline, "stiffness")
        self.scope.springs.append((elset.upper(), dofs, k, block.where(line)))

    def k_mass(self, block):
        elset = block.options.get("ELSET")
        if not isinstance(elset, str) or not block.data:
            raise DeckError(f"{block.where()}: needs ELSET=<mass elements> and a mass line")
        fields, _, line = block.data[0]
        self.scope.masses.append((elset.upper(), _number(_trimmed(fields)[0], block, line, "mass"),
                                  block.where(line)))

    # assembly --------------------------------------------------------------------------------
    def k_part(self, block):
        name = block.options.get("NAME")
        if not isinstance(name, str):
            raise DeckError(f"{block.where()}: needs NAME=<part>")
        self.scope = self.parts.setdefault(name.upper(), _Scope(name))

    def k_assembly(self, block):
        self.in_assembly = True
        self.scope = self.assembly

    def k_instance(self, block):
        name, part = block.options.get("NAME"), block.options.get("PART")
        if not isinstance(name, str) or not isinstance(part, str):
            raise DeckError(f"{block.where()}: needs NAME=<instance> and PART=<part>")
        if part.upper() not in self.parts:
            raise DeckError(f"{block.where()}: no *PART {part!r} defined before this line")
        instance = _Instance(name, self.parts[part.upper()])
        if len(block.data) >= 1:
            fields, _, line = block.data[0]
            instance.translation = np.array(
                ([_number(v, block, line) for v in _trimmed(fields)] + [0.0] * 3)[:3])
        if len(block.data) >= 2:
            fields, _, line = block.data[1]
            values = [_number(v, block, line) for v in _trimmed(fields)]
            if len(values) != 7:
                raise DeckError(f"{block.where(line)}: rotation line needs a, b (axis points) "
                                "and the angle in degrees (7 values)")
            instance.rotation = (np.array(values[:3]), np.array(values[3:6]), values[6])
        self.instances.append(instance)

    def _instance(self, name, block):
        for inst in self.instances:
            if inst.name.upper() == str(name).upper():
                return inst
        raise DeckError(f"{block.where()}: no *INSTANCE {name!r} defined before this line")

    # supports and loads ----------------------------------------------------------------------
    def k_boundary(self, block):
        for option, value in block.options.items():
            if option not in ("OP",):
                raise DeckError(f"{block.where()}: option {option} is not supported "
                                "(zero displacements only)")
        if str(block.options.get("OP", "MOD")).upper() != "MOD":
            raise DeckError(f"{block.where()}: OP={block.options['OP']} (removing earlier "
                            "supports) is not supported: all *BOUNDARY lines form one support set")
        for fields, _, line in block.data:
            fields = _trimmed(fields)
            if len(fields) >= 2 and fields[1].upper() in _BOUNDARY_TYPES:
                components = _BOUNDARY_TYPES[fields[1].upper()]
            else:
                first = _label(fields[1], block, line)
                last = _label(fields[2], block, line) if len(fields) > 2 and fields[2] else first
                if len(fields) > 3 and fields[3] and _number(fields[3], block, line) != 0.0:
                    raise DeckError(f"{block.where(line)}: prescribed displacement "
                                    f"{fields[3]} is not supported (zero supports only)")
                if not 1 <= first <= last <= 6:
                    raise DeckError(f"{block.where(line)}: DOFs {first}..{last} outside 1..6")
                components = tuple(range(first, last + 1))
            self.boundary.append((fields[0], components, block.where(line)))

    def k_cload(self, block):
        for option in block.options:
            if option not in ("OP",):
                raise DeckError(f"{block.where()}: option {option} is not supported")
        name = self.step or "cload"
        for fields, _, line in block.data:
            fields = _trimmed(fields)
            dof = _label(fields[1], block, line)
            if not 1 <= dof <= 6:
                raise DeckError(f"{block.where(line)}: DOF {dof} outside 1..6")
            self.cloads.append((name, fields[0], dof, _number(fields[2], block, line, "load"),
                                block.where(line)))


# ------------------------------------------------------------------------------ model building
def _rotation(axis_a, axis_b, angle_deg):
    """Rodrigues rotation matrix about the axis a → b by angle_deg (right-handed)."""
    axis = np.asarray(axis_b, float) - np.asarray(axis_a, float)
    norm = np.linalg.norm(axis)
    if norm == 0.0:
        raise ValueError("rotation axis points a and b coincide")
    k = axis / norm
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    t = math.radians(angle_deg)
    return np.eye(3) + math.sin(t) * K + (1 - math.cos(t)) * K @ K


def _build(reader: _Reader) -> DeckModel:
    """Flatten parts and instances into global numbered arrays."""
    placements = ([(reader.model, None)] if not reader.instances else
                  [(inst.scope, inst) for inst in reader.instances] + [(reader.assembly, None)])
    node_ids, points, index_of = [], [], {}
    scoped = []   # (scope, offset, resolve node ref → global id)
    for scope, inst in placements:
        offset = inst.offset if inst else (len(reader.instances) * reader.label_base
                                           if reader.instances else 0)
        labels = np.array(list(scope.nodes), dtype=np.int64)
        xyz = np.array(list(scope.nodes.values()), dtype=float).reshape(-1, 3)
        if inst is not None:
            xyz = xyz + inst.translation
            if isinstance(inst.rotation, tuple):
                a, b, angle = inst.rotation
                xyz = a + (xyz - a) @ _rotation(a, b, angle).T
        for label in labels + offset:
            index_of[int(label)] = len(index_of)
        node_ids.append(labels + offset)
        points.append(xyz)
        scoped.append((scope, offset, inst))
    node_ids = np.concatenate(node_ids) if node_ids else np.zeros(0, np.int64)
    points = np.concatenate(points) if points else np.zeros((0, 3))

    def global_node(ref, scope, offset, where):
        """Global node id of a node reference ('12' or, at assembly level, 'inst.12')."""
        text = str(ref)
        if "." in text and reader.instances:
            inst_name, _, label = text.rpartition(".")
            inst = next((i for i in reader.instances if i.name.upper() == inst_name.upper()), None)
            if inst is None:
                raise DeckError(f"{where}: no instance {inst_name!r} for node {text!r}")
            value = inst.offset + int(label)
        else:
            value = offset + int(text)
        if value not in index_of:
            raise DeckError(f"{where}: node {text} is not defined")
        return value

    offsets = {inst.name.upper(): inst.offset for inst in reader.instances}

    def set_ids(labels, offset):
        """Global ids of set entries: labels of the scope, or (instance | None, label)."""
        return np.unique(np.array([offsets[e[0]] + e[1] if isinstance(e, tuple) and e[0]
                                   else offset + (e[1] if isinstance(e, tuple) else e)
                                   for e in labels], dtype=np.int64))

    # sets (node sets as indices, element sets as ids), qualified with the instance name
    node_sets, element_sets = {}, {}
    for scope, offset, inst in scoped:
        prefix = f"{inst.name}." if inst is not None else ""
        for name, labels in scope.nsets.values():
            ids = set_ids(labels, offset)
            missing = [int(i) for i in ids if int(i) not in index_of]
            if missing:
                raise DeckError(f"{reader.path}: *NSET {name}: node {missing[0]} is not defined")
            node_sets[prefix + name] = np.array([index_of[int(i)] for i in ids], dtype=np.int64)
        for name, labels in scope.elsets.values():
            element_sets[prefix + name] = set_ids(labels, offset)

    # elements
    shell_rows, spring_rows, mass_rows = [], [], []
    for scope, offset, inst in scoped:
        section_of, spring_of, mass_of = {}, {}, {}
        elsets = {key: {e[1] if isinstance(e, tuple) else e for e in labels}
                  for key, (_, labels) in scope.elsets.items()}
        for elset, material, thickness, where in scope.sections:
            if elset.upper() not in elsets:
                raise DeckError(f"{where}: no element set {elset!r}")
            elset = elset.upper()
            mat = reader.materials.get(material)
            if mat is None:
                raise DeckError(f"{where}: no *MATERIAL {material!r}")
            for key in ("E", "nu"):
                if key not in mat:
                    raise DeckError(f"{mat['where']}: material {material!r} has no isotropic "
                                    "*ELASTIC (E, ν)")
            for label in elsets[elset]:
                section_of[label] = (mat["E"], mat["nu"], mat.get("rho", 0.0), thickness)
        for elset, dofs, k, where in scope.springs:
            if elset not in elsets:
                raise DeckError(f"{where}: no element set {elset!r}")
            for label in elsets[elset]:
                spring_of[label] = (dofs, k, where)
        for elset, mass, where in scope.masses:
            if elset not in elsets:
                raise DeckError(f"{where}: no element set {elset!r}")
            for label in elsets[elset]:
                mass_of[label] = mass
        for label, kind, refs, where in scope.elements:
            nodes = [index_of[global_node(r, scope, offset, where)] for r in refs]
            element_id = offset + label
            if kind in _SHELLS:
                if label not in section_of:
                    raise DeckError(f"{where}: shell element {label} has no *SHELL SECTION")
                shell_rows.append((element_id, kind, nodes, section_of[label]))
            elif kind == "MASS":
                if label not in mass_of:
                    raise DeckError(f"{where}: MASS element {label} has no *MASS")
                mass_rows.append((element_id, nodes[0], mass_of[label]))
            else:
                if label not in spring_of:
                    raise DeckError(f"{where}: spring element {label} has no *SPRING")
                dofs, k, swhere = spring_of[label]
                if kind == "SPRING2" and (len(dofs) != 2 or dofs[0] != dofs[1]):
                    raise DeckError(f"{swhere}: SPRING2 between different DOFs {dofs} is not "
                                    "supported (same DOF at both ends)")
                if not 1 <= dofs[0] <= 6:
                    raise DeckError(f"{swhere}: DOF {dofs[0]} outside 1..6")
                spring_rows.append((element_id, kind, nodes[0],
                                    nodes[1] if kind == "SPRING2" else -1, dofs[0] - 1, k))

    top = len(reader.instances) * reader.label_base if reader.instances else 0

    def node_index(text, where):
        return index_of[global_node(text, None, top, where)]

    deck_path = str(reader.path)
    supports = {}
    if reader.boundary:
        held = np.zeros((len(node_ids), 6), dtype=bool)
        for ref, components, where in reader.boundary:
            for node in _node_reference(ref, node_sets, node_index, where):
                held[node, np.array(components) - 1] = True
        nodes = np.flatnonzero(held.any(axis=1))
        supports["boundary"] = SupportSet(nodes, held[nodes])
    loads = {}
    for name, ref, dof, value, where in reader.cloads:
        table = loads.setdefault(name, np.zeros((len(node_ids), 6)))
        for node in _node_reference(ref, node_sets, node_index, where):
            table[node, dof - 1] += value

    return DeckModel(
        source=deck_path, node_ids=node_ids, points=points,
        displacement_frames=np.broadcast_to(np.eye(3), (len(node_ids), 3, 3)).copy(),
        shells=_shell_table(shell_rows, points), springs=_spring_table(spring_rows),
        point_masses=_mass_table(mass_rows), supports=supports, loads=loads,
        node_sets=node_sets, element_sets=element_sets,
        unsupported=dict(reader.unsupported), ignored=dict(reader.ignored))


def _node_reference(ref, node_sets, node_index, where):
    """Node indices of a *BOUNDARY/*CLOAD reference: a node label ('12', 'Inst-1.12') or the
    name of a node set (case-insensitive, 'Inst-1.Set' for a part's set)."""
    text = str(ref)
    if text.rpartition(".")[2].isdigit():
        return [node_index(text, where)]
    for name, nodes in node_sets.items():
        if name.upper() == text.upper():
            return list(nodes)
    raise DeckError(f"{where}: no node set {text!r}")


def _shell_table(rows, points) -> ShellElements:
    if not rows:
        return ShellElements()
    ids, triangles, owner, sections = [], [], [], []
    for row, (element_id, kind, nodes, section) in enumerate(rows):
        nodes = np.asarray(nodes, dtype=np.int64)
        if kind in ("S3", "S3R"):
            local = nodes[None, :]
        elif kind in ("S4", "S4R"):
            local = nodes[[[0, 1, 2], [0, 2, 3]]]
        else:
            local = nodes[_S8R_TRIANGLES]
        ids.append(element_id)
        triangles.append(local)
        owner.extend([row] * len(local))
        sections.extend([section] * len(local))
    triangles = np.concatenate(triangles)
    young, poisson, density, thickness = (np.array(v, dtype=float) for v in zip(*sections))
    q = (young / (1 - poisson**2))[:, None, None] * np.stack([
        np.stack([np.ones_like(poisson), poisson, 0 * poisson], axis=-1),
        np.stack([poisson, np.ones_like(poisson), 0 * poisson], axis=-1),
        np.stack([0 * poisson, 0 * poisson, (1 - poisson) / 2], axis=-1)], axis=1)
    edge = points[triangles[:, 1]] - points[triangles[:, 0]]
    length = np.linalg.norm(edge, axis=1, keepdims=True)
    axis = np.divide(edge, length, out=np.zeros_like(edge), where=length > 0)
    return ShellElements(
        element_ids=np.array(ids, dtype=np.int64), property_ids=np.zeros(len(ids), np.int64),
        triangles=triangles, triangle_element=np.array(owner, dtype=np.int64),
        membrane=thickness[:, None, None] * q, coupling=np.zeros_like(q),
        bending=(thickness**3 / 12)[:, None, None] * q,
        transverse_shear=np.zeros((len(triangles), 2, 2)), material_axis=axis,
        mass_per_area=density * thickness, rotary_inertia_per_area=density * thickness**3 / 12,
        thickness=thickness, offset=np.zeros(len(triangles)))


def _spring_table(rows) -> SpringElements:
    if not rows:
        return SpringElements()
    ids, cards, a, b, component, k = zip(*rows)
    stiffness = np.zeros((len(rows), 6))
    stiffness[np.arange(len(rows)), component] = k
    return SpringElements(
        card=np.array(cards), element_ids=np.array(ids, dtype=np.int64),
        property_ids=np.zeros(len(rows), np.int64), node_a=np.array(a, dtype=np.int64),
        node_b=np.array(b, dtype=np.int64), stiffness=stiffness,
        frames=np.broadcast_to(np.eye(3), (len(rows), 3, 3)).copy(),
        structural_damping=np.zeros(len(rows)), viscous_damping=np.zeros((len(rows), 6)),
        location=np.full(len(rows), np.nan))       # scalar springs on the node DOFs


def _mass_table(rows) -> PointMasses:
    if not rows:
        return PointMasses()
    ids, nodes, mass = zip(*rows)
    return PointMasses(element_ids=np.array(ids, dtype=np.int64),
                       node=np.array(nodes, dtype=np.int64), mass=np.array(mass, dtype=float),
                       offset=np.zeros((len(rows), 3)), inertia=np.zeros((len(rows), 3, 3)))


def read_abaqus(path, ignore_cards=()) -> DeckModel:
    """Read an Abaqus ``.inp`` file (module docstring) into a DeckModel in the file's units.

    ignore_cards: keywords (``*SURFACE`` or ``SURFACE``) or element types (``C3D8R``) the
    caller knowingly leaves out; they are counted in ``ignored`` instead of ``unsupported``.
    Raises :class:`DeckError` (one line: file, line, keyword) for input outside the subset
    that cannot be skipped safely.
    """
    path = Path(path)
    if not path.is_file():
        raise DeckError(f"deck file not found: {path}")
    reader = _Reader(path, ignore_cards)
    reader.label_base = 1
    reader.run()
    labels = [label for scope in [reader.model, reader.assembly, *reader.parts.values()]
              for label in list(scope.nodes) + [e[0] for e in scope.elements]]
    reader.label_base = 10 ** len(str(max(labels, default=0)))
    for k, inst in enumerate(reader.instances):
        inst.offset = k * reader.label_base
    if reader.instances and (reader.model.nodes or reader.model.elements):
        raise DeckError(f"{path}: nodes or elements outside *PART/*ASSEMBLY in a file with "
                        "*INSTANCE")
    try:
        return _build(reader)
    except ValueError as exc:
        if isinstance(exc, DeckError):
            raise
        raise DeckError(f"{path}: {exc}") from None


def section_values(path) -> list[tuple[str, str, float]]:
    """(where, quantity, value in the file's units) of each material's E ('E') and ρ ('rho')
    and each shell section's thickness ('thickness'), for messages that name the keyword line:
    ("plate.inp:47: *MATERIAL, NAME=PP", "E", 2.0e3)."""
    reader = _Reader(Path(path))
    reader.label_base = 1
    reader.run()
    values = []
    for name, material in reader.materials.items():
        values += [(f"{material['where']}, NAME={name}", key, float(material[key]))
                   for key in ("E", "rho") if key in material]
    for scope in [reader.model, reader.assembly, *reader.parts.values()]:
        values += [(where, "thickness", float(thickness)) for _, _, thickness, where in scope.sections]
    return values

