"""The long runs of learning from effects, saved: what ``glu learning-curves`` writes and notebook 12 reads.

A run of 10 seeds × 10,000 episodes takes tens of CPU minutes, so the notebook does not redo it: ``glu
learning-curves`` (on Dask) writes every seed's raw measurements — which held-out gesture each learner
recognised at each checkpoint, the network alone, the labels' quality — with its settings and provenance
(:func:`save_study`), and the notebook reads them (:func:`load_study`), takes the seeds, learners and
budgets it asks for (:func:`select`), and computes every table from them as it would from its own run
(:mod:`glu.studies.learning.tables`). The same command also runs a small study with the same code — one
seed, the first budget, the ``mixed`` objects without words (:func:`check_settings`) — and saves it in
``check/``; the notebook recomputes that one here and compares which gestures every learner recognises
(:func:`check_against`): a saved run that the code no longer reproduces is refused. (The long run itself
cannot be recomputed in part: a run of more episodes is not a prefix of a shorter one.)

A source checkout holds such runs for the real data and for glu's synthetic data in
``sweeps/12_learning_from_effects/real/`` and ``synthetic/`` (:func:`default_folder`, chosen by the data
source, which must be the one they were made from); they hold numbers glu computed — which held-out gesture
each learner recognised —, not the data. Another data folder or other settings: run ``glu learning-curves …
-o DIR`` and give the notebook ``saved=DIR``. The folder:

* ``learning_study.json`` — the settings, the data source, the learners, groups, checkpoints and seeds, the
  time of one update, and how it was made (the command, glu's version, the commit, the date);
* ``learning_results.npz`` — the measurements (bits: a learner recognised a held-out gesture or not);
* ``learning_curves.csv``, ``learning_budgets.csv``, ``learning_claims.csv``, ``learning_labels.csv`` —
  the tables, for reading (the notebook recomputes them);
* ``check/`` — the small check run, in the same two files;
* for the real data, ``learning_real_person.csv.gz`` and ``learning_real_person.json`` — every draw's
  predictions of the real-person study (:mod:`glu.studies.learning.real_person`) and their provenance
  (:func:`save_real_person`, :func:`load_real_person`), and ``learning_real_person_summary.csv``.

Each of the two is one set of files vouched for by its JSON file (:func:`glu.files.marked_set`): removed
before the others are rewritten and written last, so a run cut short leaves the old set whole or a folder
the reader refuses in one line, never new measurements (or a new check run) under the old provenance.
"""

from __future__ import annotations

import datetime
import gzip
import io
import json
import os
from collections.abc import Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from glu.errors import DataError
from glu.files import atomic_write_bytes, atomic_write_json, atomic_write_text, marked_set
from glu.hmm import TrainingConfig
from glu.studies.learning.online import OnlineSettings
from glu.studies.learning.real_person import RealPersonSettings
from glu.studies.learning.study import SeedResult, StudySettings
from glu.tidy import tidy

NOTEBOOK = "12_learning_from_effects"
"""The notebook whose saved runs these are (``sweeps/<notebook>/`` of a checkout, :mod:`glu.saved`)."""
STUDY_FILE, RESULTS_FILE = "learning_study.json", "learning_results.npz"
PERSON_FILE, PERSON_STUDY_FILE = "learning_real_person.csv.gz", "learning_real_person.json"
PERSON_SUMMARY_FILE = "learning_real_person_summary.csv"
"""The real-person study's summary, for reading (:func:`save_real_person` writes it with the rows)."""
FORMAT = 1
"""The version of the saved layout."""
SAME: tuple[str, ...] = ("test_per_action", "effects", "online")
"""Settings a saved run must share with the study that reads it (the others it may hold more of)."""


def default_folder(real: bool) -> Path:
    """The saved run committed for the real data or for glu's synthetic data: ``real/`` or ``synthetic/`` in
    ``sweeps/12_learning_from_effects/`` of a checkout (:class:`DataError` in an installed glu, which has
    none: make a run with ``glu learning-curves -o DIR`` and give the notebook ``saved=DIR``)."""
    from glu.saved import roots

    places = roots(NOTEBOOK)
    if not places:
        raise DataError(
            "the saved runs of learning from effects are in a source checkout of glu (sweeps/); make one "
            "with `glu learning-curves … -o DIR` and give notebook 12 saved=DIR"
        )
    return places[0] / ("real" if real else "synthetic")


