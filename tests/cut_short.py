"""Writes cut short in the middle, for the tests of sets of files that a reader takes as one whole (tables and
the key or provenance file that vouches for them, :func:`glu.files.marked_set`): after a rewrite of a complete
set fails half-way, the reader must give the old set whole or refuse the folder in one line, never a mix."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

import pytest

from glu.errors import GluError


@contextmanager
def cut_short(
    owner: Any, name: str, at: int = 2, error: type[BaseException] = KeyboardInterrupt, caught: bool = False
) -> Iterator[None]:
    """Within the block, the ``at``-th call of ``owner.name`` (a writer: ``pd.DataFrame.to_parquet``, a
    module's ``atomic_write_json``) raises ``error`` (an interrupt, a full disk) instead of writing; the
    block must end with that error, which is caught here (``caught``: the block catches it itself, as the
    command line does, and must only have reached that call)."""
    original = getattr(owner, name)
    calls: list[int] = []

    def write(*args: Any, **kwargs: Any) -> Any:
        calls.append(1)
        if len(calls) == at:
            raise error(f"cut short at call {at} of {name}")
        return original(*args, **kwargs)

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(owner, name, write)
        if caught:
            yield
        else:
            with pytest.raises(error, match="cut short"):
                yield
    assert len(calls) >= at, f"{name} was called {len(calls)} times, never cut short"


def old_or_refused(read: Callable[[], Any], is_old: Callable[[Any], bool]) -> str | None:
    """What a reader makes of a set whose rewrite was cut short: its one-line refusal (a :class:`GluError`,
    returned), or the old set whole (None); a mix of the old set and the new one fails the test."""
    try:
        got = read()
    except GluError as e:
        assert "\n" not in str(e), str(e)
        return str(e)
    assert is_old(got), "the reader took new files beside old ones for one set"
    return None
