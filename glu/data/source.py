"""Where the data comes from: ``--data DIR``, ``$GLU_DATA_DIR``, the fetched data, else synthetic.

The fetched data is ``data/real/`` in a source checkout and the user's data folder
(``~/.local/share/glu/real`` on Linux) when glu is installed (:mod:`glu.paths`).

A data folder has the layout of the public data (and of ``glu data fetch`` / ``glu data synth``)::

    affordance-words/sent-1-5_lab_aff_bag.txt     words from transcriptions (``words="lab"``)
    affordance-words/sent-all_mllr3_aff_bag.txt   words from a speech recogniser (``words="asr"``)
    affordance-words/networkDefinition.txt        nodes and values
    gestures/<recording>/data.log                 human hand trajectories (YARP logs)
    reference-models/BN_lab.mat                   the originals' learned network
    reference-models/HMM_M{3,1}_Q6_mixsplit.mat   the originals' gesture HMMs
    sentence-samples/sentence_10000samples_uniq.txt   the originals' sampled sentences

:class:`DataSource` owns this layout: code asks it for ``hand_log(recording)``, ``original_bn()``,
``original_hmms(n_mix)``, … and never spells a path inside a data folder itself.

Every result carries :meth:`DataSource.describe`, so it always says which data it came from — by its
public origin (repositories and commits) or the synthetic generator's parameters, never by a path on
this machine; :meth:`DataSource.location` adds the folder, for messages to the person at the keyboard.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from glu import paths
from glu.data.layout import (
    DEFAULT_SYNTHETIC_N,
    DEFAULT_SYNTHETIC_SEED,
    GESTURES,
    HAND_LOG,
    NETWORK_DEFINITION,
    ORIGINAL_BN,
    ORIGINAL_HMMS,
    SENTENCE_SAMPLES,
    SYNTHETIC_KEYWORD,
    SYNTHETIC_MARKER,
    WORD_FILES,
)
from glu.errors import DataError
from glu.schema import Schema, default_schema


@dataclass(frozen=True)
class DataSource:
    """A resolved data source.

    Attributes
    ----------
    kind : ``"real"`` or ``"synthetic"``
    root : the data folder, or None for synthetic data generated in memory
    origin : how it was chosen: ``"--data"``, ``"GLU_DATA_DIR"``, ``"data/real"`` or ``"default"``
    seed, n_experiments : the generator's parameters, for synthetic data
    """

    kind: str
    root: Path | None
    origin: str
    seed: int = DEFAULT_SYNTHETIC_SEED
    n_experiments: int = DEFAULT_SYNTHETIC_N

    @property
    def is_real(self) -> bool:
        """True for the authors' recordings, False for synthetic data."""
        return self.kind == "real"

    def describe(self) -> str:
        """One line saying which data this is, without machine paths: what figures and tables carry.

        Real data is named by its public origin when its checksums are the published ones (``real data:
        giampierosalvi/AffordancesAndSpeech@421f455, gsaponaro/tcds-gestures@fd608ac``); a folder that is
        not is named by its folder and why: ``data folder 'NAME' (the published data modified:
        affordance-words/… differs from the published file)`` when some of its files are the published
        ones and others differ, ``data folder 'NAME' (not the published data: …)`` otherwise; synthetic
        data by the generator's parameters. The same data gives the same line however it was found.
        """
        if self.kind == "real":
            from glu.data.fetch import published_origin

            origin = published_origin(self.root) if self.root is not None else None
            if origin is None:
                return f"data folder '{self.root.name}' ({modified_text(self.root)})"
            return f"real data: {origin}"
        return f"synthetic data (seed {self.seed}, {self.n_experiments} experiments)"

    def reason(self) -> str:
        """How this source was chosen (and, for the synthetic fallback, why no real data was used)."""
        fetched = paths.HERE.real_data_label
        return {
            "--data": "chosen explicitly (--data or the data parameter)",
            "GLU_DATA_DIR": f"given by ${paths.DATA_ENV_VAR}",
            "data/real": f"fetched into {fetched}",
        }.get(
            self.origin,
            f"no real data found: no --data, no ${paths.DATA_ENV_VAR}, nothing in {fetched} "
            "(`glu data fetch` downloads it)",
        )

    def location(self) -> str:
        """:meth:`describe`, how it was chosen and the folder: for messages on this machine, never results."""
        where = f" in {self.root}" if self.root is not None else ", generated in memory"
        return f"{self.describe()}{where} ({self.reason()})"

    # ------------------------------------------------------------------ the folder layout
    def optional(self, relative: str) -> Path | None:
        """Path of a file of this source if it has it, else None (``relative`` to the data folder)."""
        if self.root is None:
            return None
        p = self.root / relative
        return p if p.exists() else None

    def file(self, relative: str) -> Path:
        """Path of a file of this source; raises :class:`DataError` if the source has no such file."""
        if self.root is None:
            raise DataError(f"{relative}: synthetic data generated in memory has no files")
        p = self.root / relative
        if not p.exists():
            raise DataError(f"{p}: no such file in the data folder {self.root} ({self.describe()})")
        return p

    def experiments_file(self, words: str = "lab") -> Path:
        """The experiment table of a ``words`` option (:data:`WORD_FILES`)."""
        return self.file(WORD_FILES[check_words(words)])

    def network_definition(self) -> Path | None:
        """``networkDefinition.txt`` (nodes and values), if the source has it."""
        return self.optional(NETWORK_DEFINITION)

    @property
    def has_gestures(self) -> bool:
        """True if the source has a ``gestures/`` folder of hand logs."""
        return self.optional(GESTURES) is not None

    def recordings(self) -> tuple[str, ...]:
        """Names of the recordings that have a hand log, sorted."""
        folder = self.optional(GESTURES)
        if folder is None:
            return ()
        return tuple(sorted(d.name for d in folder.iterdir() if (d / HAND_LOG).is_file()))

    def has_hand_log(self, recording: str) -> bool:
        """True if the source has the hand log of ``recording``."""
        return self.optional(f"{GESTURES}/{recording}/{HAND_LOG}") is not None

    def hand_log(self, recording: str) -> Path:
        """The hand log ``gestures/<recording>/data.log``; :class:`DataError` naming the recordings if
        absent."""
        if not self.has_hand_log(recording):
            have = self.recordings()
            raise DataError(
                f"{recording}: no such recording in {self.describe()}; "
                + (f"recordings: {', '.join(have)}" if have else "it has no gesture recordings")
            )
        return self.file(f"{GESTURES}/{recording}/{HAND_LOG}")

    def original_bn(self) -> Path | None:
        """The originals' learned network ``BN_lab.mat``, if the source has it."""
        return self.optional(ORIGINAL_BN)

    def original_hmms(self, n_mix: int = 3) -> Path | None:
        """The originals' gesture HMMs with ``n_mix`` Gaussians per state, if the source has them."""
        if n_mix not in ORIGINAL_HMMS:
            raise DataError(f"n_mix={n_mix}: the originals have HMMs with M in {sorted(ORIGINAL_HMMS)}")
        return self.optional(ORIGINAL_HMMS[n_mix])

    def sentence_samples(self) -> Path | None:
        """The originals' 9,941 sampled sentences, if the source has them."""
        return self.optional(SENTENCE_SAMPLES)


