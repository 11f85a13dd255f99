"""Why a differential drive's start or goal may join nothing: the end is hemmed in.

A differential drive leaves its start only by turning in place or driving along its
heading (backwards only with ``robot.reverse``), and reaches its goal the same way. A
footprint whose nose touches a wall and whose sweep meets another can do neither: the
roadmap cannot join the end, however many vertices it has, and "more vertices may find
it" is the wrong advice. :func:`hemmed_note` measures such an end (the turn in place it
has either way, the straight it may drive) for the ``no_path`` message, so the user sees
that the pose, not the roadmap, is the problem.

Likewise a drive's graph may leave start and goal apart where the SE(2) roadmap joins them
(the body slides and turns along the roadmap's edges; the drive turns only at vertices):
:func:`drive_split_note` says so, not "the roadmap missed a passage".
"""

from __future__ import annotations

import math

from ..timespace.drive import turn_free

#: A straight this short (m) is no way out: the end counts as hemmed in when its free
#: turns cannot take it round and every straight it may drive is shorter.
STRAIGHT = 0.05
#: Longest straight measured (m).
REACH = 1.0
#: Headings tried within each free turn (its limit included) before an end is called
#: hemmed in: a part turn may clear the way out.
TURN_SAMPLES = 4


def _free_turn(geometry, x: float, y: float, h: float, side: int, steps: int = 10) -> float:
    """The largest turn in place from ``h`` towards ``side`` (+1 counter-clockwise) whose
    sweep is free, up to pi, by bisection (0: none)."""
    if turn_free(geometry, x, y, h, side * math.pi):
        return math.pi
    lo, hi = 0.0, math.pi
    for _ in range(steps):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if turn_free(geometry, x, y, h, side * mid) else (lo, mid)
    return lo


def _free_straight(geometry, x: float, y: float, h: float, sign: int, steps: int = 12) -> float:
    """The longest straight along heading ``h`` (``sign`` -1: backwards) from (x, y) that is
    free, up to :data:`REACH`, by bisection."""
    a = [x, y, h]

    def free(d: float) -> bool:
        b = [x + sign * d * math.cos(h), y + sign * d * math.sin(h), h]
        return bool(geometry.motion_free(a, b))

    if free(REACH):
        return REACH
    lo, hi = 0.0, REACH
    for _ in range(steps):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if free(mid) else (lo, mid)
    return lo


def hemmed_note(geometry, pose, end: str) -> str:
    """A clause saying that a differential drive's ``end`` ("start" or "goal") at ``pose``
    can neither turn round in place nor drive a way out, or "" when it can (a disc turns
    wherever it stands: always "").

    The goal is reached the way the start is left, reversed: forwards into it means
    through the space behind it."""
    robot = geometry.robot
    if not robot.unicycle or robot.shape == "disc":
        return ""
    x, y, h = (float(c) for c in pose[:3])
    left, right = _free_turn(geometry, x, y, h, 1), _free_turn(geometry, x, y, h, -1)
    if left + right >= 2.0 * math.pi - 1e-9:
        return ""
    ahead = 1 if end == "start" else -1  # the goal is entered driving forwards from behind it
    fwd = _free_straight(geometry, x, y, h, ahead)
    back = _free_straight(geometry, x, y, h, -ahead)
    usable = max(fwd, back) if robot.reverse else fwd
    if usable >= STRAIGHT:
        return ""
    # a part turn may clear the way: the straights at the turns' limits (and between)
    signs = (ahead, -ahead) if robot.reverse else (ahead,)
    for k in range(1, TURN_SAMPLES + 1):
        for dh in (left * k / TURN_SAMPLES, -right * k / TURN_SAMPLES):
            if any(_free_straight(geometry, x, y, h + dh, sg) >= STRAIGHT for sg in signs):
                return ""
    turns = f"turns in place at most {math.degrees(left):.0f}° left and {math.degrees(right):.0f}° right"
    if end == "start":
        way = f"drives at most {fwd:.2g} m forwards"
        other = f"{back:.2g} m backwards"
    else:
        way = f"is entered at most {fwd:.2g} m driving forwards"
        other = f"{back:.2g} m backing in"
    if robot.reverse:
        way += f" and {other}"
    elif back >= STRAIGHT:
        way += f" ({other} would be free: robot.reverse: true allows it)"
    return f"the {end} is hemmed in: it {turns} and {way}"


def _reached_components(geometry, roadmap, pose) -> set:
    """The roadmap components of the :data:`~gfuzzy.planner.bridge.TRIES` vertices nearest
    ``pose`` that a certified motion of the body (heading interpolated, as the roadmap's
    edges) reaches from it."""
    import numpy as np

    from .bridge import components, reached

    V = np.asarray(roadmap.vertices, dtype=float)
    if not len(V) or V.shape[1] != 3:  # (a hand-made roadmap of positions only: not asked)
        return set()
    label = components(roadmap)
    p = np.asarray(pose, dtype=float)[:3]
    return {int(label[i]) for i in reached(geometry, roadmap, p, np.arange(len(V)))}


def drive_split_note(geometry, roadmap, start, goal, repair: bool) -> str:
    """The ``no_path`` message of a box or footprint drive whose graph leaves ``start`` and
    ``goal`` apart although the SE(2) roadmap joins them (each reaches, by a certified
    motion, one of its nearest vertices, and these lie in one component), or "" when the
    roadmap does not join them (the roadmap's own message then). The drive turns only at
    the roadmap's vertices (and where the drive repair adds turns, ``repair``): the
    roadmap's way may hold no turn it can make; more vertices may give one, and so may
    backing up (``robot.reverse``) or the drive repair when they are off."""
    robot = geometry.robot
    if not robot.unicycle or robot.shape == "disc":
        return ""
    if not _reached_components(geometry, roadmap, start) & _reached_components(geometry, roadmap, goal):
        return ""
    helps = ["more vertices (-n) may give it the turns it needs"]
    if not robot.reverse:
        helps.append("so may backing up (robot.reverse: true)")
    if not repair:
        helps.append("so may the drive repair (drop --no-drive-repair)")
    chains = " and the drive repair found no chain of small turns between its pieces" if repair else ""
    return (
        "start and goal are joined on the roadmap, but the differential drive found no way along it: "
        f"it turns in place only at the roadmap's vertices{chains}; " + "; ".join(helps)
    )
