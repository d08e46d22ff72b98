"""The synthetic study of notebook 10 as a grid: its settings, run per seed (on Dask if asked), its tables
saved and found again (:mod:`glu.saved`).

The study (:func:`glu.studies.correspondence.experiment.correspondence_study`) trains a recogniser for every
seed, training source and feature set and recognises every condition's test gestures: a minute of CPU with
the notebook's defaults. :func:`study_tables` returns its three tables — the per-seed outcomes, the summary
with two-level intervals, the invariances' paired effects with adjusted verdicts — from the tables saved in
``sweeps/10_correspondence/`` when the settings are the notebook's defaults (``make sweeps`` regenerates
them: ``glu correspondence -o sweeps/10_correspondence/study``), else computes them once, one task
per seed (:func:`glu.machine.map_tasks`), into the cache, and reuses them after. The study draws synthetic
people only: its tables do not depend on the data folder.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import Any, NamedTuple

import pandas as pd

from glu.errors import DataError
from glu.files import atomic_path, marked_set
from glu.machine import map_tasks
from glu.saved import KEY_FILE, cache_folder, cache_key, find, write_key
from glu.studies.correspondence.experiment import (
    FEATURE_SETS,
    STUDY_FEATURE_NAMES,
    STUDY_TRAINING,
    correspondence_study,
    default_conditions,
    invariance_effects,
    summarise,
)
from glu.tidy import tidy

NOTEBOOK = "10_correspondence"
"""The notebook whose saved tables live in ``sweeps/10_correspondence/``."""
FORMAT = ("glu-correspondence", 1)
"""The saved tables' format (part of their key)."""
TABLES: tuple[str, ...] = (
    "correspondence_study",
    "correspondence_summary",
    "correspondence_invariance_effects",
)
"""The tables the study saves and notebook 10 shows: the per-seed outcomes, their summary, the invariances'
effects."""


@dataclass(frozen=True)
class StudySettings:
    """Everything the synthetic study's tables depend on (notebook 10's parameters of the same names), each
    checked when the settings are made (:class:`~glu.errors.DataError`, one line naming it)."""

    seeds: tuple[int, ...] = tuple(range(10))
    n_train: int = 8
    n_test: int = 6
    feature_sets: tuple[str, ...] = FEATURE_SETS
    yaws: tuple[float, ...] = (0, 45, 90, 135, 180)
    variety: float = 1.0
    n_states: int = 6
    n_mix: int = 1
    n_iter: int = 50
    bootstrap: int = 1000
    levels: tuple[str, ...] | None = None
    normalise_body: bool = False

    def __post_init__(self) -> None:
        def refuse(name: str, must: str) -> DataError:
            return DataError(f"{name}={getattr(self, name)!r}: {must}")

        def whole(v: Any, lo: int) -> bool:
            return isinstance(v, int) and not isinstance(v, bool) and v >= lo

        def number(v: Any) -> bool:
            return isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)

        lists = {
            "seeds": (lambda k: whole(k, 0), "whole numbers ≥ 0"),
            "feature_sets": (lambda f: isinstance(f, str), "feature sets"),
            "yaws": (number, "turns in degrees (finite numbers)"),
        }
        for name, (ok, what) in lists.items():
            v = getattr(self, name)
            if not isinstance(v, tuple) or not v or not all(map(ok, v)) or len(set(v)) != len(v):
                raise refuse(name, f"a list of {what}, at least one, each once")
        unknown = [f for f in self.feature_sets if f not in STUDY_FEATURE_NAMES]
        if unknown:
            allowed = ", ".join(STUDY_FEATURE_NAMES)
            raise refuse("feature_sets", f"unknown feature set {unknown[0]!r}; allowed: {allowed}")
        for name in ("n_train", "n_test", "n_states", "n_mix", "n_iter"):
            if not whole(getattr(self, name), 1):
                raise refuse(name, "a whole number ≥ 1")
        if not whole(self.bootstrap, 0):
            raise refuse("bootstrap", "a whole number of replicates ≥ 0")
        if not number(self.variety) or self.variety < 0:
            raise refuse("variety", "a number ≥ 0")
        if not isinstance(self.normalise_body, bool):
            raise refuse("normalise_body", "True or False")
        if self.levels is not None:
            if not isinstance(self.levels, tuple) or not self.levels:
                raise refuse("levels", "None (every condition) or a list of the conditions' levels")
            conds = default_conditions(self.normalise_body, yaws=self.yaws, variety=self.variety)
            known = list(dict.fromkeys(c.level for c in conds))
            unknown = [lv for lv in self.levels if lv not in known]
            if unknown:
                allowed = ", ".join(map(repr, known))
                raise refuse("levels", f"unknown level {unknown[0]!r}; allowed: {allowed}")

    def key(self) -> dict[str, Any]:
        """The key of the saved tables (:mod:`glu.saved`): the format and every setting."""
        return {"format": list(FORMAT), "settings": json.loads(json.dumps(asdict(self)))}

    def conditions(self) -> list[Any]:
        """The test conditions (:func:`default_conditions`), those of :attr:`levels` if given."""
        conds = default_conditions(self.normalise_body, yaws=self.yaws, variety=self.variety)
        return conds if self.levels is None else [c for c in conds if c.level in self.levels]


