"""The layout of a data folder: where each file of the real data (or its synthetic look-alike) lives.

A data folder (``glu data fetch``, ``--data DIR``) holds the authors' files under these relative paths;
:class:`glu.data.source.DataSource` reads them, :func:`glu.data.synthetic.write_synthetic_folder` writes a
synthetic folder of the same shape.
"""

from __future__ import annotations

from glu.data.hand_logs import FILE_NAME

WORD_FILES: dict[str, str] = {
    "lab": "affordance-words/sent-1-5_lab_aff_bag.txt",
    "asr": "affordance-words/sent-all_mllr3_aff_bag.txt",
}
"""``words`` option → experiment table (``lab``: transcriptions, the paper's; ``asr``: speech recogniser)."""
NETWORK_DEFINITION = "affordance-words/networkDefinition.txt"
GESTURES = "gestures"
HAND_LOG = FILE_NAME
ORIGINAL_BN = "reference-models/BN_lab.mat"
ORIGINAL_HMMS: dict[int, str] = {
    3: "reference-models/HMM_M3_Q6_mixsplit.mat",
    1: "reference-models/HMM_M1_Q6_mixsplit.mat",
}
"""Gaussians per state M → the originals' HMM file."""
SENTENCE_SAMPLES = "sentence-samples/sentence_10000samples_uniq.txt"
SYNTHETIC_MARKER = "SYNTHETIC.json"
SYNTHETIC_KEYWORD = "synthetic"
DEFAULT_SYNTHETIC_N = 1270
DEFAULT_SYNTHETIC_SEED = 0
