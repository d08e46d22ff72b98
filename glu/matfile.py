"""Reading MATLAB ``.mat`` files that may be damaged or hostile, without ever crashing the process.

SciPy's MAT v5 reader trusts the file: a data element whose type code is out of range (any byte flipped
in the right place) makes its compiled reader index past a table and die with a segmentation fault, and
an element that claims more cells or fields than its matrix holds makes it read the next variable's tag
as data (the same crash). :func:`read_mat` therefore walks the whole file first, in the order SciPy will
read it, and accepts it only when every element SciPy will meet is one it reads safely:

* the 128-byte header of a MAT v5 file (``-v6`` or ``-v7``; v4 and v7.3/HDF5 files are refused);
* top-level variables that are a matrix, or a zlib-compressed matrix (inflated here with a size cap, so a
  small file cannot unpack into gigabytes);
* inside a matrix: the array flags, at most 32 non-negative dimensions, an ASCII name, then exactly the
  parts its class has — real (and imaginary) data of a numeric type whose byte count matches the
  dimensions; characters of a character type; as many sub-matrices as the cells, or fields × elements,
  declare; nothing left over.

Only then does SciPy parse the very bytes that were checked (never the file a second time). A file that
fails the walk raises :class:`MatFileError` with the offset and what was wrong there.
"""

from __future__ import annotations

import io
import math
import os
import struct
import zlib
from pathlib import Path
from typing import Any

from glu.errors import DataError

MAX_INFLATED_BYTES = 256 * 2**20
"""The largest size a compressed variable may inflate to (256 MiB; the originals' files inflate to 40 kB)."""

# MAT v5 data types (the element tags) and array classes (the matrix flags)
_NUMERIC = {1: 1, 2: 1, 3: 2, 4: 2, 5: 4, 6: 4, 7: 4, 9: 8, 12: 8, 13: 8}  # type → bytes per value
_INT8, _INT32, _UINT32, _MATRIX, _COMPRESSED, _UTF8 = 1, 5, 6, 14, 15, 16
_CHAR_TYPES = {1, 2, 4, 16, 17, 18}  # int8, uint8, uint16, utf-8, utf-16, utf-32
_CELL, _STRUCT, _OBJECT, _CHAR, _SPARSE, _FUNCTION = 1, 2, 3, 4, 5, 16
_NUMERIC_CLASSES = range(6, 16)  # double, single, int8 … uint64
_MAX_DIMS = 32
_MAX_DEPTH = 64


class MatFileError(DataError):
    """A ``.mat`` file that is not a well-formed MAT v5 file (or holds what glu does not read)."""


def read_mat(path: str | os.PathLike, **loadmat_options: Any) -> dict[str, Any]:
    """``scipy.io.loadmat(path, **loadmat_options)``, for a file that has passed the structural walk.

    Raises :class:`MatFileError` (a :class:`~glu.errors.DataError`) naming the file and the offset of the
    first problem; ``FileNotFoundError`` and other ``OSError`` as reading the file raises them.
    """
    path = Path(path)
    data = path.read_bytes()
    try:
        check_mat(data)
    except MatFileError as e:
        raise MatFileError(f"{path}: not a readable MATLAB file ({e})") from None
    from scipy.io import loadmat

    return loadmat(io.BytesIO(data), **loadmat_options)