def settings_from_dict(d: dict[str, Any], kind: type = StudySettings) -> Any:
    """:class:`StudySettings` (or ``kind``) from its ``as_dict()`` (read back from JSON)."""
    d = dict(d)
    online = dict(d.pop("online"))
    online["config"] = TrainingConfig(**online["config"])
    tuples = {k: tuple(v) for k, v in d.items() if isinstance(v, list)}
    return kind(**{**d, **tuples, "online": OnlineSettings(**online)})


def _made_by(command: str) -> dict[str, Any]:
    """How a run was made: the command, glu's version, the commit and whether the tree had changes
    (:func:`glu.saved.made_with`), the date."""
    from glu.saved import made_with

    return {
        "command": command,
        **made_with(),
        "date": datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC"),
    }


def save_study(
    folder: str | os.PathLike,
    results: Sequence[SeedResult],
    settings: StudySettings,
    data_source: str,
    command: str,
    update_seconds: dict[str, float] | None = None,
    *,
    check: tuple[Sequence[SeedResult], StudySettings] | None = None,
    tables: Mapping[str, pd.DataFrame] | None = None,
) -> Path:
    """Write a run's measurements and provenance into ``folder`` (see the module docstring), with its check
    run (``check``: its results and :func:`check_settings`) in ``check/`` and ``tables`` (name → frame) as
    ``NAME.csv`` for reading; returns the study file.

    They are one set, vouched for by the study file (:func:`glu.files.marked_set`): it is removed before
    anything is written and written last, every file through a temporary one, so an error or an interrupt
    while an existing run is rewritten leaves a folder :func:`load_study` refuses in one line — never new
    measurements, or a new check run, under the old study file. Other files in ``folder`` (the real-person
    study's, the user's own) are left as they are."""
    folder = Path(folder)
    first = results[0]
    correct = np.stack([r.correct for r in results])  # (S, C, L, J)
    network = np.stack([r.network_correct for r in results])  # (S, G, J)
    buf = io.BytesIO()
    np.savez_compressed(
        buf,
        correct=np.packbits(correct, axis=-1),
        network=np.packbits(network, axis=-1),
        labels=np.stack([r.labels for r in results]),
        tests=np.array(correct.shape[-1]),
    )
    study = {
        "format": FORMAT,
        "settings": json.loads(json.dumps(settings.as_dict(), default=str)),
        "data_source": data_source,
        "seeds": [int(r.seed) for r in results],
        "learners": [list(lr) for lr in first.learners],
        "groups": [list(g) for g in first.groups],
        "checkpoints": [int(c) for c in first.checkpoints],
        "update_seconds": update_seconds or {},
        "made_by": _made_by(command),
    }
    with marked_set(folder, STUDY_FILE):
        for name, df in (tables or {}).items():
            atomic_write_text(folder / f"{name}.csv", df.to_csv(index=False))
        if check is not None:
            save_study(folder / CHECK_FOLDER, *check, data_source, command)
        atomic_write_bytes(folder / RESULTS_FILE, buf.getvalue())
        return atomic_write_json(folder / STUDY_FILE, study)


def _read(folder: Path, what: str, part: str, read) -> Any:
    """``read()``, its missing or unreadable files said in one line (:class:`DataError`)."""
    try:
        return read()
    except FileNotFoundError as e:
        raise DataError(
            f"{folder}: no saved {what} ({Path(e.filename).name} missing); "
            f"`glu learning-curves {part}-o DIR` writes one"
        ) from None
    except (OSError, ValueError, KeyError) as e:
        raise DataError(f"{folder}: not a readable saved {what} ({e})") from None


def load_study(folder: str | os.PathLike) -> tuple[StudySettings, list[SeedResult], dict[str, Any]]:
    """A saved run: its settings, every seed's measurements and its provenance (the study file's content)."""
    folder = Path(folder)

    def read():
        with np.load(folder / RESULTS_FILE) as npz:
            return json.loads((folder / STUDY_FILE).read_text(encoding="utf-8")), {
                k: npz[k] for k in npz.files
            }

    meta, arrays = _read(folder, "run of learning from effects", "", read)
    if meta.get("format") != FORMAT:
        raise DataError(f"{folder}: saved in format {meta.get('format')!r}, glu reads {FORMAT}; run it again")
    J = int(arrays["tests"])
    correct = np.unpackbits(arrays["correct"], axis=-1, count=J).astype(bool)
    network = np.unpackbits(arrays["network"], axis=-1, count=J).astype(bool)
    learners = [(w, lr, a, None if words is None else bool(words)) for w, lr, a, words in meta["learners"]]
    groups = [(w, a, bool(words)) for w, a, words in meta["groups"]]
    results = [
        SeedResult(
            seed,
            learners,
            np.array(meta["checkpoints"]),
            correct[s],
            groups,
            network[s],
            arrays["labels"][s],
            np.zeros(0),
        )
        for s, seed in enumerate(meta["seeds"])
    ]
    return settings_from_dict(meta["settings"]), results, meta


