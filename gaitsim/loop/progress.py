"""Progress lines of a loop run: the step, how far it is, the time spent and an estimate of the time left."""

from __future__ import annotations

import time


class Progress:
    """Reports each unit of work of a stage to ``log`` with the stage's time left, estimated from the mean time
    per unit so far (the units of a stage cost alike: simulations and fits of one twin)."""

    def __init__(self, log, clock=time.monotonic):
        self.log = log
        self.clock = clock
        self.started = clock()
        self._stage, self._total, self._done, self._stage_started = "", 0, 0, self.started

    def stage(self, name: str, total: int) -> None:
        """Begin a stage of ``total`` units."""
        self._stage, self._total, self._done, self._stage_started = name, max(int(total), 1), 0, self.clock()

    def step(self, what: str) -> None:
        """One unit of the current stage is done (``what`` names it)."""
        self._done += 1
        now = self.clock()
        left = (now - self._stage_started) / self._done * (self._total - self._done)
        self.log(f"{self._stage}: {self._done}/{self._total} {what} ({now - self.started:.0f} s elapsed, "
                 f"~{left:.0f} s left in this step)")

    def note(self, message: str) -> None:
        """A line outside any stage, with the time elapsed."""
        self.log(f"{message} ({self.clock() - self.started:.0f} s elapsed)")
