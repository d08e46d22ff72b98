"""Write the corpus of ``.mat`` files that crash SciPy's MAT v5 reader (kept in git; run again to remake).

Each file is a tiny matrix written by ``scipy.io.savemat`` with a few bytes patched, so that SciPy's compiled
reader indexes its table of data types out of range (a segmentation fault, SciPy 1.17 and earlier). None of
them holds data from anywhere but this script. ``tests/library/test_matfile.py`` checks that each one still
crashes a plain ``scipy.io.loadmat`` in a child process, and that glu refuses each with one line.

    python tests/data/mat_crashes/make_corpus.py
"""

import io
import struct
import zlib
from pathlib import Path

import numpy as np
import scipy.io

HERE = Path(__file__).parent


def saved(variables: dict, compress: bool = False) -> bytearray:
    b = io.BytesIO()
    scipy.io.savemat(b, variables, do_compression=compress)
    return bytearray(b.getvalue())


def find_tag(data: bytes, mdtype: int, nbytes: int, start: int = 128) -> int:
    """Offset of the first full element tag (type, byte count) at or after ``start``."""
    tag = struct.pack("<II", mdtype, nbytes)
    at = data.find(tag, start)
    assert at >= 0, (mdtype, nbytes)
    return at


def set_type(data: bytearray, at: int, mdtype: int) -> bytearray:
    data[at : at + 4] = struct.pack("<I", mdtype)
    return data


def compressed(plain: bytes) -> bytearray:
    """The same variables in the compressed form: the first variable wrapped in one zlib element."""
    body = zlib.compress(bytes(plain[128:]))
    return bytearray(plain[:128] + struct.pack("<II", 15, len(body)) + body)


def element(mdtype: int, data: bytes) -> bytes:
    """One full data element: its tag, its data, zeros to the next 8-byte boundary."""
    return struct.pack("<II", mdtype, len(data)) + data + bytes(-len(data) % 8)


def main() -> None:
    x = np.arange(3.0)
    cases = {}
    # 1, 2: a double array's data of type 241 (past the table's end) and of type 8 (an empty slot)
    d = saved({"x": x})
    cases["numeric_type_241"] = set_type(d.copy(), find_tag(d, 9, 24), 241)
    cases["numeric_type_8"] = set_type(d.copy(), find_tag(d, 9, 24), 8)
    # 3: characters of type 240
    c = saved({"s": "abcdefgh"})
    cases["char_type_240"] = set_type(c.copy(), find_tag(c, 16, 8), 240)
    # 4: the complex flag set on the first of two arrays in a cell: the reader takes the second array's
    # matrix tag (type 14, an empty slot) for the first one's imaginary part
    cell = np.empty((1, 2), dtype=object)
    cell[0, 0], cell[0, 1] = x, x
    k = saved({"c": cell})
    k2 = k.copy()
    flags_at = find_tag(k, 6, 8, find_tag(k, 6, 8) + 8)  # the second array flags: the first cell's
    k2[flags_at + 8 : flags_at + 12] = struct.pack("<I", 6 | 1 << 11)  # double, complex
    cases["complex_reads_next_matrix"] = k2
    # 5: characters in an array of no dimensions: SciPy turns them into strings reading dims[-1]
    header = bytes(saved({"x": x})[:128])
    body = (
        element(6, struct.pack("<II", 4, 0)) + element(5, b"") + element(1, b"s") + element(16, b"abcdefgh")
    )
    cases["char_without_dimensions"] = bytearray(header + element(14, body))
    # 6, 7: the compressed form of 1 and 4
    cases["compressed_numeric_type_241"] = compressed(cases["numeric_type_241"])
    cases["compressed_complex_reads_next_matrix"] = compressed(cases["complex_reads_next_matrix"])
    for name, data in cases.items():
        (HERE / f"{name}.mat").write_bytes(bytes(data))
        print(name, len(data), "bytes")


if __name__ == "__main__":
    main()
