"""The predictions' safety field under a deadline (the navigator's search field).

:class:`_TimedField` is a :class:`~gfuzzy.timespace.movers.MoverField` that answers the
search's safety questions in pieces and gives up between two pieces once the navigator's
deadline has passed (:class:`_OutOfTime`): the search looks at its deadline only between
expansions, and the interval store asks for the safety of thousands of points at once.
"""

from __future__ import annotations

import math
import time

import numpy as np

from ..timespace.movers import MoverField

__all__ = ["PIECE_WORK", "PIECE_STEP_WORK", "PAIR_SECONDS", "PIECE_SECONDS", "PIECE_MAX_SCALE", "Pace"]

#: The predictions' field answers the search's safety questions in pieces of about this
#: many (point, person) pairs (at least 64 points), looking at the clock between two
#: pieces (a piece took 3-4 ms here).
PIECE_WORK = 60_000
#: ... and of at most this many (point, person, step) triples, each point counted over its
#: steps ``lo..hi`` (at least one group). A piece's time grows with its steps: a
#: differential drive's store asked 8,400 points over up to 280 steps each among 5 people
#: at once, one piece of 92 ms of CPU past a 37 ms deadline (1-9 ns per triple measured
#: here, median 4: a piece of about 4 ms).
PIECE_STEP_WORK = 1_000_000
#: Seconds the search's interval store takes per unsafe (point, step) pair it is given
#: (it sorts them; 20-70 ns measured here), kept free before the deadline.
PAIR_SECONDS = 60e-9
#: Once the time of a piece has been measured (:class:`Pace`), a piece is as many of the
#: bounds above (``PIECE_WORK`` pairs, ``PIECE_STEP_WORK`` triples) as take about this long,
#: never fewer than one: each piece costs about 0.5 ms of Python beyond the kernels, and a
#: store's batch of 50,000 points among 13 people took 27-35 ms in 26 pieces, 15-18 ms in
#: one (session 38). A piece is meant to take about this long, but people closer to the
#: points cost more per triple than those the pace was timed on: a batch's first piece is
#: one of the fixed bounds, each next one at most twice the last, none meant to outlast the
#: time left (:meth:`_TimedField._pieces`), so a batch runs past its deadline by about one
#: fixed piece, or by a piece timed on a cheaper part of the batch.
PIECE_SECONDS = 0.004
#: ... and never more than this many of them (a clock that does not move measures nothing).
PIECE_MAX_SCALE = 64.0


class Pace:
    """The measured time of one piece's worth of safety work (``PIECE_WORK`` pairs or
    ``PIECE_STEP_WORK`` triples, whichever bounds the piece), shared by the fields of one
    navigator: cautious, as the navigator's other estimates (up at once, down by a fifth
    per measurement). ``None`` until a piece of at least that much work was measured."""

    def __init__(self) -> None:
        self.unit: float | None = None

    def scale(self) -> float:
        """How many of the fixed bounds the next piece may be: about ``PIECE_SECONDS``."""
        if self.unit is None:
            return 1.0
        return min(PIECE_MAX_SCALE, max(1.0, PIECE_SECONDS / max(self.unit, 1e-12)))

    def measure(self, seconds: float, units: float) -> None:
        """A piece of ``units`` times the fixed bounds took ``seconds`` (only whole pieces,
        cut by the bounds, are measured: a batch's last piece may be mostly the fixed cost
        of a piece)."""
        took = max(seconds, 0.0) / max(units, 1e-9)
        self.unit = took if self.unit is None else max(took, 0.8 * self.unit + 0.2 * took)


class _OutOfTime(Exception):
    """The search's deadline passed while the safety of its points was being computed."""


