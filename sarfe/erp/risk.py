r"""Linear squeak-and-rattle risk baseline — the industry's method, for comparison with the HBM result.

The structure is solved *linearly* (contacts removed) at the excitation frequency and the relative
motion across each contact pair is compared with the nominal gap. With the first-harmonic
coefficients of the relative normal displacement w (positive = closing) and of the two tangential
relative displacements q = (q1, q2) (sarfe Fourier convention, rows [0, c, s] of ``(2H+1, …)``):

    a_n   = √(w_1c² + w_1s²)                           normal amplitude [m]
    d     = g − t − a_n                                "dynamic tolerance" [m]; rattle risk if d < 0
    q(θ)  = q_c cos θ + q_s sin θ                      an ellipse in the tangent plane,
            semi-axes = singular values σ1 ≥ σ2 of Q = [[q1c, q1s], [q2c, q2s]],
            σ1² = ½ (‖Q‖_F² + √(‖Q‖_F⁴ − 4 det(Q)²))
    s_pp  = 2 σ1                                       peak-to-peak tangential relative motion [m]
                                                       (squeak indicator; = 2|q_1| for one direction)

g is the nominal gap [m] and t the tolerance [m] (worst-case manufacturing/assembly loss of gap);
only harmonic 1 is used (a linear response has no other). Contacts without a normal (or tangent)
row get NaN for the quantities they lack.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

__all__ = ["ContactRisk", "linear_risk", "linear_risk_from_contacts", "tangential_peak_to_peak"]


@dataclass(frozen=True)
class ContactRisk:
    """Linear risk indicators of one contact at one frequency (module docstring); SI units."""

    name: str
    frequency_hz: float               # [Hz] (NaN if not given)
    gap_m: float                      # g [m]
    tolerance_m: float                # t [m]
    normal_amplitude_m: float         # a_n [m] (NaN without a normal row)
    dynamic_tolerance_m: float        # d = g − t − a_n [m]
    rattle_risk: bool                 # d < 0
    tangential_peak_to_peak_m: float  # s_pp [m] (NaN without tangent rows)

    def as_dict(self) -> dict:
        return asdict(self)


def tangential_peak_to_peak(tangent) -> np.ndarray:
    """s_pp = 2 σ_max of the tangential ellipse; ``tangent`` (2H+1, ..., 2) [m] → (...,) [m].

    The last axis holds the two tangent directions (pass zeros, not NaN, for a missing second one).
    """
    T = np.asarray(tangent, dtype=float)
    if T.shape[0] < 3 or T.shape[-1] != 2:
        raise ValueError(f"tangent must be (2H+1 >= 3, ..., 2), got {T.shape}")
    q1c, q2c = T[1, ..., 0], T[1, ..., 1]
    q1s, q2s = T[2, ..., 0], T[2, ..., 1]
    frob2 = q1c**2 + q1s**2 + q2c**2 + q2s**2
    det = q1c * q2s - q1s * q2c
    disc = np.sqrt(np.maximum(frob2**2 - 4.0 * det**2, 0.0))
    return 2.0 * np.sqrt(0.5 * (frob2 + disc))


def linear_risk(normal, tangent, gap, tolerance, names=None, frequency_hz=float("nan")
                ) -> list[ContactRisk]:
    """Linear risk per contact at one frequency.

    Parameters
    ----------
    normal : (2H+1, n_c) [m]  harmonics of the relative normal displacement w (row 0 ignored);
        NaN columns for contacts without a normal DOF.
    tangent : (2H+1, n_c, 2) [m]  harmonics of the tangential relative displacements (q1, q2);
        NaN columns for contacts without tangent DOFs, zeros for a missing second direction.
    gap : (n_c,) or scalar [m]  nominal gap g.
    tolerance : (n_c,) or scalar [m]  tolerance t (loss of gap).
    names : contact names (default ``contact_<i>``).
    frequency_hz : [Hz]  the excitation frequency, recorded in the result.

    Returns a list of :class:`ContactRisk` (one per contact, input order).
    """
    W = np.asarray(normal, dtype=float)
    T = np.asarray(tangent, dtype=float)
    if W.ndim != 2 or W.shape[0] < 3:
        raise ValueError(f"normal must be (2H+1 >= 3, n_c), got {W.shape}")
    n_c = W.shape[1]
    if T.shape != (W.shape[0], n_c, 2):
        raise ValueError(f"tangent must be {(W.shape[0], n_c, 2)}, got {T.shape}")
    gap = np.broadcast_to(np.asarray(gap, dtype=float), (n_c,))
    tolerance = np.broadcast_to(np.asarray(tolerance, dtype=float), (n_c,))
    amplitude = np.hypot(W[1], W[2])
    dynamic = gap - tolerance - amplitude
    s_pp = tangential_peak_to_peak(T)
    names = list(names) if names is not None else [f"contact_{i}" for i in range(n_c)]
    if len(names) != n_c:
        raise ValueError(f"names has {len(names)} entries for {n_c} contacts")
    return [
        ContactRisk(str(names[c]), float(frequency_hz), float(gap[c]), float(tolerance[c]),
                    float(amplitude[c]), float(dynamic[c]), bool(dynamic[c] < 0), float(s_pp[c]))
        for c in range(n_c)
    ]


def linear_risk_from_contacts(contacts, contact_displacement, tolerance, frequency_hz=float("nan")
                              ) -> list[ContactRisk]:
    """:func:`linear_risk` from a :class:`sarfe.hbm.contacts.ContactSet` and r̃ = G ũ.

    contact_displacement : (2H+1, n_rows) [m]  harmonics of the contact rows of a linear response
    (e.g. ``HarmonicSolution.contact_displacement`` of a solve without contacts, or G ũ_lin).
    tolerance : (n_c,) or scalar [m].
    """
    R = np.asarray(contact_displacement, dtype=float)
    n_c = contacts.count
    padded = np.concatenate([R, np.full((R.shape[0], 1), np.nan), np.zeros((R.shape[0], 1))], axis=1)
    nan_col, zero_col = R.shape[1], R.shape[1] + 1
    normal_idx = np.where(contacts.normal_row >= 0, contacts.normal_row, nan_col)
    t_rows = np.asarray(contacts.tangent_rows).reshape(n_c, 2)
    t_idx = np.where(t_rows >= 0, t_rows, zero_col)
    t_idx[:, 0] = np.where(t_rows[:, 0] >= 0, t_rows[:, 0], nan_col)
    return linear_risk(padded[:, normal_idx], padded[:, t_idx], contacts.gap, tolerance,
                       names=contacts.names, frequency_hz=frequency_hz)
