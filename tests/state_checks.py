"""Comparisons of contact-state arrays robust to round-off (shared by the tests)."""
import numpy as np


def assert_states_equal_away_from_ties(a, b):
    """Contact states (samples, contacts) agree except at samples next to a state change.

    A sample where stick and slip (or open and closed) meet is decided by a comparison such as
    ``|trial force| > μ N0``, a tie up to round-off (±1e-14 μ N0, depending on the BLAS kernel);
    only those may differ, and at most one sample per change.
    """
    a, b = np.asarray(a), np.asarray(b)
    assert a.shape == b.shape

    def near_change(s):     # sample j where s changes between j-1, j or j, j+1 (periodic)
        change = s != np.roll(s, 1, axis=0)
        return change | np.roll(change, -1, axis=0)

    differ = a != b
    assert not np.any(differ & ~(near_change(a) | near_change(b))), np.argwhere(differ)
    changes = np.count_nonzero(a != np.roll(a, 1, axis=0), axis=0)
    assert np.all(np.count_nonzero(differ, axis=0) <= np.maximum(changes, 1))