def check_mat(data: bytes) -> None:
    """Walk a MAT v5 file's bytes as SciPy will read them; raise :class:`MatFileError` at the first flaw."""
    if len(data) < 128:
        raise MatFileError(f"not a MATLAB file: {len(data)} bytes, shorter than the 128-byte header")
    if 0 in data[:4]:
        raise MatFileError("a MATLAB v4 file (or not a MATLAB file): only MAT v5 files (-v6, -v7) are read")
    indicator = data[126:128]
    if indicator not in (b"IM", b"MI"):
        raise MatFileError(f"not a MATLAB v5 file: the endian indicator is {indicator!r}, not 'IM' or 'MI'")
    order = "<" if indicator == b"IM" else ">"
    major = data[125] if indicator == b"IM" else data[124]
    if major != 1:
        kind = "a MATLAB v7.3 (HDF5) file" if major == 2 else f"MAT version {major}"
        raise MatFileError(f"{kind}: only MAT v5 files (-v6, -v7) are read")
    pos = 128
    while pos < len(data):
        mdtype, nbytes = _full_tag(data, pos, order)
        body = pos + 8
        end = body + nbytes
        if nbytes == 0 or end > len(data):
            raise MatFileError(f"offset {pos}: a variable of {nbytes} bytes where {len(data) - body} remain")
        if mdtype == _COMPRESSED:
            inflated = _inflate(data[body:end], pos)
            inner_type, inner_bytes = _full_tag(inflated, 0, order, where=f"offset {pos} (inflated)")
            if inner_type != _MATRIX or inner_bytes == 0 or 8 + inner_bytes != len(inflated):
                raise MatFileError(
                    f"offset {pos}: a compressed variable must hold one matrix that fills it "
                    f"(type {inner_type}, {inner_bytes} of {len(inflated) - 8} bytes)"
                )
            _Walker(inflated, order, f"offset {pos} (inflated) ").matrix_body(8, 8 + inner_bytes, 0)
        elif mdtype == _MATRIX:
            _Walker(data, order, "offset ").matrix_body(body, end, 0)
        else:
            raise MatFileError(f"offset {pos}: a variable of data type {mdtype}; only matrices are read")
        pos = end


def _full_tag(data: bytes, pos: int, order: str, where: str | None = None) -> tuple[int, int]:
    if pos + 8 > len(data):
        raise MatFileError(f"{where or f'offset {pos}'}: the file ends inside an element tag")
    return struct.unpack_from(order + "II", data, pos)


def _inflate(chunk: bytes, pos: int) -> bytes:
    d = zlib.decompressobj()
    try:
        out = d.decompress(chunk, MAX_INFLATED_BYTES + 1)
    except zlib.error as e:
        raise MatFileError(f"offset {pos}: a compressed variable that does not inflate ({e})") from None
    if len(out) > MAX_INFLATED_BYTES:
        raise MatFileError(
            f"offset {pos}: a compressed variable inflating to more than {MAX_INFLATED_BYTES // 2**20} MiB"
        )
    if not d.eof:
        raise MatFileError(f"offset {pos}: a compressed variable cut short")
    return out


