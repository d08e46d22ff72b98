"""``glu data fetch|synth|info``: get the real data, make synthetic data, show what a source holds."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from glu import paths
from glu.cli.commands import add_command, add_group
from glu.cli.common import (
    add_data_option,
    add_deprecated_alias,
    add_json_option,
    add_out_option,
    integer,
    json_text,
    progress,
    seed,
)
from glu.data.source import DEFAULT_SYNTHETIC_N, WORD_FILES
from glu.data.synthetic import MAX_ROWS, MIN_ROWS
from glu.errors import DataError, FetchError


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``data`` command group."""
    dsub = add_group(
        sub,
        "data",
        "Get the real data (glu data fetch), write a synthetic data folder (glu data synth), "
        "or see which data source a command would use and what it holds (glu data info).",
    )

    f = add_command(
        dsub,
        "fetch",
        "Download the authors' published data (GPL-3.0) at pinned commits and check every "
        "file's sha256. The data folder appears, by one rename, only when every file is verified; a failed "
        "or interrupted fetch leaves it as it was, and the next run downloads only what is missing.",
        _fetch,
        help="download the real data at pinned commits, verifying checksums",
    )
    f.add_argument(
        "-o",
        "--out",
        type=Path,
        default=paths.REAL_DATA_DIR,
        metavar="DIR",
        help=f"data folder to write (default: {paths.HERE.real_data_label})",
    )
    add_deprecated_alias(f, "--dest", "--out")
    f.add_argument("--mirror", metavar="URL", help="fetch {URL}/{local path} instead of from GitHub")
    f.add_argument("--timeout", type=float, default=60.0, help="seconds per request (default 60)")
    f.add_argument(
        "--manifest",
        type=Path,
        default=None,
        metavar="JSON",
        help="the files to fetch, with their origin and sha256 (default: glu's, the real data)",
    )

    s = add_command(
        dsub,
        "synth",
        "Write synthetic experiments (simple physics, the same 49 words) and synthetic "
        "gesture recordings in the layout of the real data, so that every command and notebook runs on them.",
        _synth,
        help="write a synthetic data folder with the real data's layout (tables and hand logs)",
    )
    s.add_argument(
        "--n",
        type=integer,
        default=DEFAULT_SYNTHETIC_N,
        help=f"experiments per table ({MIN_ROWS} to {MAX_ROWS:,}; default {DEFAULT_SYNTHETIC_N})",
    )
    s.add_argument("--seed", type=seed, default=0, help="random seed (default 0)")
    add_out_option(s, "DIR", "output folder", folder=True)
    s.add_argument(
        "--force",
        action="store_true",
        help="replace a folder that is not glu synthetic data (never the published real data)",
    )

    i = add_command(
        dsub,
        "info",
        "Say which data source the commands use (--data, $GLU_DATA_DIR, the fetched data, "
        "else synthetic) and summarise its experiment table: the counts of each node's values and the most "
        'frequent words. --json prints {"data", "words", "experiments", "values", "most_frequent_words"}.',
        _info,
        help="say which data source is used and what it holds",
    )
    add_data_option(i)
    i.add_argument(
        "--words", choices=tuple(WORD_FILES), default="lab", help="which experiment table (default lab)"
    )
    add_json_option(i, "the summary")


def _fetch(args: argparse.Namespace) -> int:
    from glu.data.fetch import MANIFEST, fetch_all, partial_folder

    def report(i: int, n: int, r) -> None:
        extra = f": {r.detail}" if r.detail else ""
        line = f"[{i}/{n}] {r.status:10s} {r.local}{extra}"
        if bar is None:
            print(line, file=sys.stderr)
            return
        bar.total = n
        if r.status == "failed":
            bar.write(line, file=sys.stderr)
        bar.set_postfix_str(r.local, refresh=False)
        bar.update(1)

    with progress(None, "fetch", "file") as bar:
        results = fetch_all(
            args.out,
            mirror=args.mirror,
            progress=report,
            timeout=args.timeout,
            manifest_path=args.manifest or MANIFEST,
        )
    failed = [r for r in results if r.status == "failed"]
    ok = len(results) - len(failed)
    if failed:
        kept = f"; the {ok} verified files wait in {partial_folder(args.out)} for the next run" if ok else ""
        raise FetchError(
            f"{len(failed)} of {len(results)} files could not be fetched (first: {failed[0].detail}); "
            f"nothing was written to {args.out}{kept}; run the command again to retry"
        )
    print(f"{ok}/{len(results)} files verified in {args.out}")
    return 0


def _synth(args: argparse.Namespace) -> int:
    from glu.data.synthetic import write_synthetic_folder
    from glu.gestures.corpus import hand_log_arrays, synthetic_recordings

    if not MIN_ROWS <= args.n <= MAX_ROWS:
        raise DataError(f"--n {args.n} is out of range; allowed: {MIN_ROWS} to {MAX_ROWS:,}")
    recordings = {name: hand_log_arrays(g) for name, g in synthetic_recordings(args.seed).items()}
    with progress(len(WORD_FILES) + 1 + len(recordings), "synth", "file") as bar:
        out = write_synthetic_folder(
            args.out,
            args.n,
            args.seed,
            recordings,
            progress=(lambda name: bar.update(1)) if bar is not None else None,
            force=args.force,
        )
    print(
        f"wrote synthetic data (seed {args.seed}, {args.n} experiments per table, "
        f"{len(recordings)} gesture recordings) to {out}"
    )
    return 0


def _info(args: argparse.Namespace) -> int:
    from glu.data.source import load_experiments, resolve_data

    source = resolve_data(args.data)
    df = load_experiments(source, args.words)
    values = {
        node: {str(v): int(c) for v, c in df[node].value_counts(sort=False).items()}
        for node in df.columns[:8]
    }
    present = (df.iloc[:, 8:] == "present").sum().sort_values(ascending=False)
    frequent = {str(w): int(c) for w, c in present.head(10).items()}
    if args.json:
        info = {
            "data": source.location(),
            "words": args.words,
            "experiments": len(df),
            "values": values,
            "most_frequent_words": frequent,
        }
        print(json_text(info))
        return 0
    print(f"data: {source.location()}")
    print(f"experiments: {len(df)} (words={args.words})")
    for node, counts in values.items():
        print(f"  {node:10s} " + "  ".join(f"{v}={c}" for v, c in counts.items()))
    print("most frequent words: " + ", ".join(f"{w} ({c})" for w, c in frequent.items()))
    return 0
