r"""Beam cross-sections by shape (Nastran PBARL / PBEAML TYPE and DIMi) → A, I1, I2, I12, J.

The element axes are those of the Nastran beam library: y_elem "up" in the library's figures
(the height dimension), z_elem across (the width); I1 = ∫ y² dA (bending in plane 1),
I2 = ∫ z² dA, I12 = ∫ y z dA = 0 for these doubly or singly symmetric shapes, all about the
centroid; lengths in the deck's unit, A [L²], I and J [L⁴].

======  ==========================  ==============================================================
TYPE    DIM1 … DIMn                 closed form
======  ==========================  ==============================================================
ROD     r                           A = π r², I1 = I2 = π r⁴/4, J = π r⁴/2
TUBE    r_o, r_i                    A = π (r_o² − r_i²), I1 = I2 = π (r_o⁴ − r_i⁴)/4, J = 2 I1
TUBE2   r_o, t                      TUBE with r_i = r_o − t
BAR     w (z), h (y)                A = w h, I1 = w h³/12, I2 = h w³/12,
                                    J = a b³ (1/3 − 0.21 (b/a)(1 − b⁴/(12 a⁴))), a ≥ b the sides
BOX     w, h, t_1 (top/bottom), t_2 A = w h − w_i h_i (w_i = w − 2 t_2, h_i = h − 2 t_1),
        (sides)                     I1 = (w h³ − w_i h_i³)/12, I2 = (h w³ − h_i w_i³)/12,
                                    J = 2 t_1 t_2 (w − t_2)² (h − t_1)² / (w t_2 + h t_1 − t_1² − t_2²)
                                    (Bredt, wall mid-lines)
I       h, a (bottom flange), b     A = a t_a + b t_b + h_w t_w (h_w = h − t_a − t_b), I1 by the
        (top flange), t_w, t_a, t_b parallel axes about the centroid, I2 = (t_a a³ + t_b b³ + h_w t_w³)/12,
                                    J = (a t_a³ + b t_b³ + h_w t_w³)/3 (thin open walls)
======  ==========================  ==============================================================

Other library shapes (CHAN, T, L, Z, HAT, CROSS, H, HEXA, …) are not modelled: :func:`section`
raises ``ValueError`` naming the shape (the reader turns it into a one-line DeckError).
pyNastran's own PBARL/PBEAML properties are not used for these numbers: its ``J`` is missing for
PBEAML and for most shapes, and its I-section I1 takes the overall height for a flange width.
"""
from __future__ import annotations

import numpy as np

__all__ = ["SHAPES", "section"]

#: shapes with closed forms here, and their number of dimensions
SHAPES = {"ROD": 1, "TUBE": 2, "TUBE2": 2, "BAR": 2, "BOX": 4, "I": 6}


def _tube(r_o, r_i):
    i = np.pi * (r_o**4 - r_i**4) / 4.0
    return np.pi * (r_o**2 - r_i**2), i, i, 0.0, 2.0 * i


def _bar(w, h):
    a, b = max(w, h), min(w, h)
    j = a * b**3 * (1.0 / 3.0 - 0.21 * (b / a) * (1.0 - b**4 / (12.0 * a**4)))
    return w * h, w * h**3 / 12.0, h * w**3 / 12.0, 0.0, j


def _box(w, h, t1, t2):
    wi, hi = w - 2.0 * t2, h - 2.0 * t1
    if wi <= 0.0 or hi <= 0.0:
        raise ValueError(f"BOX walls thicker than the box (DIM {w:g}, {h:g}, {t1:g}, {t2:g})")
    j = 2.0 * t1 * t2 * (w - t2) ** 2 * (h - t1) ** 2 / (w * t2 + h * t1 - t1**2 - t2**2)
    return (w * h - wi * hi, (w * h**3 - wi * hi**3) / 12.0, (h * w**3 - hi * wi**3) / 12.0,
            0.0, j)


def _i(h, a, b, tw, ta, tb):
    hw = h - ta - tb
    if hw <= 0.0:
        raise ValueError(f"I flanges thicker than the height (DIM {h:g}, {ta:g}, {tb:g})")
    areas = np.array([a * ta, hw * tw, b * tb])
    heights = np.array([ta, hw, tb])
    centres = np.array([ta / 2.0, ta + hw / 2.0, h - tb / 2.0])    # from the bottom face
    area = float(areas.sum())
    yc = float(areas @ centres) / area
    i1 = float(areas @ (heights**2 / 12.0 + (centres - yc) ** 2))
    i2 = (ta * a**3 + tb * b**3 + hw * tw**3) / 12.0
    j = (a * ta**3 + b * tb**3 + hw * tw**3) / 3.0
    return area, i1, i2, 0.0, j


def section(shape: str, dims) -> tuple[float, float, float, float, float]:
    """(A, I1, I2, I12, J) of a library shape with dimensions ``dims`` (module table)."""
    shape = str(shape).upper().strip()
    if shape not in SHAPES:
        raise ValueError(f"beam library shape {shape} is not modelled (modelled: "
                         f"{', '.join(SHAPES)})")
    d = [float(x) for x in dims]
    if len(d) != SHAPES[shape] or min(d) <= 0.0:
        raise ValueError(f"{shape} needs {SHAPES[shape]} positive dimensions, got {d}")
    if shape == "ROD":
        return _tube(d[0], 0.0)
    if shape in ("TUBE", "TUBE2"):
        r_i = d[1] if shape == "TUBE" else d[0] - d[1]
        if not 0.0 <= r_i < d[0]:
            raise ValueError(f"{shape} inner radius {r_i:g} not inside the outer {d[0]:g}")
        return _tube(d[0], r_i)
    if shape == "BAR":
        return _bar(*d)
    if shape == "BOX":
        return _box(*d)
    return _i(*d)