class DataWarning(UserWarning):
    """A data folder that is not the published data although it holds files of the published names."""


def modified_text(root: Path) -> str:
    """Why the data folder ``root`` is not the published data, naming the files that differ."""
    from glu.data.fetch import published_check

    same, differ = published_check(root)
    if not differ:
        return "not the published data: it lacks the published experiment table"
    files = ", ".join(differ[:3]) + (f" and {len(differ) - 3} more" if len(differ) > 3 else "")
    verb = "differs from the published file" if len(differ) == 1 else "differ from the published files"
    if same:
        return f"the published data modified: {files} {verb}"
    return f"not the published data: {files} {verb}"


def check_words(words: str) -> str:
    """``words`` if it names an experiment table (:data:`WORD_FILES`), else :class:`DataError`."""
    if words not in WORD_FILES:
        raise DataError(f"unknown words option {words!r}; allowed: {', '.join(WORD_FILES)}")
    return words


def resolve_data(data: str | os.PathLike | None = None) -> DataSource:
    """Choose the data source: ``data`` if given, else ``$GLU_DATA_DIR``, else the fetched data, else
    synthetic.

    The fetched data is :data:`glu.paths.REAL_DATA_DIR` (``data/real/`` in a checkout, the user's data
    folder when installed).

    ``data`` may be a folder or the word ``synthetic`` (force the built-in synthetic data).
    """
    given, origin = data, "--data"
    if data is None:  # an empty $GLU_DATA_DIR is no folder
        given, origin = os.environ.get(paths.DATA_ENV_VAR) or None, "GLU_DATA_DIR"
    if given is not None:
        if str(given) == SYNTHETIC_KEYWORD:
            return DataSource(kind="synthetic", root=None, origin=origin)
        return _folder_source(Path(given), origin)
    if (paths.REAL_DATA_DIR / WORD_FILES["lab"]).is_file():
        return _folder_source(paths.REAL_DATA_DIR, "data/real")
    return DataSource(kind="synthetic", root=None, origin="default")


