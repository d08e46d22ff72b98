"""Publishing a run all at once: complete runs kept in a store, and one pointer naming the published one.

``glu reproduce`` stages a whole run — figures, result tables, recordings, models, executed notebooks, the
summary and the documentation site — in a folder of its own in the output root's store, and publishes it by
pointing ``current`` at it with one atomic rename::

    OUT/.glu-runs/               the store (glu's own: it holds the file STORE)
        current -> r20250101-120000-3fa2c1     the published run (a symbolic link, swapped by one rename)
        r20250101-120000-3fa2c1/               figures/ results/ recordings/ models/ notebooks/ site/ RUN.json
        failed/                  executed copies of notebooks that failed (NAME.failed.ipynb)
        site-source/             Sphinx's sources and doctrees, kept so that the next build reads only changes
    OUT/figures -> .glu-runs/current/figures    each place of the output layout, a link made once
    OUT/results -> .glu-runs/current/results    …

A reader going through ``OUT/results/…`` or ``OUT/site/…`` therefore sees at every instant one whole run:
the previous one until the rename, the new one after it. A stop at any moment before the rename leaves the
previous publication as it was (the staging run is removed on the way out, or by the next start when the
process was killed); a stop after it leaves the new one published. Runs other than ``current`` whose owner
is gone are removed at the next start.

Nothing glu did not write is ever removed or replaced: a place of the layout is glu's when it is missing or
a link into the store; anything else there (a folder of the user's own, a file) makes the run refuse in one
line naming it before anything runs, or, with ``force``, is left untouched (the run is then published in the
store only). In the project's checkout the folders an earlier glu wrote before the store existed are
recognised by the earlier summary and the notebooks' manifests, and moved aside into the store.
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import secrets
import shutil
import time
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from glu.errors import GluError
from glu.files import atomic_write_text
from glu.paths import OUTPUT_KINDS, PROJECT_ROOT, OutputLayout
from glu.run.summary import previous_summary

MARKER = "STORE"
"""The file that makes a folder glu's store."""
CURRENT = "current"
"""The link naming the published run."""
RUN_RECORD = "RUN.json"
"""In a run folder: which notebook wrote each of its files (written before the run is published)."""
OWNER = "OWNER"
"""In a run folder being staged: the process id of the run that stages it."""
FAILED = "failed"
"""In the store: the executed copies of notebooks that failed."""
SITE_WORK = "site-source"
"""In the store: the site's sources and Sphinx's doctrees, kept from one build to the next."""
_RUN_NAME = re.compile(r"r\d{8}-\d{6}-[0-9a-f]{6}")

STEPS: tuple[str, ...] = ("staged", "site", "recorded", "pointer", "links", "cleaned")
"""The steps of a publication, in order (:data:`STEP_HOOK` hears each as it ends)."""
STEP_HOOK: Callable[[str], None] | None = None
"""Called with each step's name as it ends (the interrupt tests stop a run there)."""


class PublishError(GluError):
    """A place of the output layout holds what glu did not write, or the store is not glu's."""


def reached(name: str) -> None:
    """Tell :data:`STEP_HOOK` that the step ``name`` of a publication ended."""
    if STEP_HOOK is not None:
        STEP_HOOK(name)


def _first_file(folder: Path, known: Iterable[str] = ()) -> Path | None:
    """The first file (in name order) under ``folder`` but those directly in it named in ``known``, or None
    when there is none (only empty folders)."""
    known = set(known)
    for f in sorted(folder.rglob("*")):
        if (f.is_file() or f.is_symlink()) and (f.parent != folder or f.name not in known):
            return f
    return None


def _owned(run: Path) -> bool:
    """Whether the process whose id the run folder's :data:`OWNER` file holds is alive."""
    try:
        os.kill(int((run / OWNER).read_text().strip()), 0)
    except PermissionError:  # alive, another user's
        return True
    except (OSError, ValueError):  # no owner, or gone
        return False
    return True