class _TimedField(MoverField):
    """The predictions' field, answering the search's safety questions in pieces of about
    ``PIECE_WORK`` (point, person) pairs (more once their time is measured: :class:`Pace`),
    raising :class:`_OutOfTime` between two pieces once ``deadline`` (on ``clock``) has
    passed. The search looks at its deadline only between expansions, and the interval
    store asks for the safety of thousands of points at once (among 100 people one such
    batch took 60-140 ms here). The groups are independent: the pieces' answers put
    together are the whole batch's.
    """

    deadline: float = math.inf
    clock = staticmethod(time.perf_counter)
    pace: Pace | None = None  # the navigator's (shared by its fields); a field's own otherwise

    def unsafe_pairs(self, poses, ptr, lo, hi):
        nodes, steps = [np.zeros(0, dtype=np.int64)], [np.zeros(0, dtype=np.int64)]
        pairs = [0]  # the store then sorts the pairs: time kept for it (PAIR_SECONDS each)
        for p, sub, a, b in self._pieces(ptr, lo, hi, lambda: pairs[0] * PAIR_SECONDS):
            n, st = super().unsafe_pairs(poses[p[0] : p[-1]], sub, a, b)
            nodes.append(n + p[0])
            steps.append(st)
            pairs[0] += len(n)
        return np.concatenate(nodes), np.concatenate(steps)

    def safe_intervals(self, poses, ptr, lo, hi):  # the compiled kernel's batches (newer stores)
        starts, ends, sps = [np.zeros(0, dtype=np.int64)], [np.zeros(0, dtype=np.int64)], [np.zeros(1, np.int64)]
        for p, sub, a, b in self._pieces(ptr, lo, hi, lambda: 0.0):
            gs, ge, sp = super().safe_intervals(poses[p[0] : p[-1]], sub, a, b)
            starts.append(gs)
            ends.append(ge)
            sps.append(np.asarray(sp[1:], dtype=np.int64) + sps[-1][-1])
        return np.concatenate(starts), np.concatenate(ends), np.concatenate(sps)

    def motion_safe(self, a, b, step, min_interval=1e-6):
        """:meth:`MoverField.motion_safe`, raising :class:`_OutOfTime` once the deadline has
        passed. The search decides the first motions from a start the margin refuses one
        by one, before its first expansion: a differential drive's start has dozens (its
        two-leg lanes), each waited for up to 40 steps, and they ran 15-20 ms past the
        deadline on a pedestrian replay, over the budget once the evasive motion followed."""
        if self.clock() > self.deadline:
            raise _OutOfTime
        return super().motion_safe(a, b, step, min_interval)

    def _pieces(self, ptr, lo, hi, after):
        """(point pointers, group pointers from 0, lo, hi) of consecutive groups, while
        the clock plus ``after()`` (seconds the caller still needs) is before the deadline.
        A piece is ``Pace.scale()`` times the fixed bounds, but a batch's first is one, each
        next at most twice the last, none meant to outlast the time left; the clock read
        before each piece times the piece before it."""
        ptr = np.asarray(ptr, dtype=np.int64)
        g = len(ptr) - 1
        lo = np.broadcast_to(np.asarray(lo, dtype=np.int64), (g,))
        hi = np.broadcast_to(np.asarray(hi, dtype=np.int64), (g,))
        if self.pace is None:
            self.pace = Pace()
        people = max(len(self.movers), 1)
        size = max(64, PIECE_WORK // people)
        # (point, person, step) triples of the groups before each group: the pieces' second bound
        work = np.concatenate([[0], np.cumsum(np.diff(ptr) * np.maximum(hi - lo + 1, 1))]) * people
        a, began, units, f = 0, None, 0.0, 0.5
        while a < g:
            now = self.clock()
            if began is not None:
                self.pace.measure(now - began, units)
            need = after()
            if now + need > self.deadline:
                raise _OutOfTime
            # a batch's first piece is one fixed piece, each next one at most twice the last: a
            # pace learnt on cheap pieces (points far from everyone) never sends a whole large
            # piece among the people; and no piece is meant to take longer than the time left
            f = min(self.pace.scale(), 2.0 * f)
            if self.pace.unit is not None and math.isfinite(self.deadline):
                f = min(f, (self.deadline - now - need) / max(self.pace.unit, 1e-12))
            f = max(f, 1.0)
            b = int(np.searchsorted(ptr, ptr[a] + int(size * f), side="right")) - 1
            b = min(b, int(np.searchsorted(work, work[a] + int(PIECE_STEP_WORK * f), side="right")) - 1)
            b = min(g, max(a + 1, b))
            units = max((ptr[b] - ptr[a]) / size, (work[b] - work[a]) / PIECE_STEP_WORK)
            began = now
            yield ptr[a : b + 1], ptr[a : b + 1] - ptr[a], lo[a:b], hi[a:b]
            a = b