def _folder_source(root: Path, origin: str) -> DataSource:
    where = f"${paths.DATA_ENV_VAR}" if origin == "GLU_DATA_DIR" else origin
    if not root.is_dir():
        raise DataError(
            f"{root}: no such data folder (given by {where}); expected a folder with affordance-words/, "
            "gestures/, reference-models/ (see `glu data fetch`), or the word 'synthetic'"
        )
    if not (root / "affordance-words").is_dir() and not (root / "gestures").is_dir():
        raise DataError(
            f"{root}: not a glu data folder (given by {where}): it has neither affordance-words/ nor "
            "gestures/"
        )
    marker = root / SYNTHETIC_MARKER
    from glu.data.fetch import published_check, published_origin

    # the checksums decide: a stray marker cannot relabel the published data
    if marker.is_file() and published_origin(root) is None:
        try:
            info = json.loads(marker.read_text())
            return DataSource(
                kind="synthetic",
                root=root.resolve(),
                origin=origin,
                seed=int(info["seed"]),
                n_experiments=int(info["n"]),
            )
        except (ValueError, KeyError, TypeError):
            raise DataError(f"{marker}: malformed marker file; expected JSON with 'seed' and 'n'") from None
    source = DataSource(kind="real", root=root.resolve(), origin=origin)
    if published_check(root)[1]:  # said where the results go (describe) and once to the person (a warning)
        import warnings

        warnings.warn(DataWarning(f"{root}: {modified_text(root)}"), stacklevel=3)
    return source


def load_schema(source: DataSource) -> Schema:
    """The schema of a source: its ``networkDefinition.txt`` if it has one, else the default schema."""
    definition = source.network_definition()
    if definition is not None:
        from glu.data.tables import read_network_definition

        schema = read_network_definition(definition)
        if tuple(schema.nodes) != default_schema().nodes:
            raise DataError(
                f"{definition}: nodes differ from the model's 8 affordance nodes "
                "and 49 words (or are in another order)"
            )
        return schema
    return default_schema()


def load_experiments(data: DataSource | str | os.PathLike | None = None, words: str = "lab") -> pd.DataFrame:
    """Load the robot experiments of a source as a validated DataFrame of categorical columns.

    Parameters
    ----------
    data : a :class:`DataSource`, a folder, ``"synthetic"``, or None (resolve as :func:`resolve_data`)
    words : ``"lab"`` (transcribed descriptions, the paper's) or ``"asr"`` (speech-recogniser output)

    Returns
    -------
    DataFrame, shape (n_experiments, 57); ``df.attrs["data_source"]`` says where it came from.
    """
    check_words(words)
    source = data if isinstance(data, DataSource) else resolve_data(data)
    if source.root is None:
        from glu.data.synthetic import ASR_NOISE, synthesize_experiments

        df = synthesize_experiments(
            source.n_experiments, source.seed, asr_noise=ASR_NOISE if words == "asr" else 0.0
        )
    else:
        from glu.data.tables import read_experiments

        df = read_experiments(source.experiments_file(words), load_schema(source))
    df.attrs["data_source"] = source.describe() + f", words={words}"
    return df
