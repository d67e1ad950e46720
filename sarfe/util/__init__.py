"""Utilities below every layer: lazy (lazy package exports, PEP 562), workers (an ordered map on
forked worker processes), progress (tqdm bars or one line per stage)."""
