r"""Tabulated force–deflection: a measured monotone curve λ_n = F(w − g), optional Jenkins friction.

    λ_n = s · F(w − g)   where w > g,    λ_n = 0 where w ≤ g

F is given as pairs (deflection δ_i [m], force F_i [N]) — in the case file (``curve``) or a CSV
file relative to it (``curve_file``, two columns, '#' comments, an optional header line) —
strictly increasing δ ≥ 0, non-decreasing F ≥ 0; a table not starting at δ = 0 gets (0, 0) in
front, and F(0) must be 0. Between the points F is piecewise linear or a monotone cubic spline
(``interpolation: linear | monotone_spline``, scipy's PchipInterpolator); beyond the last point it
continues linearly with the last slope. s = ``force_scale`` is the share of a named contact's
force carried by one node pair (1/n_p). With ``friction_coefficient`` and
``tangential_stiffness_N_m`` the contact also has a Jenkins element (:mod:`.jenkins`) with slip
limit μ λ_n, in 1 or 2 tangential directions. States: 0 open/separated, 1 closed/stick, 2 slip.

Stored per contact as the breakpoints (S,) and the polynomial of each piece (S, 4),
F = a + b t + c t² + d t³ with t = δ − δ_i (the last piece is the linear extension), so the
evaluation is vectorized over samples × contacts with a comparison count for the piece index.
"""
from __future__ import annotations

import numpy as np

from sarfe.hbm.laws import jenkins
from sarfe.hbm.laws.contract import ContactLaw, LawInputError, Linearization, NormalForce, Parameter

FRICTION = tuple(Parameter(p.name, p.key, p.unit, p.description + " (optional friction part)",
                           minimum=p.minimum, exclusive=p.exclusive, required=True, split=p.split,
                           scaled=p.scaled, tangent_part=True) for p in jenkins.PARAMETERS)
PARAMETERS = (
    Parameter("force_scale", None, "1", "share of the curve's force carried by one node pair",
              minimum=0.0, default=1.0, split=True, scaled=True),
) + FRICTION
CASE_KEYS = {
    "curve": {"type": "array", "minItems": 1,
              "items": {"type": "array", "minItems": 2, "maxItems": 2,
                        "items": {"type": "number"}}},
    "curve_file": {"type": "string", "minLength": 1},
    "interpolation": {"enum": ["linear", "monotone_spline"]},
}


def curve_table(points, interpolation="linear", key="curve"):
    """{curve_breakpoints (S,), curve_coefficients (S, 4)} of a force–deflection table
    [[δ, F], …] (see module docstring); raises LawInputError naming ``key``."""
    table = np.asarray(points, dtype=float)
    if table.ndim != 2 or table.shape[1] != 2 or not np.all(np.isfinite(table)):
        raise LawInputError(key, "must be pairs [deflection_m, force_N] of finite numbers")
    x, f = table[:, 0], table[:, 1]
    if x[0] > 0:
        x, f = np.concatenate([[0.0], x]), np.concatenate([[0.0], f])
    if x[0] < 0 or np.any(np.diff(x) <= 0):
        raise LawInputError(key, "deflections must be >= 0 and strictly increasing")
    if f[0] != 0.0:
        raise LawInputError(key, f"force at zero deflection must be 0, got {f[0]:g}")
    if np.any(np.diff(f) < 0):
        raise LawInputError(key, "forces must not decrease (a monotone curve)")
    if f[-1] <= 0.0:
        raise LawInputError(key, "all forces are 0: the curve carries no force")
    coefficients = np.zeros((x.size, 4))
    if interpolation == "monotone_spline" and x.size > 2:
        from scipy.interpolate import PchipInterpolator

        spline = PchipInterpolator(x, f)
        coefficients[:-1] = spline.c[::-1].T                  # (a, b, c, d) per piece
        last_slope = float(spline.derivative()(x[-1]))
    elif interpolation in ("linear", "monotone_spline"):
        slopes = np.diff(f) / np.diff(x)
        coefficients[:-1, 0], coefficients[:-1, 1] = f[:-1], slopes
        last_slope = float(slopes[-1])
    else:
        raise LawInputError("interpolation", "must be 'linear' or 'monotone_spline'")
    coefficients[-1, 0], coefficients[-1, 1] = f[-1], last_slope   # linear extension
    return {"curve_breakpoints": x, "curve_coefficients": coefficients}


def curve_force(p, deflection):
    """s·F(δ), s·F'(δ) over (samples × contacts) for δ = w − g > 0 (0 elsewhere)."""
    breakpoints = np.where(np.isnan(p["curve_breakpoints"]), np.inf, p["curve_breakpoints"])
    delta = np.asarray(deflection, dtype=float)
    piece = np.maximum(np.sum(breakpoints <= delta[..., None], axis=-1) - 1, 0)   # (…, n)
    contact = np.arange(delta.shape[-1])
    coefficient = p["curve_coefficients"][contact, piece]                         # (…, n, 4)
    t = delta - breakpoints[contact, piece]
    a, b, c, d = np.moveaxis(coefficient, -1, 0)
    scale = p["force_scale"]
    force = scale * (a + t * (b + t * (c + t * d)))
    slope = scale * (b + t * (2.0 * c + 3.0 * t * d))
    return force, slope


