"""An evidence explorer for the notebooks: set hard and soft evidence, watch the posteriors and the words.

:func:`explore` is the computation — the fused posteriors of some target nodes given hard evidence on the
affordance nodes and, optionally, a gesture posterior p_HMM over Action entered by a soft rule, and the
best verbal descriptions — as plain tables. :func:`evidence_explorer` puts it in front of a reader: in a
live kernel (JupyterLab) a row of dropdowns (one per affordance node), three sliders for p_HMM(Action)
and the soft rule, with the tables updated at every change; headless (``glu reproduce``), or without
ipywidgets, the same tables for the starting evidence, as a static result.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from glu.bn.inference import Engine
from glu.bn.soft import SOFT_RULES
from glu.errors import GluError
from glu.fusion import ACTION, fuse
from glu.language.descriptions import describe
from glu.machine import is_live

NOT_OBSERVED = "—"


@dataclass(frozen=True)
class Exploration:
    """What the explorer shows: the posteriors (a tidy table) and the best descriptions."""

    posteriors: pd.DataFrame
    descriptions: pd.DataFrame
    evidence_text: str

    @property
    def table(self) -> pd.DataFrame:
        """The posteriors as a wide table: a row per node, a column per value."""
        return self.posteriors.pivot_table(index="node", columns="value", values="p", sort=False)

    def to_html(self) -> str:
        """Both tables as HTML, with the evidence above them."""
        return (
            f"<p><b>evidence:</b> {self.evidence_text}</p>"
            + self.table.to_html(float_format=lambda x: f"{x:.3f}", na_rep="")
            + self.descriptions[["sentence", "score"]].to_html(index=False, float_format=lambda x: f"{x:.4f}")
        )


def explore(
    engine: Engine,
    targets: Sequence[str] = ("ObjVel", ACTION),
    evidence: Mapping[str, str] | None = None,
    p_hmm: Sequence[float] | None = None,
    rule: str = "virtual",
    nbest: int = 3,
) -> Exploration:
    """Posteriors of ``targets`` and the ``nbest`` descriptions, given ``evidence`` and a gesture posterior.

    Raises :class:`glu.errors.GluError` for impossible or malformed evidence.

    Parameters
    ----------
    engine : the Affordance–Words network's inference engine
    targets : nodes whose posteriors are shown (observed ones are left out)
    evidence : hard evidence, node → value
    p_hmm : the gesture recogniser's posterior over Action, shape (K,) in the network's value order, or
        None for no gesture; ignored when Action itself is observed
    rule : how p_hmm enters the network, one of :data:`glu.bn.soft.SOFT_RULES`
    nbest : how many descriptions
    """
    evidence = dict(evidence or {})
    schema = engine.bn.schema
    gesture = None if p_hmm is None or ACTION in evidence else np.asarray(p_hmm, dtype=float)
    shown = [t for t in targets if t not in evidence]
    post = fuse(engine, shown, evidence, gesture, rule) if shown else {}
    rows = [
        {"node": node, "value": value, "p": float(p)}
        for node in shown
        for value, p in zip(schema.values_of(node), post[node], strict=True)
    ]
    soft = None
    if gesture is not None:
        soft = {ACTION: dict(zip(schema.values_of(ACTION), gesture.tolist(), strict=True))}
    words = describe(engine, evidence, soft, rule, n=nbest)
    text = ", ".join(f"{k}={v}" for k, v in evidence.items()) or "none"
    if gesture is not None:
        text += f"; p_HMM(Action) = ({', '.join(f'{p:.2f}' for p in gesture)}) by the {rule} rule"
    return Exploration(pd.DataFrame(rows, columns=["node", "value", "p"]), words, text)


def evidence_explorer(
    engine: Engine,
    targets: Sequence[str] = ("ObjVel", ACTION),
    evidence: Mapping[str, str] | None = None,
    p_hmm: Sequence[float] | None = None,
    rule: str = "virtual",
    nbest: int = 3,
    live: bool | None = None,
) -> Any:
    """An interactive explorer in a live kernel; otherwise the posteriors of the start as a static table.

    ``live`` forces either form (default: :func:`glu.machine.is_live`). The other arguments are the starting
    point, as :func:`explore`'s (declared again here, not read from its signature: Sphinx's autodoc replaces
    the defaults of a signature it documents in the process that builds the site).
    """
    first = explore(engine, targets, evidence, p_hmm, rule, nbest)
    if not is_live(live):
        return first.table
    try:
        import ipywidgets as w
    except ImportError:
        return first.table
    schema = engine.bn.schema
    evidence = dict(evidence or {})
    drops = {
        node: w.Dropdown(
            options=[NOT_OBSERVED, *schema.values_of(node)],
            value=evidence.get(node, NOT_OBSERVED),
            description=node,
            layout=w.Layout(width="210px"),
        )
        for node in schema.affordance_nodes
    }
    actions = schema.values_of(ACTION)
    start_p = list(p_hmm) if p_hmm is not None else [1.0 / len(actions)] * len(actions)
    use_gesture = w.Checkbox(value=p_hmm is not None, description="gesture evidence p_HMM(Action)")
    sliders = [
        w.FloatSlider(value=float(p), min=0.0, max=1.0, step=0.01, description=a)
        for a, p in zip(actions, start_p, strict=True)
    ]
    rule_pick = w.ToggleButtons(options=list(SOFT_RULES), value=rule, description="rule")
    view = w.HTML(first.to_html())

    def update(_change: Any = None) -> None:
        ev = {n: d.value for n, d in drops.items() if d.value != NOT_OBSERVED}
        weights = np.array([s.value for s in sliders])
        gesture = weights / weights.sum() if use_gesture.value and weights.sum() > 0 else None
        try:
            view.value = explore(engine, targets, ev, gesture, rule_pick.value, nbest).to_html()
        except GluError as e:
            view.value = f"<p><b>cannot answer:</b> {e}</p>"

    for control in (*drops.values(), use_gesture, *sliders, rule_pick):
        control.observe(update, names="value")
    box = w.VBox(
        [
            w.HBox(list(drops.values())[:4]),
            w.HBox(list(drops.values())[4:]),
            w.HBox([use_gesture, rule_pick]),
            w.HBox(sliders),
            view,
        ]
    )
    box.update = update  # type: ignore[attr-defined]  (tests call it; the widgets call it on change)
    box.controls = {"evidence": drops, "gesture": use_gesture, "sliders": sliders, "rule": rule_pick}  # type: ignore[attr-defined]
    box.view = view  # type: ignore[attr-defined]
    return box
