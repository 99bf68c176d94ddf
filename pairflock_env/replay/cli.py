"""``pairflock-replay FILE -o replay.html``: the replay page of a recording."""

from __future__ import annotations

import argparse
import sys

from pairflock_env.replay.build import DEFAULT_MAX_MB, build_replay

__all__ = ["build_parser", "main"]


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="pairflock-replay",
        description="Write one self-contained HTML page that replays a recording in 3-D (or a "
        "top view in 2-D); it opens offline in any browser with WebGL2.",
    )
    p.add_argument("recording", help="the recording folder (written with --record or "
                   "RecordEpisode)")  # fmt: skip
    p.add_argument("-o", "--output", default="replay.html", help="the page (default %(default)s)")
    p.add_argument("--stride", type=int, default=None,
                   help="replay one recorded step in STRIDE (default: the smallest that keeps "
                   "the page's decoded data under --max-mb)")  # fmt: skip
    p.add_argument("--max-mb", type=float, default=DEFAULT_MAX_MB,
                   help="decoded data the page may hold, MB (default %(default)s)")  # fmt: skip
    p.add_argument("--title", default=None, help="page title (default: the folder's name)")
    return p


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        out = build_replay(
            args.recording, args.output, stride=args.stride, max_mb=args.max_mb, title=args.title
        )
    except (OSError, TypeError, ValueError) as exc:
        print(f"pairflock-replay: {exc}", file=sys.stderr)
        return 2
    print(
        f"{out['path']}: {out['bytes'] / 1e6:.2f} MB, {out['steps']} steps (stride "
        f"{out['stride']}), {out['bytes_per_uav_step']:.2f} bytes per UAV-step"
    )
    return 0
