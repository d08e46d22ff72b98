"""The gesture recordings of the real data: which action each shows, and the originals' segments of them.

The published data (docs/method.md §4.1) holds six YARP hand logs of one person: four training recordings with
several repetitions of one gesture each, and two single taps, towards a small sphere and a big box, that
the originals cut by hand for their test segments and the effect-anticipation figures. Synthetic data
folders (``glu data synth``) have recordings of the same names, with their gestures at the same frames.
"""

from __future__ import annotations

ORIGINAL_SEGMENTS: dict[str, tuple[tuple[int, int], ...]] = {
    "tap1_hand": ((216, 351), (401, 511), (557, 664)),
    "tap_notable_seated_1": ((121, 214),),
    "norobotview_tap_notable_seated_2": ((230, 375),),
}
"""The test segments of the originals (1-based, inclusive frames of the recording's hand log)."""

RECORDING_ACTION: dict[str, str] = {
    "grasp1_hand": "grasp",
    "tap1_hand": "tap",
    "touch1_hand": "touch",
    "push1_hand": "push",
    "tap_notable_seated_1": "tap",
    "norobotview_tap_notable_seated_2": "tap",
}
"""The action performed in each recording."""

TRAINING_RECORDINGS: tuple[str, ...] = ("grasp1_hand", "tap1_hand", "touch1_hand", "push1_hand")
"""The recordings with several repetitions of one gesture, segmented automatically for training."""
