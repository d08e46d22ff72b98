"""What every experiment shares: the tidy frame it returns, stamped with where its numbers come from.

Each experiment function returns a tidy :class:`pandas.DataFrame` (one row per number behind a figure)
whose ``attrs`` say what it is, set here and nowhere else:

``experiment``
    the experiment's name (also the default name of its result table);
``data_source``
    which data the numbers come from (:meth:`glu.data.DataSource.describe`, a model's provenance, or a
    corpus's description);
``parameters``
    the settings that produced it (seeds, folds, rules, …), so a table can be rerun.

:class:`glu.run.outputs.Outputs` writes all three into the table's JSON file and ``results/summary.json``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import pandas as pd

from glu.evidence import format_evidence
from glu.hmm import TrainingConfig

UNKNOWN_SOURCE = "unknown data"


def tidy(df: pd.DataFrame, experiment: str, data_source: str, **parameters: Any) -> pd.DataFrame:
    """Stamp ``df`` with its experiment, data source and parameters (``df.attrs``); returns ``df``."""
    df.attrs["experiment"] = experiment
    df.attrs["data_source"] = str(data_source)
    df.attrs["parameters"] = {k: _plain(v) for k, v in parameters.items()}
    return df


def model_source(model: Any) -> str:
    """The data source recorded in a model's ``meta`` (a :class:`~glu.bn.BayesNet` or a recogniser)."""
    meta = getattr(model, "meta", None) or {}
    return str(meta.get("data_source") or meta.get("data") or UNKNOWN_SOURCE)


def corpus_source(sequences: Sequence[Any]) -> str:
    """The description of a gesture corpus (:class:`glu.gestures.corpus.Corpus`), if it has one."""
    return str(getattr(sequences, "description", "") or UNKNOWN_SOURCE)


def evidence_text(evidence: Mapping[str, Any]) -> str:
    """``{"Action": "grasp", "ObjVel": "slow"}`` → ``"Action=grasp, ObjVel=slow"``."""
    return format_evidence(evidence)


def training_parameters(config: TrainingConfig | None, features: Any = None) -> dict[str, Any]:
    """The training settings to stamp on a table: the fields of ``config`` that differ from glu's defaults,
    and the invariant features when given (``{}`` for the defaults on raw features)."""
    config = config or TrainingConfig()
    default = TrainingConfig()
    out = {k: v for k, v in config.as_dict().items() if v != getattr(default, k)}
    if features is not None:
        out["features"] = features
    return out


def _plain(v: Any) -> Any:
    """A parameter value as JSON-ready data (tuples → lists, mappings → dicts, settings objects → their
    name)."""
    if hasattr(v, "name") and hasattr(v, "to_dict"):  # e.g. gesture Invariants: "centred+rotated"
        return v.name
    if isinstance(v, Mapping):
        return {str(k): _plain(x) for k, x in v.items()}
    if isinstance(v, list | tuple):
        return [_plain(x) for x in v]
    if hasattr(v, "item") and callable(v.item):
        return v.item()
    return v