def _run_folder(store: Path) -> Path:
    """A new run folder in the store (named by the time and a random part, :data:`_RUN_NAME`)."""
    while True:
        run = store / f"r{time.strftime('%Y%m%d-%H%M%S')}-{secrets.token_hex(3)}"
        with contextlib.suppress(FileExistsError):
            run.mkdir()
            return run


def _link_or_copy(src: Path, dest: Path) -> None:
    """Hard-link the file ``src`` at ``dest`` (its folder made), or copy it where links are refused."""
    dest.parent.mkdir(parents=True, exist_ok=True)
    try:
        os.link(src, dest)
    except OSError:
        shutil.copy2(src, dest)


def legacy_files(layout: OutputLayout, manifests: Mapping[str, Any] = {}) -> dict[str, set[str]]:  # noqa: B006
    """The files an earlier glu (before the store) wrote at the project's places, by kind: read from its
    ``results/summary.json`` (tables, figures, recordings, notebooks) and the notebooks' ``manifests``
    (models). Empty when there is no such summary."""
    old = previous_summary(layout.results)
    if not old:
        return {}
    names = [n.get("name") for n in old.get("notebooks") or [] if isinstance(n, dict)]
    tables = [t for t in old.get("tables") or {} if isinstance(t, str)]
    return {
        "results": {"summary.json", "summary.csv", *(f"{t}.{e}" for t in tables for e in ("csv", "json"))},
        "recordings": {r for r in old.get("recordings") or [] if isinstance(r, str)},
        "models": {m for man in manifests.values() for m in getattr(man, "models", ())},
        "notebooks": {f"{n}{e}" for n in names if isinstance(n, str) for e in (".ipynb", ".failed.ipynb")},
    }


