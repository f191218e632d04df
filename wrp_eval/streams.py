"""Per-flight random streams, batch-first: what keeps a flight's draws independent of the batch it flies in.

Every stochastic model of a batch of flights (turbulence, navigation errors, ship motion) draws flight i's
numbers from flight i's own ``numpy.random.Generator``, in stream order, so row i of any batched result is
bit-identical to the same flight simulated alone, whatever the batch size, backend or chunking.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

# what a batch's random streams may be given as (:func:`flight_generators`)
FlightRngs = (int | np.integer[Any] | np.random.SeedSequence | np.random.Generator | None
              | Sequence[np.random.Generator | int | np.integer[Any] | np.random.SeedSequence])


# the spawn-key head of a redrawn seed (:func:`redrawn_seed`): its keys (7, k) are not those of the flight and
# wind streams, which spawn children 0 and 1 of the seed (keys starting 0 or 1)
_REDRAW_KEY = 7


def redrawn_seed(seed: int, noise_draw: int) -> int | np.random.SeedSequence:
    """Draw ``noise_draw`` of a seed's streams: ``seed`` itself for 0, else an independent SeedSequence of it (the
    same mission's errors drawn again, :attr:`wrp_eval.planning.path.FlightPath.noise_draw`)."""
    return seed if noise_draw == 0 else np.random.SeedSequence(seed, spawn_key=(_REDRAW_KEY, int(noise_draw)))


def children(source: np.random.SeedSequence | np.random.Generator, n: int) -> list[np.random.Generator]:
    """The n Generators ``source`` (a SeedSequence or a Generator) would spawn next (``spawn``'s numbers and bit
    generator), without spawning them: the caller's object is left as it was, so passing the same object twice
    gives the same numbers twice (a caller that wants other streams spawns them itself)."""
    bit_generator: type[np.random.BitGenerator]
    if isinstance(source, np.random.Generator):
        seq, bit_generator = source.bit_generator.seed_seq, type(source.bit_generator)
    else:
        seq, bit_generator = source, np.random.PCG64
    if not isinstance(seq, np.random.SeedSequence):
        raise TypeError(f"children() needs a SeedSequence or a Generator seeded by one, got {type(seq).__name__}")
    first = seq.n_children_spawned
    return [np.random.Generator(bit_generator(np.random.SeedSequence(
        seq.entropy, spawn_key=tuple(seq.spawn_key) + (first + i,), pool_size=seq.pool_size))) for i in range(n)]


def flight_generators(rngs: FlightRngs, n_flights: int) -> list[np.random.Generator]:
    """One Generator per flight: ``rngs`` is a seed / None, a SeedSequence or a Generator (its first n_flights
    children, :func:`children`), or a sequence of n_flights Generators (used as is) or seeds / SeedSequences
    (one Generator each)."""
    if isinstance(rngs, (int, np.integer)) or rngs is None:
        rngs = np.random.default_rng(rngs).spawn(n_flights)
    elif isinstance(rngs, (np.random.SeedSequence, np.random.Generator)):
        rngs = children(rngs, n_flights)
    if len(rngs) != n_flights:
        raise ValueError(f"got {len(rngs)} generators for {n_flights} flights")
    return [g if isinstance(g, np.random.Generator) else np.random.default_rng(g) for g in rngs]


# steps of a BlockNormals' first block; each next block doubles, up to its block_steps: a short flight draws what it
# needs, not a long flight's numbers (a fixed block of 1,024 Dryden steps for 64 flights is ~3.5 ms of draws, and a
# 10 s flight steps 200 times)
FIRST_BLOCK_STEPS = 32


class BlockNormals:
    """Standard normals (n_flights, n_steps, width) from each flight's own generator, drawn in blocks per flight
    (one stacked draw per block, not one per step; the first :data:`FIRST_BLOCK_STEPS` steps, each next one twice
    the last, up to ``block_steps``): the numbers a flight gets depend only on its generator and on how many steps
    it has consumed, never on how the caller chunks the time axis or on the block sizes."""

    def __init__(self, rngs: FlightRngs, n_flights: int, width: int, block_steps: int = 1024) -> None:
        if block_steps < 1:
            raise ValueError(f"block_steps must be >= 1, got {block_steps}")
        self.rngs = flight_generators(rngs, n_flights)
        self.width = int(width)
        self.block_steps = int(block_steps)
        self._next_block_steps = min(FIRST_BLOCK_STEPS, self.block_steps)
        self._block = np.empty((n_flights, 0, self.width))
        self._cursor = 0

    def draw(self, n_steps: int) -> NDArray[np.float64]:
        """The next ``n_steps`` steps of every flight's stream, (n_flights, n_steps, width)."""
        out = np.empty((len(self.rngs), n_steps, self.width))
        filled = 0
        while filled < n_steps:
            if self._cursor >= self._block.shape[1]:
                if self._block.shape[1] != self._next_block_steps:
                    self._block = np.empty((len(self.rngs), self._next_block_steps, self.width))
                self._next_block_steps = min(2 * self._next_block_steps, self.block_steps)
                for row, g in zip(self._block, self.rngs, strict=True):    # per flight: its own stream, into the buffer
                    g.standard_normal(out=row)
                self._cursor = 0
            take = min(n_steps - filled, self._block.shape[1] - self._cursor)
            out[:, filled:filled + take] = self._block[:, self._cursor:self._cursor + take]
            self._cursor += take
            filled += take
        return out
