"""Utilities below every layer: lazy package exports, the process pool, progress lines."""