def regenerate_command(settings: StudySettings, data: str = "DATA") -> str:
    """The ``glu learning-curves`` command that makes a saved run of these settings."""
    seeds = settings.seeds
    span = (
        f"{seeds[0]}..{seeds[-1]}"
        if list(seeds) == list(range(seeds[0], seeds[-1] + 1))
        else ",".join(map(str, seeds))
    )
    return (
        f"glu learning-curves --episodes {max(settings.main_budgets or (settings.episodes,))} --seeds {span} "
        f"--worlds {','.join(settings.worlds)} --ambiguities {','.join(settings.ambiguities)} "
        f"--test-per-action {settings.test_per_action} --data {data} -o DIR"
    )


def select(
    results: Sequence[SeedResult], saved: StudySettings, wanted: StudySettings, data_source: str, meta: dict
) -> list[SeedResult]:
    """The seeds, learners, groups and checkpoints of ``wanted`` out of a saved run; :class:`DataError`
    (with the command that makes the right run) when the saved run lacks some, or was made from other data
    or with other settings of :data:`SAME`."""
    fix = f"run `{regenerate_command(wanted)}` and give the notebook saved=DIR"
    if meta.get("data_source") != data_source:
        raise DataError(
            f"the saved run was made from {meta.get('data_source')!r}, not {data_source!r}: {fix}"
        )
    a, b = saved.as_dict(), wanted.as_dict()
    differ = [k for k in SAME if a[k] != b[k]]
    if differ:
        raise DataError(f"the saved run has other {', '.join(differ)} than asked: {fix}")
    by_seed = {r.seed: r for r in results}
    missing_seeds = [s for s in wanted.seeds if s not in by_seed]
    have_l = {tuple(lr): k for k, lr in enumerate(results[0].learners)}
    have_g = {tuple(g): k for k, g in enumerate(results[0].groups)}
    have_c = {int(c): k for k, c in enumerate(results[0].checkpoints)}
    groups = [(w, a, words) for w in wanted.worlds for a in wanted.ambiguities for words in wanted.words]
    lack = (
        [f"seed {s}" for s in missing_seeds]
        + [f"learner {lr}" for lr in wanted.learners() if tuple(lr) not in have_l]
        + [f"group {g}" for g in groups if g not in have_g]  # (a study of the baselines alone)
        + [f"{c} episodes" for c in wanted.checkpoints if c not in have_c]
    )
    if lack:
        raise DataError(f"the saved run lacks {', '.join(lack[:3])}{' …' if len(lack) > 3 else ''}: {fix}")
    li = [have_l[tuple(lr)] for lr in wanted.learners()]
    gi = [have_g[g] for g in groups]
    ci = [have_c[c] for c in wanted.checkpoints]
    out = []
    for s in wanted.seeds:
        r = by_seed[s]
        out.append(
            r._replace(
                learners=wanted.learners(),
                checkpoints=np.array(wanted.checkpoints),
                correct=r.correct[np.ix_(ci, li)],
                groups=[r.groups[g] for g in gi],
                network_correct=r.network_correct[gi],
                labels=r.labels[gi],
            )
        )
    return out


CHECK_FOLDER = "check"
"""The sub-folder of a saved run that holds its check run (:func:`check_settings`)."""


def check_settings(settings: StudySettings, seeds: Sequence[int] = (), episodes: int | None = None):
    """The small run a saved run carries for its check: the learners of the ``mixed`` ambiguity without
    words and the baselines, of ``seeds`` (default: the first seed) up to ``episodes`` (default: the first
    budget), with every other setting of ``settings``.

    A run of more episodes is not a prefix of a run of fewer (the episodes' objects and effects, and the
    random labels matched to the network's accuracy, are drawn for the whole run at once), so the long run
    cannot be recomputed in part: ``glu learning-curves`` runs this small study with the same code and saves
    it beside the long run, and the notebook recomputes it (:func:`check_against`)."""
    ambiguity = "mixed" if "mixed" in settings.ambiguities else settings.ambiguities[0]
    episodes = settings.main_budgets[0] if episodes is None else episodes
    return replace(
        settings,
        episodes=episodes,
        seeds=tuple(seeds) or settings.seeds[:1],
        ambiguities=(ambiguity,),
        words=(False,) if False in settings.words else settings.words[:1],
        budgets=(episodes,),
    )


