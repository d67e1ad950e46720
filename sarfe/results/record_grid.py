"""The time grid of response.h5's contact histories (issue 30 item 3), without h5py: the
pipeline's cost check (``sarfe validate``) sizes the file from it, and a CLI start must not load
the HDF5 library. The rule and what a user loses: :mod:`sarfe.results.response_h5`.

    record_samples(H, N, N_case) -> N_rec     stored samples per period, ≤ N
    record_histories(force_time, state, N_rec) -> (decimated force, per-bin peak force,
                                                   per-bin highest state)
"""
from __future__ import annotations

import math

import numpy as np

RECORD_SAMPLES_PER_HARMONIC = 16   # N_rec = max(RECORD_MIN_SAMPLES, 2^⌈log₂ 16 H⌉), ≤ N
RECORD_MIN_SAMPLES = 64
# gzip (level 4, shuffled) only from this many entries: below it a dataset is stored whole
# (contiguous), its chunk index and filter calls costing more than the bytes saved
COMPRESS_MIN_ENTRIES = 65536


def record_samples(harmonics: int, samples_per_period: int, base_samples: int | None = None
                   ) -> int:
    """N_rec, the time samples per period stored (module docstring): N / s with s the smallest
    decimation dividing N such that N / s ≤ max(RECORD_MIN_SAMPLES, 2^⌈log₂ 16 H⌉,
    ``base_samples``) (the case's solver.samples_per_period, before a sweep raised N: a run at
    its own N stores all of it; a power-of-two N gives that bound exactly)."""
    N = int(samples_per_period)
    target = max(RECORD_MIN_SAMPLES, int(base_samples or 0),
                 2 ** math.ceil(math.log2(RECORD_SAMPLES_PER_HARMONIC * max(int(harmonics), 1))))
    step = max(1, -(-N // target))
    while N % step:
        step += 1
    return N // step


def record_histories(force_time, state, record: int) -> tuple:
    """The stored time histories of one point at N_rec = ``record`` samples per period, from
    the solve's λ(θ_j) ``force_time`` (N, n_rows) [N] and ``state`` (N, n_c) (either None):
    (decimated force (N_rec, n_rows), per-bin force of largest magnitude (N_rec, n_rows),
    per-bin highest state (N_rec, n_c) int8); bin j holds AFT samples j s … j s + s − 1,
    s = N / N_rec."""
    out = [None, None, None]
    if force_time is not None:
        F = np.asarray(force_time, dtype=float)
        bins = F.reshape(record, F.shape[0] // record, *F.shape[1:])
        out[0] = bins[:, 0]
        where = np.argmax(np.abs(bins), axis=1)[:, None]
        out[1] = np.take_along_axis(bins, where, axis=1)[:, 0]
    if state is not None:
        S = np.asarray(state, dtype=np.int8)
        out[2] = S.reshape(record, S.shape[0] // record, *S.shape[1:]).max(axis=1)
    return tuple(out)


__all__ = ["record_samples", "record_histories", "RECORD_SAMPLES_PER_HARMONIC",
           "RECORD_MIN_SAMPLES", "COMPRESS_MIN_ENTRIES"]
