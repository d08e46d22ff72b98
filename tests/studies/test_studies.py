"""What the studies declare to the runner (glu.studies): the notebooks' parameter choices, merged."""

from __future__ import annotations

import importlib

from glu.studies import STUDIES, parameter_choices


def test_studies_that_share_a_parameter_agree_on_its_choices():
    """A parameter name means the same thing in every notebook: the studies declaring it allow the same values
    (feature_sets is shared by notebooks 10 and 11), and the merged choices are each study's."""
    declared: dict[str, dict[str, tuple[str, ...]]] = {}
    for name in STUDIES:
        study = importlib.import_module(f"glu.studies.{name}")
        for param, allowed in getattr(study, "parameter_choices", dict)().items():
            declared.setdefault(param, {})[name] = tuple(allowed)
    assert set(declared["feature_sets"]) == {"correspondence", "corpus_evaluation"}
    for param, by_study in declared.items():
        assert len(set(by_study.values())) == 1, (param, by_study)
    assert parameter_choices() == {p: next(iter(v.values())) for p, v in declared.items()}