def settings_from_parameters(params: Mapping[str, Any]) -> StudySettings:
    """The study's settings from notebook 10's parameters (its cell's names, which are the fields'; a list
    becomes a tuple; other names in ``params`` are ignored): one call instead of the fields one by one, the
    values checked as :class:`StudySettings` checks them."""
    given = {f.name: params[f.name] for f in fields(StudySettings) if f.name in params}
    return StudySettings(**{k: tuple(v) if isinstance(v, list) else v for k, v in given.items()})


class StudyTables(NamedTuple):
    """The study's tables and the folder they were read from."""

    results: pd.DataFrame
    summary: pd.DataFrame
    effects: pd.DataFrame
    folder: Path


def _one_seed(seed: int, settings: StudySettings) -> pd.DataFrame:
    config = STUDY_TRAINING.replace(n_states=settings.n_states, n_mix=settings.n_mix, n_iter=settings.n_iter)
    return correspondence_study(
        feature_sets=settings.feature_sets,
        conditions=settings.conditions(),
        seeds=[seed],
        n_train=settings.n_train,
        n_test=settings.n_test,
        normalise_body=settings.normalise_body,
        config=config,
    )


def run_study(settings: StudySettings, workers: int = 0) -> tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame]:
    """The study's per-seed outcomes, one task per seed (in this process, or on a LocalCluster of
    ``workers``), then the summary and the invariances' effects (:data:`TABLES`)."""
    parts = map_tasks(_one_seed, list(settings.seeds), settings, workers=workers)
    results = pd.concat(parts, ignore_index=True)
    attrs = dict(parts[0].attrs)
    attrs["parameters"] = {**attrs.get("parameters", {}), "seeds": list(settings.seeds)}
    results = tidy(
        results, attrs.get("experiment", TABLES[0]), attrs.get("data_source", ""), **attrs["parameters"]
    )
    return results, summarise(results, settings.bootstrap), invariance_effects(results, settings.bootstrap)


def write_tables(folder: Path, tables: tuple[pd.DataFrame, ...], key: dict[str, Any], command: str) -> Path:
    """The tables as Parquet (zstd) in ``folder``, their stamps and the key in its key file.

    The tables and the key file are one set (:func:`glu.files.marked_set`): the key file is removed first
    and written last, each table through a temporary file, so an error or an interrupt while an existing
    folder is rewritten leaves one that :func:`read_tables` refuses and :func:`glu.saved.find` passes by,
    never new tables under the old key. Other files in ``folder`` are left as they are."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    stamps = {}
    with marked_set(folder, KEY_FILE):
        for name, df in zip(TABLES, tables, strict=True):
            stamps[name] = json.loads(json.dumps(df.attrs, default=str))
            plain = df.copy()
            plain.attrs = {}
            with atomic_path(folder / f"{name}.parquet", suffix=".parquet") as tmp:
                plain.to_parquet(tmp, index=False, compression="zstd")
        write_key(folder, key, command, stamps=stamps)
    return folder


def read_tables(folder: str | Path) -> StudyTables:
    """The tables :func:`write_tables` saved in ``folder``, stamped again."""
    folder = Path(folder)
    try:
        doc = json.loads((folder / KEY_FILE).read_text(encoding="utf-8"))
        frames = [pd.read_parquet(folder / f"{name}.parquet") for name in TABLES]
    except (OSError, ValueError) as e:
        raise DataError(f"{folder}: not a folder of saved correspondence tables ({e})") from None
    for name, df in zip(TABLES, frames, strict=True):
        stamp = doc.get("stamps", {}).get(name, {})
        tidy(df, stamp.get("experiment", name), stamp.get("data_source", ""), **stamp.get("parameters", {}))
    return StudyTables(*frames, folder)


def study_tables(
    settings: StudySettings, workers: int = 0, log: Callable[[str], None] = lambda s: None
) -> StudyTables:
    """The study's tables: saved ones with the same key, else computed now into the cache and kept there."""
    key = settings.key()
    found = find(NOTEBOOK, key)
    if found is not None:
        return read_tables(found)
    folder = cache_folder(NOTEBOOK, key)
    log(f"no saved tables for these settings: running the study into {folder}")
    write_tables(
        folder, run_study(settings, workers), cache_key(key), f"glu run {NOTEBOOK} with these parameters"
    )
    return read_tables(folder)