def normal(p, gap, w, wdot):
    deflection = np.asarray(w) - gap
    closed = deflection > 0.0
    force, slope = curve_force(p, np.where(closed, deflection, 0.0))
    return NormalForce(np.where(closed, force, 0.0), np.where(closed, slope, 0.0), None, closed)


def linearize(p, gap):
    """At u = 0: the tangent of the curve at δ = −g (right slope at 0) and F(−g) where g ≤ 0;
    spring = the steepest slope of the curve (the homotopy's scale) where open."""
    gap = np.asarray(gap, dtype=float)
    closed = gap <= 0
    force, slope = curve_force(p, np.where(closed, -gap, 0.0)[None])
    coefficients = np.where(np.isnan(p["curve_coefficients"]), 0.0, p["curve_coefficients"])
    steepest = p["force_scale"] * coefficients[..., 1].max(axis=-1)
    spring = np.where(closed, slope[0], steepest)
    return Linearization(spring, np.zeros_like(spring), np.where(closed, force[0], 0.0), closed)


def static_deflection(p, force):
    """δ with s·F(δ) = force [N] (bisection on the monotone curve; beyond the table the linear
    extension with the last slope, δ = δ_S + (force − s F_S) / (s F'_S)). A force the curve never
    reaches (above a plateau: last slope 0) raises ValueError — the case check
    (:func:`check_preload`) rejects such a preload_N before."""
    force = np.asarray(force, dtype=float)
    breakpoints = np.where(np.isnan(p["curve_breakpoints"]), -np.inf, p["curve_breakpoints"])
    upper = breakpoints.max(axis=-1)
    top, slope = curve_force(p, upper[None])
    beyond = force > top[0]
    if np.any(beyond & (slope[0] <= 0.0)):
        largest = float(np.max(top[0][beyond & (slope[0] <= 0.0)]))
        raise ValueError(f"a static force of {float(np.max(force[beyond])):g} N is above the "
                         f"largest force {largest:g} N of a curve that ends flat")
    upper = np.where(beyond, upper + (force - top[0]) / np.where(beyond, slope[0], 1.0), upper)
    lower = np.zeros_like(upper)
    for _ in range(80):
        middle = 0.5 * (lower + upper)
        above = curve_force(p, middle[None])[0][0] >= force
        upper, lower = np.where(above, middle, upper), np.where(above, lower, middle)
    return upper


def check_preload(table, preload_N):
    """A preload P [N] the curve cannot carry: P above the largest force F_S of a curve whose
    linear extension is flat (last slope 0) → LawInputError naming ``preload_N``. A rising last
    piece carries any P (the docs' linear extension)."""
    top = float(table["curve_coefficients"][-1, 0])
    last_slope = float(table["curve_coefficients"][-1, 1])
    if preload_N > top and last_slope <= 0.0:
        raise LawInputError("preload_N", f"{preload_N:g} N is above the curve's largest force "
                            f"{top:g} N (the curve ends flat and cannot carry it)")


def prepare(contact, resolve):
    """The curve of a case contact: ``curve`` pairs or a ``curve_file`` CSV (relative to the case)."""
    given = [key for key in ("curve", "curve_file") if key in contact]
    if len(given) != 1:
        raise LawInputError("curve", "give exactly one of curve or curve_file")
    interpolation = contact.get("interpolation", "linear")
    if "curve" in contact:
        table = curve_table(contact["curve"], interpolation)
    else:
        table = curve_table(read_curve_file(resolve(contact["curve_file"])), interpolation,
                            "curve_file")
    if isinstance(contact.get("preload_N"), (int, float)):
        check_preload(table, float(contact["preload_N"]))
    return table


def read_curve_file(path):
    """(S, 2) pairs of a curve CSV: two comma-separated columns, '#' comment lines anywhere and
    at most one header line (the first line that is not a comment) → LawInputError naming
    ``curve_file``."""
    try:
        text = path.read_text(errors="replace")
    except OSError:
        raise LawInputError("curve_file", f"file not found: {path}") from None
    lines = [(number, line.split("#", 1)[0].strip())
             for number, line in enumerate(text.splitlines(), start=1)]
    lines = [(number, line) for number, line in lines if line]
    rows = []
    for position, (number, line) in enumerate(lines):
        fields = [field.strip() for field in line.split(",")]
        try:
            values = [float(field) for field in fields]
        except ValueError:
            if position == 0:
                continue                    # the header line
            raise LawInputError("curve_file", f"{path.name} line {number}: not two numbers "
                                f"({line!r})") from None
        if len(values) != 2:
            raise LawInputError("curve_file", f"{path.name} line {number}: {len(values)} "
                                "columns, expected 2 (deflection_m, force_N)")
        rows.append(values)
    if not rows:
        raise LawInputError("curve_file", f"{path.name}: no data rows (two columns "
                            "deflection_m, force_N)")
    return np.array(rows, dtype=float)


def check(p):
    if "curve_breakpoints" not in p or np.any(np.all(np.isnan(p["curve_breakpoints"]), axis=-1)):
        raise ValueError("a tabulated contact needs a curve (parameters from curve_table)")


LAW = ContactLaw(
    name="tabulated",
    summary="measured monotone force–deflection curve λ_n = F(w − g), optional Jenkins friction",
    parameters=PARAMETERS, normal=normal, linearize=linearize,
    static_deflection=static_deflection, tangent=jenkins, tangent_dofs="optional",
    case_keys=CASE_KEYS, prepare=prepare, check=check, states=jenkins.STATES,
)
