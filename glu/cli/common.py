"""What the commands share: argument types, the data, model and evidence options, and loading a model.

Every option that appears in more than one command is defined here once, with its help text, and its
choices come from the package's constants (the word tables of :mod:`glu.data.source`, the unseen-row modes
of :mod:`glu.bn.learning`, the soft rules of :mod:`glu.bn.soft`), so the command line cannot drift from
the package.
"""

from __future__ import annotations

import argparse
import contextlib
import errno
import functools
import json
import math
import os
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from glu.cli.terminal import one_line
from glu.data.source import SYNTHETIC_KEYWORD, WORD_FILES
from glu.errors import EvidenceError, MissingDependencyError
from glu.evidence import check_disjoint, parse_evidence, parse_soft
from glu.files import is_special, is_stdout
from glu.machine import check_memory, human_bytes
from glu.paths import HERE

DATA_HELP = (
    f"data folder, or '{SYNTHETIC_KEYWORD}' (default: $GLU_DATA_DIR, the fetched data in "
    f"{HERE.real_data_label}, else built-in synthetic data)"
)


def _number(text: str, kind: type, what: str) -> float:
    try:
        return kind(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected {what}, not {text!r}") from None


def integer(text: str) -> int:
    """Any whole number."""
    return int(_number(text, int, "a whole number"))


def positive_int(text: str) -> int:
    """A whole number ≥ 1."""
    v = int(_number(text, int, "a whole number"))
    if v < 1:
        raise argparse.ArgumentTypeError(f"expected a whole number ≥ 1, not {v}")
    return v


def seed(text: str) -> int:
    """A random seed: a whole number in [0, 2**32 - 1]."""
    v = int(_number(text, int, "a whole number"))
    if not 0 <= v < 2**32:
        raise argparse.ArgumentTypeError(f"a seed is a whole number in [0, 2**32 - 1], not {v}")
    return v


def positive_float(text: str) -> float:
    """A finite number > 0."""
    v = _number(text, float, "a number")
    if not 0 < v < float("inf"):
        raise argparse.ArgumentTypeError(f"expected a positive number, not {text}")
    return v


def nonneg_float(text: str) -> float:
    """A finite number ≥ 0."""
    v = _number(text, float, "a number")
    if not 0 <= v < float("inf"):
        raise argparse.ArgumentTypeError(f"expected a number ≥ 0, not {text}")
    return v


def tolerance(text: str) -> float:
    """--renormalise TOL: a number in [0, 1)."""
    tol = _number(text, float, "a tolerance such as 1e-4")
    if not 0 <= tol < 1:
        raise argparse.ArgumentTypeError(f"a tolerance is a number in [0, 1), not {text}")
    return tol


def _writable_folder(folder: Path) -> str | None:
    """Why files cannot be created in ``folder`` (made if missing), or None when they can."""
    probe = folder
    while not probe.exists() and probe.parent != probe:  # ends at "/" or ".", which exist
        probe = probe.parent
    if not probe.is_dir():
        return f"{probe} is a file, not a folder"
    if not os.access(probe, os.W_OK | os.X_OK):
        return f"the folder {probe} is not writable"
    return None


def special_output_problem(text: str) -> str | None:
    """For ``-`` and an existing device, FIFO or socket (written through by :mod:`glu.files`): '' when it
    can be written, else why not; for a path the system cannot resolve (a loop of symbolic links, too
    long), why not; None for any other path."""
    if is_stdout(text):
        return ""
    try:
        os.stat(text)
    except OSError as e:
        if e.errno in (errno.ELOOP, errno.ENAMETOOLONG):
            return f"cannot write {text}: {e.strerror}"
        return None  # missing, or a folder that is a file: the checks of output_file say which
    if not is_special(text):
        return None
    return "" if os.access(text, os.W_OK) else f"cannot write {text}: permission denied"


def output_file(text: str) -> Path:
    """-o FILE: a file path whose folder can be written (checked before any work, not after it)."""
    if not text.strip():
        raise argparse.ArgumentTypeError("expected a file name, not an empty string")
    problem = special_output_problem(text)
    if problem is not None:
        if problem:
            raise argparse.ArgumentTypeError(problem)
        return Path(text)
    path = Path(text)
    if path.is_dir() or text.endswith(("/", os.sep)):
        raise argparse.ArgumentTypeError(f"{text} is a folder; give a file name")
    problem = _writable_folder(path.parent)
    if problem:
        raise argparse.ArgumentTypeError(f"cannot write {text}: {problem}")
    return path


IMAGE_SUFFIXES = (".png", ".svg", ".pdf", ".jpg", ".jpeg", ".eps", ".tif", ".tiff", ".webp")
"""What ``--plot FILE`` may be (formats matplotlib writes)."""


def output_image(text: str) -> Path:
    """--plot FILE: an image file (by its suffix) whose folder can be written."""
    path = output_file(text)
    if is_stdout(text):
        raise argparse.ArgumentTypeError("an image is not written to standard output; give a file name")
    if path.suffix.lower() not in IMAGE_SUFFIXES:
        raise argparse.ArgumentTypeError(f"{text}: an image is {', '.join(IMAGE_SUFFIXES)}")
    return path


def output_folder(text: str) -> Path:
    """-o DIR: a folder that exists or can be made, and can be written."""
    if not text.strip():
        raise argparse.ArgumentTypeError("expected a folder name, not an empty string")
    if is_stdout(text) or is_special(text):
        raise argparse.ArgumentTypeError(
            f"{text} is not a folder: this command writes several files; give a folder"
        )
    path = Path(text)
    if path.exists() and not path.is_dir():
        raise argparse.ArgumentTypeError(f"{text} is a file; give a folder")
    problem = _writable_folder(path)
    if problem:
        raise argparse.ArgumentTypeError(f"cannot write into {text}: {problem}")
    return path


def _json_ready(obj: Any) -> Any:
    """``obj`` with ±inf as None (a log-likelihood or score of −∞: impossible); NaN stays (it is a bug)."""
    if isinstance(obj, float) and math.isinf(obj):
        return None
    if isinstance(obj, dict):
        return {k: _json_ready(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_json_ready(v) for v in obj]
    return obj


def json_text(obj: Any) -> str:
    """Strict JSON for ``--json`` output: ±inf become null; a NaN raises ValueError (never printed)."""
    return json.dumps(_json_ready(obj), allow_nan=False)


def public_argv(argv: list[str], data: str | None = None) -> list[str]:
    """The arguments without a path of this machine (no one else's): the data folder named ``DATA``, unless
    it is ``synthetic``, however it was written (``--data DIR``, ``--data=DIR``, or an abbreviation argparse
    accepts such as ``--dat DIR``, given as ``data``, the folder the command parsed); any other absolute
    path shown as ``…/NAME``."""
    out = []
    for i, a in enumerate(argv):
        flag, eq, value = a.partition("=") if a.startswith("--") and "=" in a else ("", "", a)
        if (value and value == data) or flag == "--data" or (i and argv[i - 1] == "--data"):
            value = value if value == "synthetic" else "DATA"
        elif os.path.isabs(value):
            value = f"…/{os.path.basename(os.path.normpath(value))}"
        out.append(f"{flag}={value}" if eq else value)
    return out


def command_line(data: str | None = None) -> str:
    """The command being run, as a shell would take it again (:func:`public_argv`; ``data``: the data folder
    it parsed): for provenance."""
    import shlex

    return "glu " + shlex.join(public_argv(sys.argv[1:], data))


def say_to(as_json: bool) -> Any:
    """``print`` for what a command says besides its answer: to stdout, or to stderr when stdout holds the
    answer alone (``--json``)."""
    return functools.partial(print, file=sys.stderr if as_json else sys.stdout)


def chosen(args: argparse.Namespace, *names: str) -> dict[str, Any]:
    """The options ``names`` as keyword arguments (each option's destination is the parameter's name)."""
    return {name: getattr(args, name) for name in names}


# ------------------------------------------------------------------ shared options


def add_data_option(p: argparse.ArgumentParser, purpose: str = "") -> None:
    """``--data``: the data folder (the same help everywhere, plus what this command uses it for)."""
    p.add_argument("--data", metavar="DIR", help=DATA_HELP + (f"; {purpose}" if purpose else ""))


def add_data_args(p: argparse.ArgumentParser) -> None:
    """``--data``, ``--words``, ``--unseen-words``: where the network is learned from, and how."""
    from glu.bn.learning import UNSEEN_MODES

    add_data_option(p)
    p.add_argument(
        "--schema",
        type=Path,
        metavar="FILE",
        help="your own network: a schema file (.json/.yaml: nodes, values, roles, words); "
        "with --experiments instead of --data",
    )
    p.add_argument(
        "--experiments",
        type=Path,
        metavar="TABLE",
        help="your own experiments for --schema (.csv/.tsv: a column per node, and a column per "
        "word or a 'description' column)",
    )
    p.add_argument(
        "--words",
        choices=tuple(WORD_FILES),
        default="lab",
        help="descriptions: lab = transcriptions (the paper's), asr = speech recogniser",
    )
    p.add_argument(
        "--unseen-words",
        choices=UNSEEN_MODES,
        default=UNSEEN_MODES[0],
        help="CPT rows of word parent configurations never seen: zero (the original's) or uniform",
    )


def add_model_args(p: argparse.ArgumentParser) -> None:
    """``--model`` (with ``--renormalise``) or the data options of :func:`add_data_args` (read by
    :func:`load_model`)."""
    p.add_argument(
        "--model",
        type=Path,
        help="model file (.json, the original .mat, or .bif/.xmlbif/.uai); default: learn from --data",
    )
    add_renormalise_option(p)
    add_data_args(p)


def add_renormalise_option(p: argparse.ArgumentParser) -> None:
    """``--renormalise [TOL]``: how far from 1 a CPT row of a BIF, XMLBIF or UAI file may sum."""
    from glu.bn.exchange import IMPORT_TOL
    from glu.bn.rows import RENORMALISE_DEFAULT

    p.add_argument(
        "--renormalise",
        type=tolerance,
        nargs="?",
        const=RENORMALISE_DEFAULT,
        metavar="TOL",
        help=f"a BIF, XMLBIF or UAI model: rescale CPT rows whose sum is within TOL of 1 (default without "
        f"the option: {IMPORT_TOL:g}; --renormalise alone: {RENORMALISE_DEFAULT:g}); the rows rescaled are "
        "reported",
    )


def add_engine_args(p: argparse.ArgumentParser) -> None:
    """``--max-table``: the largest table exact inference may build (read by :func:`make_engine`)."""
    from glu.bn.plan import MAX_TABLE_DEFAULT, MAX_TABLE_ENV

    p.add_argument(
        "--max-table",
        type=positive_int,
        metavar="N",
        help=f"largest table (entries) exact inference may build in a large network; a network that needs "
        f"more is refused with its size and elimination width (default: ${MAX_TABLE_ENV}, else "
        f"{MAX_TABLE_DEFAULT:,})",
    )


def make_engine(bn: Any, args: argparse.Namespace) -> Any:
    """The :class:`~glu.bn.inference.Engine` of ``bn`` with the command's ``--max-table``, which is first
    checked against the memory this process may use (a table of N entries takes 8 N bytes)."""
    from glu.bn import inference

    max_table = getattr(args, "max_table", None)
    if max_table is not None:
        check_memory(8 * max_table, f"--max-table {max_table:,} (a table of that many entries)")
    return inference.make_engine(bn, max_table=max_table)


def add_evidence_args(p: argparse.ArgumentParser) -> None:
    """``--evidence``, ``--soft``, ``--soft-rule`` (read by :func:`read_evidence`)."""
    p.add_argument(
        "--evidence", action="extend", nargs="+", default=[], metavar="NODE=VALUE", help="hard evidence"
    )
    p.add_argument(
        "--soft",
        action="append",
        default=[],
        metavar="NODE=v1:p1,v2:p2,…",
        help="soft evidence on an affordance node, a distribution over its values, "
        "e.g. a gesture posterior Action=grasp:0.2,tap:0.6,touch:0.2",
    )
    add_soft_rule_option(p)


def add_description_args(p: argparse.ArgumentParser) -> None:
    """``--score`` and ``--candidates``: how verbal descriptions are scored, and which sentences are
    ranked."""
    from glu.language.candidates import CANDIDATES, DEFAULT_CANDIDATES
    from glu.language.descriptions import DEFAULT_SCORE, SCORES

    p.add_argument(
        "--score",
        choices=tuple(SCORES),
        default=DEFAULT_SCORE,
        help="sentence score: paper = (1/L) Σ log p(w), the papers' formula (default); "
        "original = (1 + Σ log p(w))/L, what the originals' code printed",
    )
    p.add_argument(
        "--candidates",
        default=DEFAULT_CANDIDATES,
        metavar="{" + ",".join(CANDIDATES) + ",FILE}",
        help="sentences to rank: grammar = every sentence of the grammar, exactly (default); "
        "samples = the originals' 9,941 sampled sentences (in the data folder); "
        "FILE = one sentence per line",
    )


def read_candidates(args: argparse.Namespace, source: Any | None = None) -> list[tuple[str, ...]] | None:
    """The sentences ``--candidates`` names (None: the whole grammar); ``source`` holds the samples."""
    from glu.language.candidates import candidate_sentences

    if args.candidates == "samples" and source is None:
        from glu.data.source import resolve_data

        source = resolve_data(getattr(args, "data", None))
    return candidate_sentences(args.candidates, source)


def read_evidence(args: argparse.Namespace) -> tuple[dict[str, str], dict[str, dict[str, float]]]:
    """The hard and soft evidence of ``--evidence`` and ``--soft`` (a node may not be in both)."""
    evidence = parse_evidence(args.evidence)
    soft = parse_soft(args.soft)
    check_disjoint(evidence, soft)
    return evidence, soft


MODEL_BYTES_PER_BYTE = 40
"""Memory a model file takes to read, per byte of the file: 33–34 measured for a network with a CPT of 2^24
entries (a 67 MB UAI file read with 2.2 GB, an 84 MB BIF or JSON file with 2.5–2.8 GB), rounded up."""


def read_model_file(path: Path, fmt: str | None = None, renormalise: float | None = None) -> Any:
    """A :class:`~glu.bn.model.BayesNet` from a file: glu's JSON, the originals' ``.mat``, or BIF/XMLBIF/UAI.

    ``renormalise``: the tolerance of :func:`glu.bn.exchange.import_bn` for rows that do not sum to 1.
    """
    from glu.bn.model import BayesNet
    from glu.errors import ModelError

    if renormalise is not None and path.suffix.lower() in (".mat", ".json"):
        raise EvidenceError("--renormalise applies to BIF, XMLBIF and UAI files")
    try:
        size = path.stat().st_size
    except FileNotFoundError:
        size = 0  # each reader says "no such file" in its own words
    except OSError as e:  # a loop of symbolic links, a name too long
        raise ModelError(f"{path}: cannot read the model ({e.strerror})") from None
    check_memory(MODEL_BYTES_PER_BYTE * size, f"{path} ({human_bytes(size)}: reading its tables)")
    suffix = path.suffix.lower()
    if fmt is None and suffix == ".mat":
        return BayesNet.from_bnt_mat(path)
    if fmt is None and suffix == ".json":
        return BayesNet.load(path)
    from glu.bn.exchange import import_bn

    return import_bn(path, fmt, renormalise)


def load_model(args: argparse.Namespace) -> tuple[Any, str]:
    """The model named by ``--model``, or the one learned from ``--data``; returns (BayesNet, description)."""

    model = getattr(args, "model", None)
    if model is not None:
        if getattr(args, "data", None):
            raise EvidenceError("give either --model or --data, not both")
        if getattr(args, "schema", None) or getattr(args, "experiments", None):
            raise EvidenceError("give either --model or --schema/--experiments, not both")
        bn = read_model_file(model, renormalise=getattr(args, "renormalise", None))
        r = bn.meta.get("renormalised")
        rescaled = f"; {r['rows']} CPT row(s) rescaled to sum to 1 on import" if r else ""
        return bn, one_line(f"model {model} ({bn.meta.get('data_source', 'unknown data')}{rescaled})")
    from glu.bn.learning import learn_bn
    from glu.data.source import load_experiments, resolve_data

    schema_file, table = getattr(args, "schema", None), getattr(args, "experiments", None)
    if (schema_file is None) != (table is None):
        raise EvidenceError("give --schema FILE and --experiments TABLE together (your own network and data)")
    if schema_file is not None:
        from glu.data.tables import read_experiment_table
        from glu.schema import read_schema_file

        if getattr(args, "data", None):
            raise EvidenceError("give either --data or --schema/--experiments, not both")
        schema = read_schema_file(schema_file)
        df = read_experiment_table(table, schema)
    else:
        schema, df = None, load_experiments(resolve_data(args.data), args.words)
    bn = learn_bn(df, schema, unseen_words=args.unseen_words)
    return bn, one_line(f"learned from {df.attrs['data_source']}, unseen words {args.unseen_words}")


# ------------------------------------------------------------------ progress and optional dependencies


def progress_bar(total: int | None, desc: str, unit: str, quiet: bool = False) -> Any:
    """A tqdm bar on stderr when it is a terminal and the output is not ``--json`` (``quiet``); else None.

    Callers print plain lines instead when this is None, so logs and pipes never see bar characters.
    """
    if quiet or not sys.stderr.isatty():
        return None
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit=unit, file=sys.stderr, leave=False, dynamic_ncols=True)


@contextlib.contextmanager
def progress(total: int | None, desc: str, unit: str) -> Iterator[Any]:
    """The :func:`progress_bar` of a block (None when there is none), closed when the block ends."""
    bar = progress_bar(total, desc, unit)
    try:
        yield bar
    finally:
        if bar is not None:
            bar.close()


def require_extra(extra: str, *modules: str) -> None:
    """Raise :class:`MissingDependencyError` (one line) unless every module can be imported.

    ``extra`` names the optional dependencies that provide them (``pip install 'glu[EXTRA]'``).
    """
    import importlib.util

    missing = [m for m in modules if importlib.util.find_spec(m) is None]
    if missing:
        raise MissingDependencyError(
            f"this command needs {', '.join(missing)}, which the plain `pip install glu` leaves out; "
            f"install them with: pip install 'glu[{extra}]'"
        )


# ------------------------------------------------------------------ one spelling per option


class DeprecatedAlias(argparse.Action):
    """An old spelling of an option that still works, hidden from ``--help``: it stores into the new option's
    destination and says once, on stderr, which spelling to use instead."""

    def __init__(self, option_strings, dest, replacement: str, **kwargs):  # type: ignore[no-untyped-def]
        self.replacement = replacement
        super().__init__(option_strings, dest, **kwargs)

    def __call__(self, parser, namespace, values, option_string=None):  # type: ignore[no-untyped-def]
        print(f"{parser.prog}: {option_string} is deprecated; use {self.replacement}", file=sys.stderr)
        setattr(namespace, self.dest, self.const if self.nargs == 0 else values)


def add_deprecated_alias(
    p: argparse.ArgumentParser, old: str, new: str, replacement: str | None = None, const: Any = None
) -> None:
    """Keep ``old`` working as a hidden alias of the option ``new`` (one deprecation line on stderr).

    ``const``: the old spelling was a flag, equivalent to ``new`` with this value (``replacement`` says so).
    """
    target = next(a for a in p._actions if new in a.option_strings)
    if const is None and target.nargs == 0:  # a flag for a flag (store_true)
        const, replacement = target.const, replacement or "/".join(target.option_strings)
    if const is not None:
        value: dict[str, Any] = {"nargs": 0, "const": const}
        replacement = replacement or f"{new} {const}"
    else:
        value = {
            "type": target.type,
            "nargs": target.nargs,
            "choices": target.choices,
            "metavar": target.metavar,
        }
        replacement = replacement or "/".join(target.option_strings)
    p.add_argument(
        old,
        action=DeprecatedAlias,
        dest=target.dest,
        default=argparse.SUPPRESS,
        replacement=replacement,
        help=argparse.SUPPRESS,
        **value,
    )


def add_out_option(p: argparse.ArgumentParser, metavar: str, help: str, folder: bool = False) -> None:
    """``-o/--out``, required: the file (:func:`output_file`) or, with ``folder``, the folder
    (:func:`output_folder`) a command writes, checked before any work."""
    kind = output_folder if folder else output_file
    p.add_argument("-o", "--out", type=kind, required=True, metavar=metavar, help=help)


def add_json_option(p: argparse.ArgumentParser, what: str) -> None:
    """``--json``: ``what`` as strict JSON, alone on stdout (anything else the command says goes to
    stderr)."""
    p.add_argument("--json", action="store_true", help=f"strict JSON on stdout, nothing else: {what}")


def add_soft_rule_option(p: argparse.ArgumentParser, what: str = "soft evidence") -> None:
    """``--soft-rule``: how a distribution over a node's values enters the network."""
    from glu.bn.soft import SOFT_RULES

    p.add_argument(
        "--soft-rule",
        choices=SOFT_RULES,
        default=SOFT_RULES[0],
        help=f"how {what} enters the network: virtual (likelihood) evidence, as the originals, or "
        "Jeffrey's rule",
    )


def scheduler_address(text: str) -> str:
    """--scheduler ADDRESS: a Dask scheduler address (tcp://host:port) or 'synchronous'."""
    from glu.errors import DataError
    from glu.machine import check_scheduler

    try:
        return check_scheduler(text) or text
    except DataError as e:
        raise argparse.ArgumentTypeError(str(e).removeprefix(f"--scheduler {text!r}: ")) from None


def add_cluster_args(p: argparse.ArgumentParser, unit: str) -> None:
    """``--scheduler`` and ``--workers``: where the Dask tasks (one per ``unit``) run."""
    p.add_argument(
        "--scheduler",
        type=scheduler_address,
        metavar="ADDRESS",
        help=f"an existing Dask scheduler, e.g. tcp://127.0.0.1:8786 ('synchronous': run here, one {unit} "
        "after another); default: a LocalCluster with one worker per core",
    )
    p.add_argument(
        "--workers", type=positive_int, metavar="N", help="LocalCluster workers (default: one per core)"
    )


def add_hmm_size_args(p: argparse.ArgumentParser) -> None:
    """``--states``, ``--mix`` and ``--iter`` of the gesture HMMs, defaults from
    :class:`~glu.hmm.TrainingConfig` (read by :func:`hmm_config`)."""
    from glu.hmm import TrainingConfig

    d = TrainingConfig()
    for flag, default, text in (
        ("--states", d.n_states, "Q, states per HMM"),
        ("--mix", d.n_mix, "M, Gaussians per state"),
        ("--iter", d.n_iter, "most EM iterations"),
    ):
        p.add_argument(flag, type=positive_int, default=default, help=f"{text} (default {default})")


def hmm_config(args: argparse.Namespace, *fields: str) -> Any:
    """The :class:`~glu.hmm.TrainingConfig` of the options of :func:`add_hmm_size_args` and the options
    ``fields`` (named as its fields)."""
    from glu.hmm import TrainingConfig

    return TrainingConfig(n_states=args.states, n_mix=args.mix, n_iter=args.iter, **chosen(args, *fields))
