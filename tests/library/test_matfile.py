"""Reading ``.mat`` files that crash SciPy's reader: glu refuses them in one line and never crashes.

The corpus in ``tests/data/mat_crashes/`` (written by its ``make_corpus.py``) holds small files on which a
plain ``scipy.io.loadmat`` dies with a segmentation fault; each is checked to still crash SciPy in a child
process (so the test keeps its teeth when SciPy changes), to be refused by :func:`glu.matfile.read_mat`, and
to give one error line and exit 2 from ``glu bn import`` and ``glu query --model``. Well-formed files —
the originals' models when the real data is here, and files SciPy writes — read exactly as SciPy reads them.
"""

from __future__ import annotations

import io
import struct
import subprocess
import sys
import zlib
from pathlib import Path

import numpy as np
import pytest
import scipy.io
from cli_run import run
from conftest import NO_SHARED_REASON, SHARED

from glu import matfile
from glu.matfile import MatFileError, check_mat, read_mat

CORPUS = sorted((Path(__file__).parents[1] / "data" / "mat_crashes").glob("*.mat"))


def test_the_corpus_is_there():
    names = {p.stem for p in CORPUS}
    assert {"numeric_type_241", "compressed_numeric_type_241", "complex_reads_next_matrix"} <= names
    assert len(CORPUS) >= 6


def test_each_corpus_file_still_crashes_scipy():
    """A child per file, all at once: a plain loadmat is killed by a signal (a negative return code)."""
    code = "import sys, scipy.io; scipy.io.loadmat(sys.argv[1])"
    children = {
        p.name: subprocess.Popen([sys.executable, "-c", code, str(p)], stderr=subprocess.DEVNULL)
        for p in CORPUS
    }
    codes = {name: child.wait(timeout=120) for name, child in children.items()}
    assert all(c < 0 for c in codes.values()), codes


@pytest.mark.parametrize("path", CORPUS, ids=lambda p: p.stem)
def test_read_mat_refuses_each_corpus_file(path):
    with pytest.raises(MatFileError, match=rf"^{path}: .*offset \d+"):
        read_mat(path)


@pytest.mark.parametrize("path", CORPUS, ids=lambda p: p.stem)
@pytest.mark.parametrize("command", ["bn import", "query"])
def test_commands_refuse_each_corpus_file_in_one_line(capsys, tmp_path, path, command):
    out = tmp_path / "out.json"
    argv = (
        ["bn", "import", str(path), "-o", str(out)]
        if command == "bn import"
        else ["query", "--model", str(path), "--target", "Action"]
    )
    status, stdout, err = run(capsys, *argv)
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert status == 2 and stdout == ""
    assert len(lines) == 1 and lines[0].startswith(f"glu {command.split()[0]}") and ": error: " in lines[0]
    assert str(path) in lines[0] and "offset" in lines[0]
    assert not out.exists()


def _same(a, b) -> None:
    """Two loadmat results equal, recursively (arrays, structs, cells)."""
    if isinstance(a, dict):
        assert a.keys() == b.keys()
        for k in a:
            if not k.startswith("__"):
                _same(a[k], b[k])
    elif isinstance(a, np.ndarray) and a.dtype == object and a.shape == () and hasattr(a.item(), "toarray"):
        _same(a.item(), b.item())
    elif isinstance(a, np.ndarray) and a.dtype == object:
        assert a.shape == b.shape
        for x, y in zip(a.flat, b.flat, strict=True):
            _same(x, y)
    elif isinstance(a, np.ndarray) and a.dtype.names:
        for name in a.dtype.names:
            _same(a[name], b[name])
    elif hasattr(a, "_fieldnames"):
        assert a._fieldnames == b._fieldnames
        for name in a._fieldnames:
            _same(getattr(a, name), getattr(b, name))
    elif hasattr(a, "toarray"):  # sparse
        np.testing.assert_array_equal(a.toarray(), b.toarray())
    else:
        np.testing.assert_array_equal(a, b)


