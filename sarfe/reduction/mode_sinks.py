"""Where spectrum slicing keeps the eigenvectors it has found until Craig–Bampton copies them into
T's interior rows: in memory, or in a temporary file on disk while two processes slice.

A sink stores column blocks Φ_j (n, k_j) float64 as they are found: ``put(vectors)`` returns a
handle (the array itself, or the block's columns in the file), ``prefix(handle, k)`` the handle of
its first k columns, ``keep(values, handle)`` marks a block certified (gap by gap, ascending in
λ; a put block may never be kept: a run's pending values its successor did not need).
``values()`` → the kept λ (ascending, concatenated); ``blocks()`` → the kept vectors as column
blocks in the same order, each (n, ≤ ``width``): arrays, or read-only maps of the file.

Two slicing processes each hold a Krylov store and a factor of K − σM at once; the vectors they
have certified (up to 0.45 GB each on the door trim at 5 mm) are not needed again until the end.
In :class:`FileSink` they wait on disk: written pages are page cache, which the kernel writes
back and may evict — not memory of either process (a tmpfs directory, such as /dev/shm or a
memory-backed TMPDIR, would make them memory again). The file is removed once mapped; its maps
end with the last block copied. :func:`park_arrays` puts other arrays (Ψ, the residual loads and
their statics) in such a file for the same span.
"""
from __future__ import annotations

import os
import tempfile
import weakref

import numpy as np


class MemorySink:
    """Vectors kept in memory, blocks as found (one process: nothing waits on disk)."""

    def __init__(self):
        self._values, self._blocks = [], []

    def put(self, vectors):
        return vectors

    @staticmethod
    def prefix(handle, count):
        return handle if count == handle.shape[1] else handle[:, :count]

    @staticmethod
    def count(handle):
        return handle.shape[1]

    def keep(self, values, handle):
        self._values.append(np.asarray(values, dtype=float))
        self._blocks.append(handle)

    def values(self):
        return np.concatenate(self._values) if self._values else np.zeros(0)

    def blocks(self):
        blocks, self._blocks = self._blocks, []
        return blocks

    def remove(self):
        self._blocks = []


class FileSink:
    """Vectors in a temporary file, column after column (float64, column-major); handles are
    ``range`` s of file columns. ``path``: an existing file to go on with (the forked worker's
    sink, which this process maps after the worker has written it) — else a new one in
    ``directory`` (None: the system's temporary directory)."""

    def __init__(self, rows, path=None, directory=None):
        if path is None:
            handle, path = tempfile.mkstemp(prefix="sarfe-modes-", suffix=".f64", dir=directory)
            os.close(handle)
        self.rows, self.path = int(rows), path
        self._values, self._kept = [], []

    def _columns(self):
        return os.path.getsize(self.path) // (8 * self.rows)

    def put(self, vectors, width=16):
        """Append (n, k) → range of its columns in the file (written ``width`` columns at a time:
        no column-major copy of the whole block)."""
        start = self._columns()
        with open(self.path, "ab") as out:
            for first in range(0, vectors.shape[1], width):
                np.asfortranarray(vectors[:, first:first + width], dtype=float).T.tofile(out)
        return range(start, start + vectors.shape[1])

    @staticmethod
    def prefix(handle, count):
        return handle[:count]

    @staticmethod
    def count(handle):
        return len(handle)

    def keep(self, values, handle):
        self._values.append(np.asarray(values, dtype=float))
        self._kept.append(handle)

    def values(self):
        return np.concatenate(self._values) if self._values else np.zeros(0)

    def kept(self):
        """The kept column ranges (picklable: the worker sends them to this process)."""
        return list(self._kept)

    def read(self, handle):
        """The columns ``handle`` (a range) mapped from the file, (n, k) read-only."""
        if len(handle) == 0:
            return np.zeros((self.rows, 0))
        return np.memmap(self.path, dtype=float, mode="r", order="F",
                         offset=8 * self.rows * handle.start, shape=(self.rows, len(handle)))

    def blocks(self, kept=None, width=64):
        """Maps of the kept columns (``kept``: ranges, default this sink's), each (n, ≤ width)
        and contiguous in the file; the file is then removed (the maps stay valid)."""
        kept = self._kept if kept is None else kept
        blocks = []
        try:
            for columns in kept:
                for first in range(columns.start, columns.stop, width):
                    count = min(width, columns.stop - first)
                    blocks.append(np.memmap(self.path, dtype=float, mode="r", order="F",
                                            offset=8 * self.rows * first,
                                            shape=(self.rows, count)))
        finally:
            self.remove()
        return blocks

    def remove(self):
        try:
            os.remove(self.path)
        except OSError:
            pass


def park_arrays(*arrays):
    """Write (n, k) arrays (or None) to a temporary :class:`FileSink` on disk and return a
    function that reads them back, in their memory order, and removes the file."""
    sink = FileSink(next(a.shape[0] for a in arrays if a is not None))
    try:
        parked = [None if a is None else (sink.put(a), "F" if np.isfortran(a) else "C")
                  for a in arrays]
    except BaseException:
        sink.remove()
        raise

    def restore():
        try:
            return [None if p is None else np.array(sink.read(p[0]), order=p[1])
                    for p in parked]
        finally:
            sink.remove()

    weakref.finalize(restore, sink.remove)      # an error on the way: the file goes too
    return restore