class _Walker:
    """The sequential walk of one matrix's bytes, element by element, as SciPy's ``VarReader5`` reads."""

    def __init__(self, data: bytes, order: str, where: str):
        self.data, self.order, self.where = data, order, where

    def fail(self, pos: int, what: str) -> None:
        raise MatFileError(f"{self.where}{pos}: {what}")

    def element(self, pos: int, end: int) -> tuple[int, int, int, int]:
        """One data element at ``pos``: (type, its data's start, its byte count, the next element)."""
        if pos + 8 > end:
            self.fail(pos, "the matrix ends inside an element tag")
        (word,) = struct.unpack_from(self.order + "I", self.data, pos)
        if word >> 16:  # a small data element: type and byte count in one word, up to 4 bytes of data
            nbytes, mdtype = word >> 16, word & 0xFFFF
            if nbytes > 4:
                self.fail(pos, f"a small data element of {nbytes} bytes (at most 4)")
            return mdtype, pos + 4, nbytes, pos + 8
        (nbytes,) = struct.unpack_from(self.order + "I", self.data, pos + 4)
        nxt = pos + 8 + nbytes + (-nbytes % 8)
        if nxt > end:
            self.fail(pos, f"an element of {nbytes} bytes that runs past its matrix")
        return word, pos + 8, nbytes, nxt

    def dims(self, pos: int, end: int) -> tuple[list[int], int]:
        """The dimensions: at least two, as MATLAB writes them (SciPy reads a character array of none
        out of bounds)."""
        dims, nxt = self.ints(pos, end, "the dimensions")
        if len(dims) < 2:
            self.fail(pos, f"{len(dims)} dimensions (a MATLAB array has at least 2)")
        return dims, nxt

    def ints(self, pos: int, end: int, what: str) -> tuple[list[int], int]:
        mdtype, start, nbytes, nxt = self.element(pos, end)
        if mdtype not in (_INT32, _UINT32) or nbytes % 4 or nbytes > 4 * _MAX_DIMS:
            self.fail(pos, f"{what}: {nbytes} bytes of type {mdtype} (expected up to {_MAX_DIMS} int32)")
        values = list(struct.unpack_from(f"{self.order}{nbytes // 4}i", self.data, start))
        if any(v < 0 for v in values):
            self.fail(pos, f"{what}: negative values {values}")
        return values, nxt

    def text(self, pos: int, end: int, what: str) -> tuple[bytes, int]:
        mdtype, start, nbytes, nxt = self.element(pos, end)
        raw = self.data[start : start + nbytes]
        if mdtype not in (_INT8, _UTF8) or (mdtype == _UTF8 and not raw.isascii()):
            self.fail(pos, f"{what}: data type {mdtype} (expected int8 text)")
        return raw, nxt

    def numeric(self, pos: int, end: int, count: int | None, what: str) -> tuple[int, int]:
        mdtype, _, nbytes, nxt = self.element(pos, end)
        if mdtype not in _NUMERIC:
            self.fail(pos, f"{what}: data type {mdtype} is not a numeric type")
        if count is not None and nbytes != count * _NUMERIC[mdtype]:
            self.fail(pos, f"{what}: {nbytes} bytes for {count} values of {_NUMERIC[mdtype]} bytes")
        return nbytes // _NUMERIC[mdtype], nxt

    def submatrix(self, pos: int, end: int, depth: int) -> int:
        mdtype, nbytes = _full_tag(self.data, pos, self.order, where=f"{self.where}{pos}")
        if mdtype != _MATRIX:
            self.fail(pos, f"data type {mdtype} where a matrix (14) belongs")
        stop = pos + 8 + nbytes
        if stop > end:
            self.fail(pos, f"a matrix of {nbytes} bytes that runs past its parent")
        if nbytes:  # an empty matrix is a bare tag
            self.matrix_body(pos + 8, stop, depth + 1)
        return stop

    def matrix_body(self, pos: int, end: int, depth: int) -> None:
        if depth > _MAX_DEPTH:
            self.fail(pos, f"matrices nested more than {_MAX_DEPTH} deep")
        if pos + 16 > end:
            self.fail(pos, "a matrix too short for its array flags")
        (flags,) = struct.unpack_from(self.order + "I", self.data, pos + 8)
        mclass, is_complex = flags & 0xFF, flags >> 11 & 1
        dims, pos = self.dims(pos + 16, end)
        _, pos = self.text(pos, end, "the name")
        size = math.prod(dims)
        if mclass in _NUMERIC_CLASSES:
            for part in ("real part", "imaginary part")[: 1 + is_complex]:
                _, pos = self.numeric(pos, end, size, part)
        elif mclass == _CHAR:
            mdtype, _, nbytes, nxt = self.element(pos, end)
            if mdtype not in _CHAR_TYPES:
                self.fail(pos, f"characters of data type {mdtype}")
            pos = nxt
        elif mclass == _SPARSE:
            if len(dims) != 2:
                self.fail(pos, f"a sparse matrix of {len(dims)} dimensions")
            _, pos = self.numeric(pos, end, None, "row indices")
            n_ptr, pos = self.numeric(pos, end, None, "column pointers")
            if n_ptr < 1:
                self.fail(pos, "a sparse matrix without column pointers")
            for part in ("values", "imaginary values")[: 1 + is_complex]:
                _, pos = self.numeric(pos, end, None, part)
        elif mclass == _CELL:
            for _ in range(size):
                pos = self.submatrix(pos, end, depth)
        elif mclass in (_STRUCT, _OBJECT):
            if mclass == _OBJECT:
                _, pos = self.text(pos, end, "the class name")
            at = pos
            lengths, pos = self.ints(pos, end, "the field-name length")
            if len(lengths) != 1 or lengths[0] == 0:
                self.fail(at, f"field-name lengths {lengths} (expected one positive value)")
            names, pos = self.text(pos, end, "the field names")
            length = lengths[0]
            for _ in range(size * (len(names) // length)):
                pos = self.submatrix(pos, end, depth)
        elif mclass == _FUNCTION:
            pos = self.submatrix(pos, end, depth)
        else:
            self.fail(pos, f"a matrix of class {mclass}, which glu does not read")
        if pos != end:
            self.fail(pos, f"{end - pos} bytes left over at the end of a matrix")
