"""A ``.npy`` file that grows along its first axis while it is written.

The header is written with a fixed width (room for a 20-digit step count), so that after each
appended chunk it is rewritten in place with the new length: one ``pwrite`` of a few dozen
bytes, done only after the chunk's data is in the file. A process killed at any moment leaves a
file whose header counts only rows that are complete, and ``numpy.load`` reads it (the reader
ignores bytes past the counted rows).
"""

from __future__ import annotations

import os

import numpy as np

__all__ = ["GrowingNpy", "read_npy_header"]

_MAGIC = b"\x93NUMPY\x01\x00"  # format version 1.0: a 2-byte header length follows
_PREAMBLE = len(_MAGIC) + 2
_ALIGN = 64
_MAX_ROWS = 10**20 - 1  # the widest count the fixed header leaves room for


def _header_text(descr: str, shape: tuple[int, ...]) -> str:
    return f"{{'descr': {descr!r}, 'fortran_order': False, 'shape': {shape!r}, }}"


class GrowingNpy:
    """An open ``.npy`` file of rows of ``row_shape`` and ``dtype``, appended chunk by chunk.

    ``append(rows)`` writes data past the counted rows; ``commit()`` then rewrites the header
    so that it counts them. Rows appended but not committed are ignored by every reader.
    """

    def __init__(self, path: str | os.PathLike, dtype: np.dtype, row_shape: tuple[int, ...]):
        self.path = os.fspath(path)
        self.dtype = np.dtype(dtype)
        if self.dtype.hasobject:
            raise TypeError(f"dtype {self.dtype} of {self.path!r}: object arrays cannot grow")
        self.row_shape = tuple(int(n) for n in row_shape)
        self.rows = 0  # committed
        self._written = 0  # appended (committed or not)
        widest = _header_text(self.dtype.str, (_MAX_ROWS, *self.row_shape))
        total = _PREAMBLE + len(widest) + 1
        self._header_len = -(-total // _ALIGN) * _ALIGN - _PREAMBLE
        self._file = open(self.path, "wb", buffering=0)  # noqa: SIM115 - closed by close()
        self._file.write(self._header(0))

    def _header(self, rows: int) -> bytes:
        text = _header_text(self.dtype.str, (rows, *self.row_shape))
        body = text.ljust(self._header_len - 1).encode("latin1") + b"\n"
        return _MAGIC + len(body).to_bytes(2, "little") + body

    def append(self, rows: np.ndarray) -> None:
        """Write ``rows`` (k, *row_shape) after the rows already written."""
        rows = np.ascontiguousarray(rows, dtype=self.dtype)
        if rows.shape[1:] != self.row_shape:
            raise ValueError(
                f"rows of shape {rows.shape[1:]} for {self.path!r}, whose rows are {self.row_shape}"
            )
        view = memoryview(rows).cast("B")
        while view:  # a raw write may write less than asked
            view = view[self._file.write(view) :]
        self._written += rows.shape[0]

    def commit(self, fsync: bool = False) -> None:
        """Count every appended row in the header (after their data, when ``fsync``, is on
        disk)."""
        if fsync:
            os.fsync(self._file.fileno())
        os.pwrite(self._file.fileno(), self._header(self._written), 0)
        self.rows = self._written

    def close(self) -> None:
        if not self._file.closed:
            self._file.close()


def read_npy_header(path: str | os.PathLike) -> tuple[np.dtype, tuple[int, ...], int]:
    """The dtype, shape and data offset of the ``.npy`` file ``path`` (any format version)."""
    with open(path, "rb") as f:
        version = np.lib.format.read_magic(f)
        if version == (1, 0):
            shape, fortran, dtype = np.lib.format.read_array_header_1_0(f)
        else:
            shape, fortran, dtype = np.lib.format.read_array_header_2_0(f)
        if fortran:
            raise ValueError(f"{os.fspath(path)!r} is in Fortran order; recordings are C order")
        return dtype, shape, f.tell()