def _written(tmp_path, compress: bool) -> Path:
    """A file with every class glu may meet: doubles, ints, complex, text, a cell, a struct, a sparse
    matrix."""
    import scipy.sparse

    cell = np.empty((1, 3), dtype=object)
    cell[0, 0], cell[0, 1], cell[0, 2] = np.arange(4.0), "word", np.eye(2, dtype=np.int32)
    variables = {
        "x": np.arange(6.0).reshape(2, 3),
        "z": np.array([1 + 2j, 3 - 1j]),
        "i": np.arange(5, dtype=np.uint8),
        "s": "a string",
        "c": cell,
        "st": {"a": np.ones(3), "b": {"inner": "text", "v": np.array([[1.0]])}},
        "sp": scipy.sparse.csc_array(np.array([[0, 1.5], [2.0, 0]])),
        "e": np.zeros((0, 3)),
    }
    path = tmp_path / f"w{int(compress)}.mat"
    scipy.io.savemat(path, variables, do_compression=compress)
    return path


@pytest.mark.parametrize("compress", [False, True], ids=["uncompressed", "compressed"])
@pytest.mark.parametrize("options", [{}, {"squeeze_me": True, "struct_as_record": False}])
def test_well_formed_files_read_as_scipy_reads_them(tmp_path, compress, options):
    path = _written(tmp_path, compress)
    _same(read_mat(path, **options), scipy.io.loadmat(path, **options))


@pytest.mark.shared_data
@pytest.mark.skipif(SHARED is None, reason=NO_SHARED_REASON)
@pytest.mark.parametrize("name", ["BN_lab.mat", "HMM_M1_Q6_mixsplit.mat", "HMM_M3_Q6_mixsplit.mat"])
def test_the_originals_read_as_scipy_reads_them(name):
    path = SHARED / "reference-models" / name
    options = {"squeeze_me": True, "struct_as_record": False} if name.startswith("BN") else {}
    _same(read_mat(path, **options), scipy.io.loadmat(path, **options))


def _header(version: bytes = b"\x00\x01", indicator: bytes = b"IM") -> bytes:
    return b"MATLAB 5.0 MAT-file".ljust(116, b" ") + bytes(8) + version + indicator


@pytest.mark.parametrize(
    ("data", "message"),
    [
        (b"", "shorter than the 128-byte header"),
        (bytes(200), "v4 file"),
        (_header(version=b"\x00\x02"), r"v7\.3 \(HDF5\)"),
        (_header(indicator=b"XX"), "endian indicator"),
        (_header() + struct.pack("<II", 9, 8) + bytes(8), "only matrices are read"),
        (_header() + struct.pack("<II", 14, 64), "a variable of 64 bytes where 0 remain"),
        (_header() + struct.pack("<II", 15, 4) + b"junk", "does not inflate"),
    ],
    ids=["empty", "v4", "v7.3", "indicator", "not-a-matrix", "truncated", "bad-zlib"],
)
def test_malformed_files_are_refused_with_the_reason(data, message):
    with pytest.raises(MatFileError, match=message):
        check_mat(data)


def test_a_compressed_variable_cannot_inflate_past_the_cap(monkeypatch):
    """A zlib bomb: 1 MiB of zeros compresses to 1 kB; with a cap of 64 kB it is refused before SciPy."""
    monkeypatch.setattr(matfile, "MAX_INFLATED_BYTES", 64 * 1024)
    body = zlib.compress(struct.pack("<II", 14, 2**20) + bytes(2**20))
    with pytest.raises(MatFileError, match="inflating to more than"):
        check_mat(_header() + struct.pack("<II", 15, len(body)) + body)


def test_a_well_formed_file_is_parsed_from_the_checked_bytes(tmp_path, monkeypatch):
    """SciPy reads the bytes that were checked, not the file again (no window to swap it)."""
    path = _written(tmp_path, False)
    seen = []
    real = scipy.io.loadmat
    monkeypatch.setattr(scipy.io, "loadmat", lambda f, **kw: seen.append(f) or real(f, **kw))
    read_mat(path)
    assert len(seen) == 1 and isinstance(seen[0], io.BytesIO)


