"""The compiled simulation backend (``backend="fast"``): the reference kernel's world in numba.

Same scenario, same start state, same per-run random streams, same event
logs byte for byte as ``swarmtag.sim``'s numpy kernel, which stays the
readable reference and the test oracle. Runs are advanced in parallel on
every core. Needs numba (the ``fast`` extra); import this package only
through ``swarmtag.sim.simulate(..., backend="fast")`` or after checking
``swarmtag.sim.backends.fast_available()``.
"""

from __future__ import annotations

from swarmtag.sim.fast._jit import discard_stale_machine_code
from swarmtag.sim.fast._runner import TagCacheFull, kernel_compiled, simulate_fast
from swarmtag.sim.fast._scene import seeded_scenes
from swarmtag.sim.fast._tick import advance

discard_stale_machine_code(advance)  # before anything loads it

__all__ = ["TagCacheFull", "kernel_compiled", "seeded_scenes", "simulate_fast"]