@dataclass
class Store:
    """The store of an output layout, and what is at each of the layout's places.

    Attributes
    ----------
    layout : the places readers look at (the project's, or ``--out``'s)
    force : leave a place holding what glu did not write untouched (the run is published in the store)
    state : kind → ``linked`` (a link into the store), ``absent``, ``legacy`` (an earlier glu's folder,
        moved aside when the run is published) or ``kept`` (not glu's; left untouched with ``force``)
    """

    layout: OutputLayout
    force: bool = False
    state: dict[str, str] = field(default_factory=dict)

    @property
    def root(self) -> Path:
        """The store's folder."""
        return self.layout.store

    @property
    def site_work(self) -> Path:
        """Where the site's sources are assembled and built (:data:`SITE_WORK`)."""
        return self.root / SITE_WORK

    @property
    def failed(self) -> Path:
        """Where the executed copies of failed notebooks are kept (:data:`FAILED`)."""
        return self.root / FAILED

    def current(self) -> Path | None:
        """The published run's folder, or None before the first publication."""
        try:
            name = os.readlink(self.root / CURRENT)
        except OSError:
            return None
        run = self.root / name
        return run if _RUN_NAME.fullmatch(name) and run.is_dir() else None

    def _target(self, kind: str) -> str:
        place = self.layout.folder(kind)
        return os.path.relpath(self.root / CURRENT / kind, place.parent)

    # ---------------------------------------------------------------------------------------- checks
    def survey(self, legacy: Mapping[str, set[str]] | None = None) -> dict[str, str]:
        """Check the store and every place before anything runs; :class:`PublishError` in one line naming
        the first file glu did not write (unless ``force``). ``legacy``: the files an earlier glu wrote
        (:func:`legacy_files`), recognised in the project's checkout only."""
        self._check_root()
        for kind in OUTPUT_KINDS:
            self.state[kind] = self._place(kind, legacy)
        return self.state

    def _check_root(self) -> None:
        root = self.root
        if root.is_symlink() or (root.exists() and not root.is_dir()):
            raise PublishError(f"{root} is not a folder glu made; move it away (glu keeps its runs there)")
        if root.is_dir() and not (root / MARKER).is_file():
            stray = _first_file(root)
            if stray is not None:
                raise PublishError(
                    f"{stray} is not glu's: {root.name}/ is where glu keeps its runs, and it holds no "
                    f"{MARKER} file; move that folder away"
                )

    def _place(self, kind: str, legacy: Mapping[str, set[str]] | None) -> str:
        place = self.layout.folder(kind)
        if place.is_symlink():
            if os.readlink(place) == self._target(kind):
                return "linked"
            return self._foreign(kind, place, f"{place} is a link glu did not make")
        if not place.exists():
            return "absent"
        if not place.is_dir():
            return self._foreign(kind, place, f"{place} is a file glu did not write")
        stray = self._stray(kind, place, legacy)
        if stray is None:
            return "legacy"
        return self._foreign(kind, place, f"{stray} is not from a glu run (no record of glu's lists it)")

    def _stray(self, kind: str, place: Path, legacy: Mapping[str, set[str]] | None) -> Path | None:
        """The first file in the folder ``place`` that no earlier glu wrote, or None when every one is."""
        if legacy is None or PROJECT_ROOT is None or self.layout.root != PROJECT_ROOT:
            return _first_file(place)
        build = PROJECT_ROOT / "build"
        if build in place.parents:  # the checkout's build/ is glu's own (`make clean` removes it)
            return None
        return _first_file(place, legacy.get(kind, ()))

    def _foreign(self, kind: str, place: Path, what: str) -> str:
        if self.force:
            return "kept"
        raise PublishError(
            f"{what}; glu never replaces what it did not write: move it away, or give --force to leave it "
            f"untouched (that part of the run is then published in {self.root / CURRENT / kind} only)"
        )

    # ---------------------------------------------------------------------------------------- a run
    def begin(self) -> Path:
        """Make the store if needed, remove what stopped runs left, and return a new run folder to stage
        in (owned by this process until it is published or discarded)."""
        self.root.mkdir(parents=True, exist_ok=True)
        marker = self.root / MARKER
        if not marker.is_file():
            atomic_write_text(
                marker,
                "glu's store of runs (glu reproduce): `current` names the published one; glu manages "
                "everything in this folder.\n",
            )
        self.clean()
        run = _run_folder(self.root)
        (run / OWNER).write_text(f"{os.getpid()}\n")
        return run

    def clean(self) -> list[Path]:
        """Remove the runs that are not published and whose owner is gone (a stopped or killed run, an
        earlier publication); returns them."""
        if not self.root.is_dir():
            return []
        current, removed = self.current(), []
        for entry in sorted(self.root.iterdir()):
            if entry.name.startswith(f".{CURRENT}-") and entry.is_symlink():  # a pointer never swapped in
                entry.unlink()
                continue
            if not (_RUN_NAME.fullmatch(entry.name) and entry.is_dir()) or entry == current:
                continue
            if _owned(entry):
                continue
            shutil.rmtree(entry, ignore_errors=True)
            removed.append(entry)
        return removed

    def discard(self, run: Path) -> None:
        """Remove a staged run unless it is the published one (a stop after the rename keeps it)."""
        if run.exists() and self.current() != run:
            shutil.rmtree(run, ignore_errors=True)

    def carry_over(self, run: Path, notebooks: Iterable[str]) -> dict[str, str]:
        """Link into ``run`` the published run's files of ``notebooks`` (a partial run keeps the others'
        outputs); returns their relative path → notebook."""
        current = self.current()
        if current is None:
            return {}
        wanted = set(notebooks)
        kept = {p: nb for p, nb in read_record(current).items() if nb in wanted}
        for rel in kept:
            _link_or_copy(current / rel, run / rel)
        return kept

    def record(self, run: Path, files: Mapping[str, str]) -> None:
        """Write the run's record: each notebook's files (relative path → notebook)."""
        doc = {"glu": "a run of glu reproduce", "files": dict(sorted(files.items()))}
        atomic_write_text(run / RUN_RECORD, json.dumps(doc, indent=1) + "\n")
        reached("recorded")

    def publish(self, run: Path, log: Callable[[str], None] = lambda s: None) -> None:
        """Publish the staged ``run``: one rename of the pointer, then the places' links (made once), then
        the earlier runs removed."""
        pointer = self.root / f".{CURRENT}-{secrets.token_hex(4)}"
        os.symlink(run.name, pointer)
        os.replace(pointer, self.root / CURRENT)
        reached("pointer")
        self._link_places(log)
        reached("links")
        (run / OWNER).unlink(missing_ok=True)
        self.clean()
        reached("cleaned")

    def _link_places(self, log: Callable[[str], None]) -> None:
        aside: Path | None = None
        for kind in OUTPUT_KINDS:
            place, state = self.layout.folder(kind), self.state.get(kind, "absent")
            if state == "kept" or (state == "absent" and (place.exists() or place.is_symlink())):
                log(
                    f"glu reproduce: {place} is not glu's and was left untouched; this run's {kind}: "
                    f"{self.root / CURRENT / kind}"
                )
                continue
            if state == "legacy" and place.is_dir() and not place.is_symlink():
                if aside is None:  # an earlier glu's folders: moved aside, removed as an earlier run
                    aside = _run_folder(self.root)
                os.replace(place, aside / kind)
            if not place.is_symlink():
                place.parent.mkdir(parents=True, exist_ok=True)
                os.symlink(self._target(kind), place)
            self.state[kind] = "linked"


