"""What the user asks for: an accuracy target (``fast | balanced | fine | {erp_db: x} |
{amplitude_rel: x}``) as a relative first-harmonic contact amplitude error and/or an ERP level
error [dB].

An ERP level error of ε_dB corresponds to a relative amplitude error 10^{ε_dB/20} − 1 (0.5 dB ≈
5.9 %); :meth:`AccuracyTarget.amplitude_budget` is the stricter of both.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

PRESETS = {   # ERP of impacts converges slowly in H (ERP ∝ Σ (kω)² |w_k|²): dB targets are looser
    "fast": {"amplitude_rel": 5e-2, "erp_db": 2.0},
    "balanced": {"amplitude_rel": 1e-2, "erp_db": 0.5},
    "fine": {"amplitude_rel": 1e-3, "erp_db": 0.1},
}


@dataclass(frozen=True)
class AccuracyTarget:
    """What the user asks for: relative first-harmonic amplitude error and/or ERP level error [dB]."""

    amplitude_rel: float | None = None
    erp_db: float | None = None
    name: str = ""

    def amplitude_budget(self) -> float:
        """Relative amplitude error allowed (the stricter of both targets)."""
        values = []
        if self.amplitude_rel is not None:
            values.append(self.amplitude_rel)
        if self.erp_db is not None:
            values.append(10 ** (self.erp_db / 20.0) - 1.0)
        return min(values) if values else PRESETS["balanced"]["amplitude_rel"]

    def met_by(self, amplitude_rel: float, erp_db: float, share: float = 1.0) -> bool:
        """The errors (relative amplitude, level [dB]) are within ``share`` of the target."""
        ok = True
        if self.amplitude_rel is not None:
            ok &= bool(amplitude_rel <= share * self.amplitude_rel)
        if self.erp_db is not None:
            ok &= bool(abs(erp_db) <= share * self.erp_db)
        if self.amplitude_rel is None and self.erp_db is None:
            ok &= bool(amplitude_rel <= share * self.amplitude_budget())
        return ok


def parse_accuracy(value) -> AccuracyTarget:
    """'fast' | 'balanced' | 'fine' | {'erp_db': x} | {'amplitude_rel': x} | 'erp_db=0.5' → target.

    Raises ValueError naming the problem.
    """
    if isinstance(value, AccuracyTarget):
        return value
    if isinstance(value, str):
        text = value.strip()
        if text in PRESETS:
            return AccuracyTarget(**PRESETS[text], name=text)
        if "=" in text:
            key, _, number = text.partition("=")
            return parse_accuracy({key.strip(): float(number)})
        raise ValueError(f"accuracy must be one of {sorted(PRESETS)} or {{erp_db: x}} / "
                         f"{{amplitude_rel: x}}, got {value!r}")
    if isinstance(value, dict):
        unknown = set(value) - {"erp_db", "amplitude_rel"}
        if unknown or not value:
            raise ValueError(f"accuracy accepts the keys erp_db and amplitude_rel, got {sorted(value)}")
        for key, number in value.items():
            if not (isinstance(number, (int, float)) and math.isfinite(number) and number > 0):
                raise ValueError(f"accuracy.{key} must be a number > 0, got {number!r}")
        name = ", ".join(f"{k}={v:g}" for k, v in value.items())
        return AccuracyTarget(value.get("amplitude_rel"), value.get("erp_db"), name)
    raise ValueError(f"accuracy: unsupported value {value!r}")


__all__ = ["PRESETS", "AccuracyTarget", "parse_accuracy"]
