"""The originals' 2013 gesture HMMs (Saponaro et al., CR-HRI 2013), imported from their ``.mat`` files.

``HMM_M3_Q6_mixsplit.mat`` (and the single-Gaussian ``HMM_M1_Q6_mixsplit.mat``) hold the variables
``hmm{k}_prior`` (Q), ``hmm{k}_trans`` (Q×Q), ``hmm{k}_mu`` (3×Q×M), ``hmm{k}_Sigma`` (3×3×Q×M) and
``hmm{k}_mixmat`` (Q×M) for k = 1 tap, 3 grasp, 4 push, 0 garbage (docs/method.md §4.4). There was no touch
model: the originals used push in its place, and so does :func:`load_original_hmms`. Their inputs are the
logged features / 1000 (:func:`glu.gestures.features.log_features`). Where the files are in a data folder
is :meth:`glu.data.DataSource.original_hmms`'s business.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from glu.errors import ModelError
from glu.hmm.model import GestureHMM
from glu.schema import ACTIONS

ORIGINAL_MODEL_INDEX: dict[str, int] = {"grasp": 3, "tap": 1, "touch": 4, "garbage": 0}
"""Variable index k of ``hmm{k}_*`` in the original .mat files. There was no touch model: the originals
used the push model (k = 4) in its place (docs/method.md §4.4)."""


def original_hmm(mat: Mapping[str, Any], k: int, name: str = "") -> GestureHMM:
    """Model ``hmm{k}`` of an original .mat file (as read by ``scipy.io.loadmat``, not squeezed).

    Reads ``hmm{k}_prior`` (Q), ``hmm{k}_trans`` (Q×Q), ``hmm{k}_mixmat`` (Q×M), ``hmm{k}_mu`` (D×Q×M, or
    D×Q when M = 1) and ``hmm{k}_Sigma`` (D×D×Q×M, or D×D×Q).
    """
    keys = [f"hmm{k}_{v}" for v in ("prior", "trans", "mixmat", "mu", "Sigma")]
    missing = [key for key in keys if key not in mat]
    if missing:
        found = sorted(x for x in mat if not x.startswith("__"))
        raise ModelError(f"model hmm{k}: missing {', '.join(missing)}; the file has {', '.join(found)}")
    prior, trans, mixmat, mu, sigma = (np.asarray(mat[key], dtype=float) for key in keys)
    prior = prior.reshape(-1)
    Q = len(prior)
    mixmat = mixmat.reshape(Q, -1)
    M = mixmat.shape[1]
    D = mu.shape[0]
    try:
        mu = mu.reshape(D, Q, M)
        sigma = sigma.reshape(D, D, Q, M)
    except ValueError:
        raise ModelError(
            f"model hmm{k}: mu {mu.shape} / Sigma {sigma.shape} do not fit Q={Q}, M={M}"
        ) from None
    means = np.transpose(mu, (1, 2, 0))  # (Q, M, D)
    covars = np.transpose(sigma, (2, 3, 0, 1))  # (Q, M, D, D)
    return GestureHMM(prior, trans, mixmat, means, covars, name=name)


def load_original_hmms(
    path: str | os.PathLike, actions: Sequence[str] = ACTIONS, include_garbage: bool = False
) -> dict[str, GestureHMM]:
    """The originals' 2013 HMMs by action: grasp (hmm3), tap (hmm1), touch (hmm4, the push model).

    ``path`` is ``HMM_M3_Q6_mixsplit.mat`` or ``HMM_M1_Q6_mixsplit.mat``; with ``include_garbage`` the
    garbage model (hmm0) is added as ``"garbage"``. Their inputs are the logged features / 1000.
    :func:`glu.gestures.recognizer.load_original_models` makes a recogniser of them.
    """
    from glu.matfile import MatFileError, read_mat

    path = Path(path)
    if not path.is_file():
        raise ModelError(f"{path}: no such file (expected an original HMM .mat file)")
    try:
        mat = read_mat(path)
    except MatFileError as e:
        raise ModelError(str(e)) from None
    except Exception as e:  # scipy raises several types for a damaged file
        raise ModelError(f"{path}: not a readable MATLAB file ({e})") from None
    names = list(actions) + (["garbage"] if include_garbage else [])
    models = {}
    for a in names:
        if a not in ORIGINAL_MODEL_INDEX:
            raise ModelError(f"no original model for {a!r}; allowed: {', '.join(ORIGINAL_MODEL_INDEX)}")
        try:
            models[a] = original_hmm(mat, ORIGINAL_MODEL_INDEX[a], name=a)
        except ModelError as e:
            raise ModelError(f"{path}: {e}") from None
    return models