def _link_tree(src: Path, dest: Path, skip: Iterable[str]) -> None:
    """Hard-link every file under ``src`` into ``dest`` (copy where links are refused), but the top-level
    entries named in ``skip``."""
    skip = set(skip)
    for f in sorted(src.rglob("*")):
        rel = f.relative_to(src)
        if rel.parts[0] not in skip and not f.is_dir():
            _link_or_copy(f, dest / rel)


def republish(
    layout: OutputLayout,
    part: str,
    build: Callable[[OutputLayout, Path], Any],
    log: Callable[[str], None] = lambda s: None,
) -> Path:
    """Publish the published run again with one ``part`` (a kind: ``site``) made anew by ``build(staged,
    work)``: a new run folder holds the same files (hard links) but that part, then one rename publishes
    it, as :func:`glu.run.reproduce.reproduce` publishes a run. Returns the new run's folder."""
    store = Store(layout, force=True)
    store.survey()
    current = store.current()
    if current is None:
        raise PublishError(f"no run is published in {layout.root} yet: run `glu reproduce` first")
    run = store.begin()
    try:
        _link_tree(current, run, skip={part, OWNER})
        build(OutputLayout.under(run), store.site_work)
        store.publish(run, log)
    finally:
        store.discard(run)
    return run


def read_record(run: Path) -> dict[str, str]:
    """A run's record (:data:`RUN_RECORD`): relative path → notebook; {} when it has none."""
    try:
        files = json.loads((run / RUN_RECORD).read_text())["files"]
    except (OSError, ValueError, KeyError, TypeError):
        return {}
    if not isinstance(files, dict):
        return {}
    return {p: nb for p, nb in files.items() if isinstance(p, str) and isinstance(nb, str) and _inside(p)}


def _inside(relative: str) -> bool:
    """Whether a path read from a record stays inside its run folder (relative, no ``..``)."""
    path = Path(relative)
    return bool(relative) and not path.is_absolute() and ".." not in path.parts


def refuse_published(layout: OutputLayout, who: str) -> None:
    """:class:`PublishError` when ``layout``'s places are the links of a store: a run that does not publish
    (``glu run``, a notebook by hand) must not write into a published run."""
    for kind in OUTPUT_KINDS:
        if layout.folder(kind).is_symlink() and (layout.store / MARKER).is_file():
            raise PublishError(
                f"{layout.root} holds the runs glu reproduce published; {who} writes into a folder of its "
                "own: give another output folder"
            )