def check_against(engine, folder: str | os.PathLike, seeds: Sequence[int]) -> dict[str, Any]:
    """Recompute, here, the check run saved in ``folder`` (:func:`check_settings`) for ``seeds`` and compare
    which held-out gestures every learner recognises at every checkpoint with the saved ones.

    Returns ``{"seeds", "episodes", "learners", "decisions", "differ"}``: how many held-out decisions were
    compared and how many differ. Raises :class:`DataError` when the folder has no check run of those seeds,
    or when more than 1 % of the decisions differ (the saved run is not what this code computes: run it
    again; a few may differ on another machine, where floating-point sums round otherwise)."""
    from glu.studies.learning.study import learning_study

    folder = Path(folder)
    small, saved, meta = load_study(folder / CHECK_FOLDER)
    again = (meta.get("made_by") or {}).get("command") or regenerate_command(small)
    missing = [s for s in seeds if s not in small.seeds]
    if missing:
        raise DataError(
            f"{folder}: its check run holds seeds {list(small.seeds)}, not {missing}; give the notebook "
            f"check_seeds from those (or [] to skip the check)"
        )
    by_seed = {r.seed: r for r in saved}
    here = learning_study(engine, replace(small, seeds=tuple(seeds)))
    compared = differ = 0
    for r in here:
        there = by_seed[r.seed]
        if r.learners != there.learners or list(r.checkpoints) != list(there.checkpoints):
            raise DataError(
                f"{folder}: the saved check run has other learners or checkpoints than this code makes; "
                f"run `{again}` again"
            )
        compared += r.correct.size
        differ += int((r.correct != there.correct).sum())
    out = {
        "seeds": list(seeds),
        "episodes": small.episodes,
        "learners": len(small.learners()),
        "decisions": compared,
        "differ": differ,
    }
    if differ > 0.01 * compared:
        raise DataError(
            f"the saved run is not what this code computes: {differ} of {compared} held-out decisions of "
            f"seeds {list(seeds)} up to {small.episodes} episodes differ; run `{again}` again"
        )
    return out


def save_real_person(
    folder: str | os.PathLike,
    rows: pd.DataFrame,
    settings: RealPersonSettings,
    data_source: str,
    command: str,
    summary: pd.DataFrame | None = None,
) -> Path:
    """Write the real-person study's rows (gzip, byte for byte the same for the same rows), their
    ``summary`` (:func:`~glu.studies.learning.real_person.real_person_summary`, if given, as
    :data:`PERSON_SUMMARY_FILE` for reading) and their provenance into ``folder``; returns the provenance
    file.

    They are one set, vouched for by the provenance file (:func:`glu.files.marked_set`): it is removed
    first and written last, so an error or an interrupt while an existing study is rewritten leaves a folder
    :func:`load_real_person` refuses in one line, never new rows under the old provenance. Other files in
    ``folder`` (the run of learning curves, the user's own) are left as they are."""
    folder = Path(folder)
    text = rows.to_csv(index=False).encode("utf-8")
    provenance = {
        "format": FORMAT,
        "settings": json.loads(json.dumps(settings.as_dict(), default=str)),
        "data_source": data_source,
        "made_by": _made_by(command),
    }
    with marked_set(folder, PERSON_STUDY_FILE):
        atomic_write_bytes(folder / PERSON_FILE, gzip.compress(text, mtime=0))
        if summary is not None:
            atomic_write_text(folder / PERSON_SUMMARY_FILE, summary.to_csv(index=False))
        return atomic_write_json(folder / PERSON_STUDY_FILE, provenance)


def load_real_person(folder: str | os.PathLike, data_source: str) -> tuple[pd.DataFrame, dict[str, Any]]:
    """The real-person study's rows saved in ``folder`` (stamped as
    :func:`~glu.studies.learning.real_person.real_person_study` stamps them) and their provenance;
    :class:`DataError` when they are missing or were made from other data."""
    folder = Path(folder)

    def read():
        meta = json.loads((folder / PERSON_STUDY_FILE).read_text(encoding="utf-8"))
        return meta, pd.read_csv(folder / PERSON_FILE, keep_default_na=False, na_values=[""])

    meta, rows = _read(folder, "real-person study", "--part real-person ", read)
    if meta.get("data_source") != data_source:
        raise DataError(
            f"the saved real-person study was made from {meta.get('data_source')!r}, not {data_source!r}: "
            "run `glu learning-curves --part real-person --data DATA -o DIR` and give the notebook saved=DIR"
        )
    rows["predicted"] = rows["predicted"].astype(object).where(rows["predicted"].notna(), None)
    settings = settings_from_dict(meta["settings"], RealPersonSettings)
    return tidy(rows, "learning_real_person", data_source, **settings.as_dict()), meta


