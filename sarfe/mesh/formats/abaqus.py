r"""Abaqus ``.inp`` input files (the common shell subset) → :class:`sarfe.mesh.formats.deck.DeckModel`.

meshio's Abaqus reader keeps nodes, connectivity and sets only (no sections, materials,
boundary conditions, loads, springs), drops ``*Instance`` positions and fails on repeated
``*NODE`` blocks, sets made of sets and repeated ``ELSET=``; this small reader covers:

=========================== ===============================================================
keyword                      read as
=========================== ===============================================================
``*NODE`` (repeated)         nodes (``NSET=`` adds them to a node set); ``SYSTEM=R`` only
``*ELEMENT``                 S3, S4, S4R, S8R shells (S8R: split into six linear triangles on
                             its corner and midside nodes, no node dropped); B31, B32, B32R
                             beams (:mod:`~sarfe.mesh.formats.abaqus_beams`); SPRING1/SPRING2;
                             MASS; ``ELSET=`` adds the elements to an element set
``*NSET`` / ``*ELSET``       ids, names of earlier sets (sets of sets), ``GENERATE``;
                             a repeated name appends; ``INSTANCE=`` in an assembly
``*SHELL SECTION``           ``ELSET``, ``MATERIAL``, first data value = thickness (no offset);
                             ``NODAL THICKNESS``: each element's thickness = the mean of its
                             nodes' ``*NODAL THICKNESS`` values (constant per element)
``*NODAL THICKNESS``         node label or node set, thickness
``*BEAM SECTION``            ``ELSET``, ``MATERIAL``, ``SECTION`` = RECT, CIRC, PIPE: dimensions,
                             then the local 1-direction (default (0, 0, −1)); no offsets
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

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from sarfe.mesh.formats.abaqus_beams import BEAM_NODES, DEFAULT_DIRECTION_1
from sarfe.mesh.formats.abaqus_lines import keyword_blocks, parse_label, parse_number, trimmed
from sarfe.mesh.formats.abaqus_model import POINT_ELEMENT_NODES, SHELL_NODES, build_deck_model
from sarfe.mesh.formats.deck import DeckError, DeckModel

# keywords that only steer an analysis (no stiffness, mass, support or load): skipped
_CONTROL = {"HEADING", "PREPRINT", "STEP", "END STEP", "STATIC", "FREQUENCY", "OUTPUT",
            "NODE OUTPUT", "ELEMENT OUTPUT", "NODE PRINT", "EL PRINT", "NODE FILE", "EL FILE",
            "RESTART", "MONITOR", "PHYSICAL CONSTANTS", "END PART", "END INSTANCE",
            "END ASSEMBLY", "ENERGY PRINT", "ENERGY FILE", "CONTACT OUTPUT", "FIELD OUTPUT",
            "HISTORY OUTPUT", "DIAGNOSTICS", "CONTROLS"}
_BOUNDARY_TYPES = {"ENCASTRE": (1, 2, 3, 4, 5, 6), "PINNED": (1, 2, 3), "XSYMM": (1, 5, 6),
                   "YSYMM": (2, 4, 6), "ZSYMM": (3, 4, 5), "XASYMM": (2, 3, 4),
                   "YASYMM": (1, 3, 5), "ZASYMM": (1, 2, 6)}


@dataclass
class _Scope:
    """Labels and sets of one part (or of the whole file / the assembly level)."""

    name: str
    nodes: dict = field(default_factory=dict)          # label → (x, y, z)
    elements: list = field(default_factory=list)       # (label, type, node refs, where)
    nsets: dict = field(default_factory=dict)          # NAME → (name, [labels])
    elsets: dict = field(default_factory=dict)
    sections: list = field(default_factory=list)       # (elset, material, thickness, where)
    beam_sections: list = field(default_factory=list)  # (elset, material, kind, dims, n1, where)
    nodal_thickness: list = field(default_factory=list)  # (node label or nset, t, where)
    springs: list = field(default_factory=list)        # (elset, dof a, dof b, k, where)
    masses: list = field(default_factory=list)         # (elset, mass, where)


@dataclass
class _Instance:
    name: str
    scope: _Scope
    rotation: np.ndarray = field(default_factory=lambda: np.eye(3))
    translation: np.ndarray = field(default_factory=lambda: np.zeros(3))
    offset: int = 0


class _Reader:
    """The keyword handlers ``k_<keyword>``: each block's content into scopes, materials,
    instances, supports and loads (flattened by :func:`sarfe.mesh.formats.abaqus_model.
    build_deck_model`)."""


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
        self.unsupported_where: dict = {}   # name → "file:line" of its first appearance

    # bookkeeping ---------------------------------------------------------------------------
    def skip(self, name: str, count: int = 1, where: str = ""):
        table = self.ignored if name.upper().lstrip("*") in self.ignore else self.unsupported
        table[name] = table.get(name, 0) + count
        if where:
            self.unsupported_where.setdefault(name, where)

    def run(self):
        for block in keyword_blocks(self.path):
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
                self.skip("*" + block.keyword, where=f"{block.file}:{block.line}")
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
            fields = trimmed(fields)
            label = parse_label(fields[0], block, line)
            xyz = [parse_number(v, block, line, "coordinate") if v else 0.0 for v in fields[1:4]]
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
        size = SHELL_NODES.get(kind) or BEAM_NODES.get(kind) or POINT_ELEMENT_NODES.get(kind)
        if size is None:
            self.skip(kind or "*ELEMENT without TYPE", len(block.data),
                      where=f"{block.file}:{block.line}")
            return
        labels = []
        for fields, _, line in block.data:
            fields = trimmed(fields)
            if len(fields) != size + 1:
                raise DeckError(f"{block.where(line)}: TYPE={kind} needs {size} nodes, got "
                                f"{len(fields) - 1}")
            label = parse_label(fields[0], block, line)
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
            fields = trimmed(fields)
            if block.options.get("GENERATE"):
                values = [parse_label(v, block, line) for v in fields]
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
            if option not in ("ELSET", "MATERIAL", "SECTION INTEGRATION", "OFFSET", "NAME",
                              "NODAL THICKNESS"):
                raise DeckError(f"{block.where()}: option {option} is not supported")
        offset = block.options.get("OFFSET", "0")
        if str(offset).upper() not in ("0", "0.", "0.0", "MIDDLE", "SMID"):
            raise DeckError(f"{block.where()}: OFFSET={offset} (shell offset) is not supported; "
                            "model the mid-surface")
        line = block.line
        if "NODAL THICKNESS" in block.options:
            thickness = None                  # from *NODAL THICKNESS (abaqus_model)
        elif not block.data:
            raise DeckError(f"{block.where()}: the thickness data line is missing")
        else:
            fields, _, line = block.data[0]
            thickness = parse_number(trimmed(fields)[0], block, line, "thickness")
        self.scope.sections.append((str(block.options.get("ELSET", "")),
                                    str(block.options.get("MATERIAL", "")).upper(),
                                    thickness, block.where(line)))

    def k_beam_section(self, block):
        for option in block.options:
            if option not in ("ELSET", "MATERIAL", "SECTION", "OFFSET1", "OFFSET2"):
                raise DeckError(f"{block.where()}: option {option} is not supported")
        for option in ("OFFSET1", "OFFSET2"):
            if option in block.options and parse_number(block.options[option], block,
                                                        block.line) != 0.0:
                raise DeckError(f"{block.where()}: {option}={block.options[option]} (beam "
                                "offset) is not supported; model the beam axis")
        if not all(isinstance(block.options.get(k), str) for k in ("ELSET", "MATERIAL", "SECTION")):
            raise DeckError(f"{block.where()}: needs ELSET=, MATERIAL= and SECTION=")
        if not block.data:
            raise DeckError(f"{block.where()}: the section dimensions line is missing")
        fields, _, line = block.data[0]
        dims = [parse_number(v, block, line, "dimension") for v in trimmed(fields)]
        direction = DEFAULT_DIRECTION_1
        if len(block.data) > 1:
            fields, _, dline = block.data[1]
            direction = tuple(([parse_number(v, block, dline, "direction")
                                for v in trimmed(fields)] + [0.0] * 3)[:3])
        self.scope.beam_sections.append((block.options["ELSET"], block.options["MATERIAL"].upper(),
                                         block.options["SECTION"].upper(), dims, direction,
                                         block.where(line)))

    def k_nodal_thickness(self, block):
        for fields, _, line in block.data:
            fields = trimmed(fields)
            if len(fields) < 2:
                raise DeckError(f"{block.where(line)}: needs a node (or node set) and a thickness")
            self.scope.nodal_thickness.append(
                (fields[0], parse_number(fields[1], block, line, "thickness"), block.where(line)))

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
                      else "*ELASTIC (temperature table)", where=f"{block.file}:{block.line}")
            return
        fields, _, line = block.data[0]
        values = [parse_number(v, block, line) for v in trimmed(fields)[:2]]
        self.material["E"], self.material["nu"] = values[0], values[1]

    def k_density(self, block):
        if self.material is None:
            raise DeckError(f"{block.where()}: *DENSITY outside a *MATERIAL")
        if len(block.data) != 1:
            raise DeckError(f"{block.where()}: a temperature table of densities is not supported "
                            "(one density line)")
        fields, _, line = block.data[0]
        self.material["rho"] = parse_number(trimmed(fields)[0], block, line, "density")

    def k_spring(self, block):
        elset = block.options.get("ELSET")
        if not isinstance(elset, str):
            raise DeckError(f"{block.where()}: needs ELSET=<springs>")
        if "ORIENTATION" in block.options or "NONLINEAR" in block.options:
            raise DeckError(f"{block.where()}: ORIENTATION/NONLINEAR springs are not supported")
        if len(block.data) < 2:
            raise DeckError(f"{block.where()}: needs a DOF line and a stiffness line")
        (dofs, _, line), (values, _, kline) = block.data[0], block.data[1]
        dofs = [parse_label(v, block, line) for v in trimmed(dofs)]
        k = parse_number(trimmed(values)[0], block, kline, "stiffness")
        self.scope.springs.append((elset.upper(), dofs, k, block.where(line)))

    def k_mass(self, block):
        elset = block.options.get("ELSET")
        if not isinstance(elset, str) or not block.data:
            raise DeckError(f"{block.where()}: needs ELSET=<mass elements> and a mass line")
        fields, _, line = block.data[0]
        self.scope.masses.append((elset.upper(), parse_number(trimmed(fields)[0], block, line, "mass"),
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
                ([parse_number(v, block, line) for v in trimmed(fields)] + [0.0] * 3)[:3])
        if len(block.data) >= 2:
            fields, _, line = block.data[1]
            values = [parse_number(v, block, line) for v in trimmed(fields)]
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
            fields = trimmed(fields)
            if len(fields) >= 2 and fields[1].upper() in _BOUNDARY_TYPES:
                components = _BOUNDARY_TYPES[fields[1].upper()]
            else:
                first = parse_label(fields[1], block, line)
                last = parse_label(fields[2], block, line) if len(fields) > 2 and fields[2] else first
                if len(fields) > 3 and fields[3] and parse_number(fields[3], block, line) != 0.0:
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
            fields = trimmed(fields)
            dof = parse_label(fields[1], block, line)
            if not 1 <= dof <= 6:
                raise DeckError(f"{block.where(line)}: DOF {dof} outside 1..6")
            self.cloads.append((name, fields[0], dof, parse_number(fields[2], block, line, "load"),
                                block.where(line)))


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
        return build_deck_model(reader)
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
        values += [(where, "thickness", float(thickness)) for _, _, thickness, where in scope.sections
                   if thickness is not None]
    return values