def _el(mdtype: int, payload: bytes) -> bytes:
    """A data element: its tag, then its bytes padded to 8."""
    return struct.pack("<II", mdtype, len(payload)) + payload + bytes(-len(payload) % 8)


def _matrix(mclass: int, dims: list[int], *parts: bytes, name: bytes = b"x") -> bytes:
    """A matrix element (type 14): array flags of class ``mclass``, dimensions, name, then ``parts``."""
    head = _el(6, struct.pack("<II", mclass, 0)) + _el(5, struct.pack(f"<{len(dims)}i", *dims)) + _el(1, name)
    return _el(14, head + b"".join(parts))


def _doubles(*values: float) -> bytes:
    return _el(9, struct.pack(f"<{len(values)}d", *values))


def _nested_cells(depth: int) -> bytes:
    inner = _matrix(6, [1, 1], _doubles(1.0), name=b"")
    for _ in range(depth):
        inner = _matrix(1, [1, 1], inner, name=b"")
    return inner


@pytest.mark.parametrize(
    ("variable", "message"),
    [
        (_el(15, zlib.compress(_el(9, bytes(8)))), r"must hold one matrix that fills it \(type 9"),
        (_el(15, zlib.compress(_matrix(6, [1, 1], _doubles(1.0)))[:-6]), "a compressed variable cut short"),
        (_matrix(6, [-1, 2], _doubles(1.0)), r"the dimensions: negative values \[-1, 2\]"),
        (_matrix(6, [1, 2], _doubles(1.0)), "real part: 8 bytes for 2 values of 8 bytes"),
        (_matrix(1, [1, 1], _el(9, bytes(8))), "data type 9 where a matrix \\(14\\) belongs"),
        (_matrix(1, [1, 1], struct.pack("<II", 14, 800)), "a matrix of 800 bytes that runs past its parent"),
        (_nested_cells(70), "matrices nested more than 64 deep"),
        (_el(14, _el(6, struct.pack("<II", 6, 0))[:8]), "a matrix too short for its array flags"),
        (_matrix(5, [2, 2, 2], _el(5, b""), _el(5, b""), _doubles()), "a sparse matrix of 3 dimensions"),
        (_matrix(5, [2, 2], _el(5, b""), _el(5, b""), _doubles()), "a sparse matrix without column pointers"),
        (_matrix(2, [1, 1], _el(5, struct.pack("<2i", 4, 4)), _el(1, b"abcd")), r"name lengths \[4, 4\]"),
        (_matrix(2, [1, 1], _el(5, struct.pack("<i", 0)), _el(1, b"")), r"field-name lengths \[0\]"),
        (_matrix(6, [1, 1], _doubles(1.0), _doubles(2.0)), "16 bytes left over at the end of a matrix"),
    ],
    ids=[
        "compressed-non-matrix", "compressed-cut-short", "negative-dimension", "wrong-byte-count",
        "cell-of-non-matrix", "sub-matrix-past-parent", "nested-70-deep", "no-array-flags", "sparse-3d",
        "sparse-no-pointers", "two-field-name-lengths", "zero-field-name-length", "left-over-bytes",
    ],
)  # fmt: skip
def test_malformed_matrices_are_refused_at_their_offset(variable, message):
    with pytest.raises(MatFileError, match=r"^offset \d+( \(inflated\))?: .*" + message):
        check_mat(_header() + variable)


def test_a_function_handle_reads_as_scipy_reads_it(tmp_path):
    """A function handle (class 16) holds one matrix, walked like any other; SciPy then reads the bytes."""
    path = tmp_path / "f.mat"
    path.write_bytes(
        _header() + _matrix(16, [1, 1], _matrix(6, [1, 2], _doubles(1.0, 2.0), name=b""), name=b"f")
    )
    _same(read_mat(path)["f"], scipy.io.loadmat(path)["f"])
    with pytest.raises(MatFileError, match="left over"):  # the walk does not stop at the handle's matrix
        check_mat(_header() + _matrix(16, [1, 1], _matrix(6, [1, 1], _doubles(1.0), name=b""), _doubles(2.0)))