SHIPPED, HERE = "shipped", "none"
"""The notebook's ``saved`` values: glu's run for this data, or no saved run (everything computed here)."""


def study_results(
    engine,
    settings: StudySettings,
    saved: str | os.PathLike,
    data_source: str,
    real: bool,
    check_seeds: Sequence[int] = (0,),
) -> tuple[list[SeedResult], dict[str, Any]]:
    """The seeds' results the notebook's tables are computed from, and where they come from.

    ``saved``: :data:`HERE` runs the study here (:func:`~glu.studies.learning.study.learning_study`);
    :data:`SHIPPED` reads glu's saved run for this data (:func:`default_folder`), any other value the
    folder of a ``glu learning-curves`` run. A saved run is narrowed to ``settings`` (:func:`select`) and
    checked against this code on ``check_seeds`` up to the first budget (:func:`check_against`). The second
    value says where the results come from: ``{"folder", "made_by", "check"}`` (folder None: computed here).
    """
    from glu.studies.learning.study import learning_study

    if str(saved) == HERE:
        return learning_study(engine, settings), {"folder": None, "made_by": None, "check": None}
    folder = default_folder(real) if str(saved) == SHIPPED else Path(saved)
    stored, results, meta = load_study(folder)
    chosen = select(results, stored, settings, data_source, meta)
    check = check_against(engine, folder, check_seeds) if check_seeds else None
    where = f"glu's saved run for this data ({folder.name})" if str(saved) == SHIPPED else str(folder)
    return chosen, {"folder": where, "made_by": meta.get("made_by"), "check": check}


def provenance_line(where: dict[str, Any], what: str = "budgets") -> str:
    """One sentence saying where the results (``what``, plural: "budgets", "real-person draws") come from and
    how they were checked (:func:`study_results`, :func:`real_person_rows`)."""
    if where["folder"] is None:
        return f"Every {what.removesuffix('s')} was computed here."
    m = where["made_by"] or {}
    text = (
        f"The {what} come from {where['folder']}, made by `{m.get('command', '?')}` on {m.get('date', '?')} "
        f"(glu {m.get('glu', '?')}{', commit ' + m['commit'][:12] if m.get('commit') else ''}"
        f"{' with changes' if m.get('dirty') else ''})."
    )
    c = where["check"]
    if c:
        text += (
            f" Recomputed here: seeds {', '.join(map(str, c['seeds']))}, {c['learners']} learners of each "
            f"world after {c['episodes']:,} episodes recognise the held-out gestures as saved in "
            f"{c['decisions'] - c['differ']:,} of {c['decisions']:,} decisions."
        )
    return text


def real_person_rows(
    engine, source, settings: RealPersonSettings, saved: str | os.PathLike, data_source: str
) -> tuple[pd.DataFrame, dict[str, Any]]:
    """The real-person study's rows: run here (``saved`` :data:`HERE`) or read from glu's saved run
    (:data:`SHIPPED`) or a folder, which must hold the same settings; and where they come from."""
    from glu.gestures.corpus import gesture_sequences
    from glu.studies.learning.real_person import real_person_study

    if str(saved) == HERE:
        standing = gesture_sequences(source, include_test=False)
        rows = real_person_study(engine, standing, settings, data_source=data_source)
        return rows, {"folder": None, "made_by": None, "check": None}
    folder = default_folder(True) if str(saved) == SHIPPED else Path(saved)
    rows, meta = load_real_person(folder, data_source)
    if meta["settings"] != json.loads(json.dumps(settings.as_dict(), default=str)):
        raise DataError(
            f"{folder}: the saved real-person study has other settings than asked; run `glu learning-curves "
            "--part real-person --data DATA -o DIR` with them and give the notebook saved=DIR"
        )
    where = f"glu's saved run for this data ({folder.name})" if str(saved) == SHIPPED else str(folder)
    return rows, {"folder": where, "made_by": meta.get("made_by"), "check": None}
