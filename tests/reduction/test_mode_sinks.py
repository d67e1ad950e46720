"""Where spectrum slicing keeps found eigenvectors: in memory, or waiting in a file on disk.

A sink must give back exactly the columns it was given (a file holds float64 as written: no
rounding), only the kept ones, in the order kept, and leave no file behind.
"""
import os

import numpy as np
import pytest

from sarfe.reduction.mode_sinks import FileSink, MemorySink

ROWS = 1000


def blocks_of(rng):
    """Three column blocks as slicing produces them: C-order Ritz vectors, a Fortran one, none."""
    return [rng.standard_normal((ROWS, 7)), np.asfortranarray(rng.standard_normal((ROWS, 40))),
            np.zeros((ROWS, 0))]


@pytest.mark.parametrize("kind", ["memory", "file"])
def test_kept_columns_come_back_exactly_in_order(kind, tmp_path):
    """Put three blocks, keep the second, a prefix of the first (pending values a run used in
    part) and the empty one: the blocks read back are those columns, bit for bit, in that order;
    the file is gone once they are mapped."""
    rng = np.random.default_rng(3)
    first, second, empty = blocks_of(rng)
    sink = MemorySink() if kind == "memory" else FileSink(ROWS, directory=tmp_path)
    handles = [sink.put(block) for block in (first, second, empty)]
    sink.keep(np.arange(40.0), handles[1])
    sink.keep(np.arange(40.0, 45.0), sink.prefix(handles[0], 5))
    sink.keep(np.zeros(0), handles[2])
    expected = np.hstack([second, first[:, :5]])
    np.testing.assert_array_equal(sink.values(), np.arange(45.0))
    blocks = sink.blocks()
    assert sum(block.shape[1] for block in blocks) == 45
    np.testing.assert_array_equal(np.hstack(blocks), expected)
    if kind == "file":
        assert max(block.shape[1] for block in blocks) <= 64      # mapped block by block
        assert not os.path.exists(sink.path) and not list(tmp_path.iterdir())


def test_another_process_maps_the_kept_columns(tmp_path):
    """The forked worker writes to the file, this process maps it from the kept ranges alone."""
    rng = np.random.default_rng(4)
    writer = FileSink(ROWS, directory=tmp_path)
    vectors = rng.standard_normal((ROWS, 100))
    unused = writer.put(vectors[:, :30])                  # pending vectors never certified
    kept = writer.put(vectors[:, 30:])
    assert len(unused) == 30 and kept == range(30, 100)
    reader = FileSink(ROWS, path=writer.path)
    np.testing.assert_array_equal(np.hstack(reader.blocks([kept], width=16)), vectors[:, 30:])
    assert not list(tmp_path.iterdir())


def test_read_returns_a_parked_array(tmp_path):
    """Arrays parked whole (Craig–Bampton's Ψ and statics) read back unchanged; none with no
    columns reads as (n, 0)."""
    rng = np.random.default_rng(5)
    sink = FileSink(ROWS, directory=tmp_path)
    psi = rng.standard_normal((ROWS, 12))
    handles = sink.put(psi), sink.put(np.zeros((ROWS, 0)))
    np.testing.assert_array_equal(sink.read(handles[0]), psi)
    assert sink.read(handles[1]).shape == (ROWS, 0)
    sink.remove()
    assert not list(tmp_path.iterdir())
