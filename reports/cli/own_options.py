"""The options of a user's own model file (``xval import``, ``xval compare MODEL``,
``xval simulate MODEL``): ``--driver``, ``--keyframe``, ``--close``."""

from __future__ import annotations

import argparse
import math


def close_arg(text: str) -> tuple[str, tuple[float, ...], str, tuple[float, ...]]:
    """An argparse type: ``LINK_A:x,y,z=LINK_B:x,y,z`` (m, link frames) as ``(a, pa, b,
    pb)``."""
    try:
        left, right = text.split("=")
        ends = []
        for part in (left, right):
            link, xyz = part.rsplit(":", 1)
            p = tuple(float(v) for v in xyz.split(","))
            if not link or len(p) != 3 or not all(math.isfinite(v) for v in p):
                raise ValueError
            ends.append((link, p))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"{text!r}: give LINK_A:x,y,z=LINK_B:x,y,z (the point of each link, m, in "
            "the link's frame, that the loop pins together)") from None
    return ends[0][0], ends[0][1], ends[1][0], ends[1][1]


def add_own_options(s, what: str = "with a model file: ") -> None:
    s.add_argument("--driver", help=f"{what}its input joint (default: the one actuated "
                   "joint)")
    s.add_argument("--keyframe", help=f"{what}the reference configuration (default: qpos0)")
    s.add_argument("--close", action="append", type=close_arg, default=[],
                   metavar="LINK_A:x,y,z=LINK_B:x,y,z",
                   help=f"{what}a loop closure a URDF cannot hold: these two link points "
                        "pinned together (repeatable)")
