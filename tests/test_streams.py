"""Per-flight random streams: children are SeedSequence.spawn's numbers without spawning; blocks of normals
do not depend on how the steps are drawn."""

import numpy as np

from wrp_eval.streams import FIRST_BLOCK_STEPS, BlockNormals, children, flight_generators


def test_children_are_the_spawned_ones_and_leave_the_source_untouched():
    seq = np.random.SeedSequence(5)
    ours = [g.standard_normal(4) for g in children(seq, 3)]
    spawned = [np.random.default_rng(s).standard_normal(4) for s in np.random.SeedSequence(5).spawn(3)]
    assert all(np.array_equal(a, b) for a, b in zip(ours, spawned, strict=True))
    assert seq.n_children_spawned == 0
    again = [g.standard_normal(4) for g in flight_generators(seq, 3)]     # the same object twice: same numbers
    assert all(np.array_equal(a, b) for a, b in zip(ours, again, strict=True))
    gen = np.random.default_rng(7)
    first = [g.standard_normal(2) for g in children(gen, 2)]
    assert all(np.array_equal(a, b.standard_normal(2))
               for a, b in zip(first, np.random.default_rng(7).spawn(2), strict=True))
    assert all(np.array_equal(a, b.standard_normal(2)) for a, b in zip(first, children(gen, 2), strict=True))


def test_block_normals_do_not_depend_on_the_chunking():
    whole = BlockNormals(3, 2, 4, block_steps=8).draw(20)
    pieces = BlockNormals(3, 2, 4, block_steps=8)
    chunked = np.concatenate([pieces.draw(k) for k in (1, 7, 5, 7)], axis=1)
    assert np.array_equal(whole, chunked)
    alone = BlockNormals([np.random.default_rng(s) for s in np.random.SeedSequence(3).spawn(2)][1:], 1, 4, 8)
    assert np.array_equal(whole[1:], alone.draw(20))


def test_block_sizes_never_change_the_numbers_and_a_short_draw_draws_little():
    n_steps, width = 3 * FIRST_BLOCK_STEPS + 5, 3
    own = [g.standard_normal((n_steps, width)) for g in flight_generators(4, 2)]
    for block_steps in (1, 8, FIRST_BLOCK_STEPS, 1024):
        assert np.array_equal(BlockNormals(4, 2, width, block_steps).draw(n_steps), np.stack(own))
    growing = BlockNormals(4, 2, width, block_steps=100)      # blocks 32, 64, 100, 100: draws across their ends
    chunked = np.concatenate([growing.draw(k) for k in (1, 31, 0, 64, 5, n_steps - 101)], axis=1)
    assert np.array_equal(chunked, np.stack(own))
    short = BlockNormals(4, 2, width, block_steps=1024)
    short.draw(5)               # one first block: FIRST_BLOCK_STEPS steps drawn, not 1,024
    after = [g.standard_normal() for g in short.rngs]
    assert after == [g.standard_normal((FIRST_BLOCK_STEPS * width) + 1)[-1] for g in flight_generators(4, 2)]


def test_children_continue_after_spawned_ones_keep_the_bit_generator_and_refuse_legacy_sources():
    import pytest
    seq = np.random.SeedSequence(9)
    spawned = seq.spawn(1)[0]
    nxt = children(seq, 1)[0].standard_normal(3)
    assert not np.array_equal(nxt, np.random.default_rng(spawned).standard_normal(3))
    assert np.array_equal(nxt, np.random.default_rng(np.random.SeedSequence(9).spawn(2)[1]).standard_normal(3))
    mt = np.random.Generator(np.random.MT19937(4))
    assert isinstance(children(mt, 1)[0].bit_generator, np.random.MT19937)
    with pytest.raises(TypeError):
        children(np.random.RandomState(1), 1)             # a legacy source has no SeedSequence
