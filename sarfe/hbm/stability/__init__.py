"""Stability of periodic solutions: Hill's method, contact-row counts, checks."""
