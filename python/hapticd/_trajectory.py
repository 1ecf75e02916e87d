"""A lockstep run sampled every tick into NumPy arrays (record())."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

if TYPE_CHECKING:
    from ._native import Client


@dataclass(frozen=True)
class Trajectory:
    """Samples of one run, row i from the i-th step. Positions, velocities and forces are (N, 3)
    arrays in W (m, m/s, N); time is server time (s)."""

    tick: npt.NDArray[np.uint64]           # (N,)
    time: npt.NDArray[np.float64]          # (N,) s
    position: npt.NDArray[np.float64]      # (N, 3) m
    velocity: npt.NDArray[np.float64]      # (N, 3) m/s
    force: npt.NDArray[np.float64]         # (N, 3) N
    proxy: npt.NDArray[np.float64]         # (N, 3) m
    contact_count: npt.NDArray[np.uint32]  # (N,)
    flags: npt.NDArray[np.uint32]          # (N,) StateFlag bits

    def __len__(self) -> int:
        return len(self.tick)


def record(client: Client, ticks: int, every: int = 1, timeout: float = 5.0) -> Trajectory:
    """Steps a lockstep server `ticks` ticks, `every` ticks at a time, and returns a Trajectory of
    the sample each step ends on (the step's reply carries it, so none is lost). Raises ValueError
    for counts that are not positive whole numbers, TimeoutError if a sample does not arrive within
    `timeout` seconds, and hapticd.FailedPreconditionError from a real-time server."""
    if int(ticks) != ticks or ticks < 1:
        raise ValueError(f"record: ticks must be a whole number >= 1, got {ticks!r}")
    if int(every) != every or every < 1:
        raise ValueError(f"record: every must be a whole number >= 1, got {every!r}")
    ticks, every = int(ticks), int(every)
    rows = -(-ticks // every)
    tick = np.empty(rows, dtype=np.uint64)
    time = np.empty(rows)
    vectors = {name: np.empty((rows, 3)) for name in ("position", "velocity", "force", "proxy")}
    contact_count = np.empty(rows, dtype=np.uint32)
    flags = np.empty(rows, dtype=np.uint32)
    done = 0
    for row in range(rows):
        step = min(every, ticks - done)
        last = client.step(step)
        done += step
        state = client.wait_for_tick(last, timeout)
        if state is None:
            raise TimeoutError(f"record: no sample of tick {last} within {timeout} s")
        tick[row] = state.tick
        time[row] = state.server_time
        for name, array in vectors.items():
            array[row] = getattr(state, name)
        contact_count[row] = state.contact_count
        flags[row] = state.flags
    return Trajectory(tick=tick, time=time, contact_count=contact_count, flags=flags, **vectors)
