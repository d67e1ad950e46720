"""`PanelMesh`: a triangle shell mesh (optionally with tetrahedra) and its named groups.

Plain data, SI units (points in metres).  Group naming convention (docs/design.md):

* ``clip_*`` / ``clamp_*``  fixed supports (node groups)
* ``contact_<pair>_a`` / ``contact_<pair>_b``  paired node sets, same length, a[i] faces b[i]
* ``excite_*``  excitation points (node groups)
* ``skin``  radiating surface (element group, and its nodes as node group)
* ``part_<name>``  element groups carrying their own thickness / material
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


class GroupError(KeyError):
    """A named node / element group is missing; the message lists the available names."""

    def __str__(self) -> str:  # KeyError would print the repr with quotes
        return str(self.args[0]) if self.args else ""


def _index_array(values, name: str) -> np.ndarray:
    array = np.array(values, dtype=np.int64).reshape(-1)
    if array.size and array.min() < 0:
        raise ValueError(f"group {name!r} has negative indices")
    return array


@dataclass(frozen=True)
class PanelMesh:
    """Shell mesh of one or several panel parts.

    points        (n_nodes, 3) float   node coordinates [m]
    triangles     (n_tri, 3) int       node indices of the linear shell triangles
    node_groups   {name: (k,) int}     node indices (clips, clamps, contact nodes, excitation, ...)
    element_groups {name: (m,) int}    triangle indices (parts, skin)
    tetrahedra    (n_tet, 4|10) int or None   optional solid elements
    """

    points: np.ndarray
    triangles: np.ndarray
    node_groups: dict = field(default_factory=dict)
    element_groups: dict = field(default_factory=dict)
    tetrahedra: np.ndarray | None = None

    def __post_init__(self):
        points = np.array(self.points, dtype=np.float64)  # own copy: frozen and read-only
        if points.ndim != 2 or points.shape[1] != 3:
            raise ValueError(f"points must have shape (n, 3), got {points.shape}")
        triangles = np.array(self.triangles, dtype=np.int64).reshape(-1, 3)
        n = len(points)
        if triangles.size and (triangles.min() < 0 or triangles.max() >= n):
            raise ValueError("triangles reference nodes outside points")
        tets = self.tetrahedra
        if tets is not None:
            tets = np.array(tets, dtype=np.int64)
            if tets.ndim != 2 or tets.shape[1] not in (4, 10):
                raise ValueError(f"tetrahedra must have shape (n, 4|10), got {tets.shape}")
            if tets.size and (tets.min() < 0 or tets.max() >= n):
                raise ValueError("tetrahedra reference nodes outside points")
        node_groups = {str(k): _index_array(v, k) for k, v in self.node_groups.items()}
        for name, idx in node_groups.items():
            if idx.size and idx.max() >= n:
                raise ValueError(f"node group {name!r} references nodes outside points")
        element_groups = {str(k): _index_array(v, k) for k, v in self.element_groups.items()}
        for name, idx in element_groups.items():
            if idx.size and idx.max() >= len(triangles):
                raise ValueError(f"element group {name!r} references triangles outside the mesh")
        for arr in [points, triangles, tets, *node_groups.values(), *element_groups.values()]:
            if arr is not None:
                arr.setflags(write=False)
        object.__setattr__(self, "points", points)
        object.__setattr__(self, "triangles", triangles)
        object.__setattr__(self, "tetrahedra", tets)
        object.__setattr__(self, "node_groups", node_groups)
        object.__setattr__(self, "element_groups", element_groups)

    @property
    def n_nodes(self) -> int:
        return len(self.points)

    @property
    def n_triangles(self) -> int:
        return len(self.triangles)

    def node_group(self, name: str) -> np.ndarray:
        """Node indices of group `name`; `GroupError` (a KeyError) lists the available names."""
        try:
            return self.node_groups[name]
        except KeyError:
            raise GroupError(
                f"no node group {name!r}; available: {', '.join(sorted(self.node_groups)) or 'none'}"
            ) from None

    def element_group(self, name: str) -> np.ndarray:
        """Triangle indices of group `name`; `GroupError` (a KeyError) lists the available names."""
        try:
            return self.element_groups[name]
        except KeyError:
            raise GroupError(
                f"no element group {name!r}; available: "
                f"{', '.join(sorted(self.element_groups)) or 'none'}"
            ) from None

    def group_names(self, prefix: str = "") -> list[str]:
        """Sorted names of node and element groups starting with `prefix`."""
        names = set(self.node_groups) | set(self.element_groups)
        return sorted(n for n in names if n.startswith(prefix))

    def part_names(self) -> list[str]:
        """Names `<name>` of the `part_<name>` element groups."""
        return sorted(n[5:] for n in self.element_groups if n.startswith("part_"))

    def contact_pairs(self) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        """{pair: (a_nodes, b_nodes)} for every `contact_<pair>_a` / `contact_<pair>_b` couple."""
        pairs = {}
        for name in self.node_groups:
            if name.startswith("contact_") and name.endswith("_a"):
                pair = name[len("contact_"):-2]
                other = f"contact_{pair}_b"
                if other not in self.node_groups:
                    raise GroupError(f"contact group {name!r} has no partner {other!r}")
                a, b = self.node_groups[name], self.node_groups[other]
                if len(a) != len(b):
                    raise ValueError(f"contact pair {pair!r}: {len(a)} a-nodes vs {len(b)} b-nodes")
                pairs[pair] = (a, b)
        return dict(sorted(pairs.items()))

    def subset(self, triangle_indices) -> "PanelMesh":
        """Mesh of the given triangles only: unused nodes dropped, indices and groups remapped.

        Node groups keep only nodes that survive; element groups only surviving triangles.
        Tetrahedra are dropped.
        """
        keep = np.unique(np.asarray(triangle_indices, dtype=np.int64))
        triangles = self.triangles[keep]
        used = np.unique(triangles)
        node_map = np.full(self.n_nodes, -1, dtype=np.int64)
        node_map[used] = np.arange(len(used))
        tri_map = np.full(self.n_triangles, -1, dtype=np.int64)
        tri_map[keep] = np.arange(len(keep))
        node_groups = {}
        for name, idx in self.node_groups.items():
            mapped = node_map[idx]
            node_groups[name] = mapped[mapped >= 0]
        element_groups = {}
        for name, idx in self.element_groups.items():
            mapped = tri_map[idx]
            element_groups[name] = mapped[mapped >= 0]
        return PanelMesh(self.points[used], node_map[triangles], node_groups, element_groups)

    def part(self, name: str) -> "PanelMesh":
        """`subset` of the element group `part_<name>` (or `name` if it already starts with part_)."""
        group = name if name.startswith("part_") else f"part_{name}"
        return self.subset(self.element_group(group))

    def scaled(self, factor: float) -> "PanelMesh":
        """Same mesh with coordinates multiplied by `factor` (e.g. 1e-3 for mm → m)."""
        return PanelMesh(self.points * factor, self.triangles, self.node_groups,
                         self.element_groups, self.tetrahedra)

    def __repr__(self) -> str:
        tets = "" if self.tetrahedra is None else f", {len(self.tetrahedra)} tetrahedra"
        return (f"PanelMesh({self.n_nodes} nodes, {self.n_triangles} triangles{tets}, "
                f"node groups {sorted(self.node_groups)}, element groups {sorted(self.element_groups)})")
