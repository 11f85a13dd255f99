"""Named constants shared by several stages of the pipeline.

They live here, below every stage, so that a later stage (re-timing, the stages, the
navigator) can use them without importing the planner that runs it.
"""

from __future__ import annotations

__all__ = ["SPEED_SAFETY", "MAX_POINTS", "MAX_MOVER_SAMPLES", "AMAX_PER_VMAX", "INTERVAL_BATCH_CELLS", "MAX_MAGNITUDE",
           "MAX_RECORDED_TIME", "MAX_RUN_STEPS"]

#: Planning speed is vmax shrunk by this factor, so rounding never lifts a step above vmax.
SPEED_SAFETY = 1.0 - 1e-9
#: Largest number of graph points (edges cut into steps) a query may use (about 1 GB with
#: the search's Python lists); the 10,000-vertex hall benchmark has 0.7 million.
MAX_POINTS = 3_000_000
#: Largest number of mover samples (movers x time steps) a query may use: about 0.7 GB.
MAX_MOVER_SAMPLES = 20_000_000
#: The speed layer's acceleration bound for a robot without ``amax``: this many times
#: vmax per second (full speed reached in half a second).
AMAX_PER_VMAX = 2.0

#: Cells (points x steps, one bool each) of the movers' safety computed in one batch by
#: the search's interval store: about 8 MB of bools at a time, whatever the horizon.
INTERVAL_BATCH_CELLS = 8_000_000

#: Largest magnitude of a number in a scene file or a finite option: beyond it lengths and
#: times overflow or stop resolving the time step (1e9 + 0.07 is still 1e9 + 0.07).
MAX_MAGNITUDE = 1e9
#: Largest time on a recording's own clock (``gfuzzy tracks``): Unix time in seconds or in
#: milliseconds is rebased to the window's start, which must then be within MAX_MAGNITUDE.
MAX_RECORDED_TIME = 1e13
#: Largest number of steps of a simulated run: a navigation's replans (``max_time / period``,
#: ``gfuzzy navigate``), a populated walk's ORCA steps (``duration / dt``, ``gfuzzy populate``).
#: ``--period 1e-9`` asked for 1.2e11 replans: a run that never ended.
MAX_RUN_STEPS = 100_000
