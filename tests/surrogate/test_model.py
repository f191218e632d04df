import dataclasses
import json
from unittest import mock

import numpy as np
import pytest
import torch

from wrp_eval.atomic import temporaries
from wrp_eval.errors import InputError
from wrp_eval.surrogate.model import CHECKPOINT_VERSION, Surrogate, ViewQuery
from wrp_eval.surrogate.scarce import ScarceCoverage

from .conftest import random_surrogate


@pytest.mark.parametrize("kernel,layers,per_view", [(3, 2, False), (5, 2, False), (3, 3, False), (1, 1, False),
                                                     (3, 2, True), (5, 3, True)])
def test_view_query_matches_full_forward(kernel, layers, per_view):
    """The incremental one-view evaluation equals a full forward pass, at the ends and in the middle (with the
    per-view inputs too: the flown geometry changes with the candidate)."""
    s = random_surrogate(9, kernel=kernel, layers=layers, per_view=per_view)
    rng = np.random.default_rng(1)
    base = rng.normal(0, 1, (9, 4))
    query = ViewQuery(s, base)
    for view in (0, 1, 4, 7, 8):
        cand = rng.normal(0, 1, (6, 4))
        full = np.repeat(base[None], 6, axis=0)
        full[:, view] = cand
        np.testing.assert_allclose(query.errors(view, cand), s.predict(full), atol=2e-5)
    assert query.forward_calls == 5 and query.queries == 30


@pytest.mark.parametrize("kernel,layers", [(3, 2), (5, 3)])
def test_view_query_matches_full_forward_with_the_scarce_channel(ring_scarce, kernel, layers):
    """The scarce coverage lost changes with the candidate too, and the one-view evaluation still equals the
    full pass; the channel does move the prediction."""
    s = random_surrogate(len(ring_scarce), kernel=kernel, layers=layers, scarce=ring_scarce)
    rng = np.random.default_rng(2)
    base = rng.normal(0, 0.5, (9, 4)) * [2, 2, 2, 0.1]
    query = ViewQuery(s, base)
    for view in (0, 4, 8):
        cand = rng.normal(0, 1, (6, 4)) * [3, 3, 3, 0.2]
        full = np.repeat(base[None], 6, axis=0)
        full[:, view] = cand
        np.testing.assert_allclose(query.errors(view, cand), s.predict(full), atol=2e-5)
    moving = s.moving_features(full)
    assert moving.shape == (6, 9, 4) and np.ptp(moving[:, 8, 3]) > 0.5
    with mock.patch.object(ScarceCoverage, "lost", lambda self, view, off: np.zeros(len(off))):
        blind = s.predict(full)                  # the same network with the scarce channel held at 0
    assert np.max(np.abs(blind - s.predict(full))) > 1e-6


def test_a_view_not_taken_loses_its_whole_scarce_share(ring_scarce):
    """With conditions that say view 4 was not photographed, its scarce channel is the view's whole removal, not
    the loss at its (meaningless, zero) offset."""
    s = random_surrogate(len(ring_scarce), scarce=ring_scarce)
    off = np.zeros((2, 9, 4))
    taken = np.ones((2, 9), bool)
    taken[1, 4] = False
    moving = s.moving_features(off, taken=taken)
    assert moving[0, 4, 3] == pytest.approx(0.0, abs=1e-9)
    assert moving[1, 4, 3] == ring_scarce.removal[4] > 0.0
    np.testing.assert_array_equal(np.delete(moving[1], 4, axis=0), np.delete(moving[0], 4, axis=0))
    cond = np.broadcast_to(s.views.condition_reference, (2, 9, 5)).copy()
    cond[1, 4, -1] = 0.0
    y = s.predict(off, cond)
    cond[1, 4, -1] = 1.0
    assert y[1] != s.predict(off, cond)[1]


def test_a_scarce_checkpoint_needs_the_coverage_it_was_trained_on(tmp_path, ring_scarce):
    s = random_surrogate(len(ring_scarce), scarce=ring_scarce)
    s.save(tmp_path / "s.pt")
    again = Surrogate.load(tmp_path / "s.pt", inputs="scarce", scarce=ring_scarce)
    off = np.random.default_rng(0).normal(0, 1, (4, 9, 4))
    np.testing.assert_array_equal(again.predict(off), s.predict(off))
    with pytest.raises(InputError, match="not given to the loader") as err:
        Surrogate.load(tmp_path / "s.pt", inputs="scarce")
    assert "\n" not in str(err.value)
    other = dataclasses.replace(ring_scarce, level=3.0)
    with pytest.raises(InputError, match="another ship, oracle or plan"):
        Surrogate.load(tmp_path / "s.pt", scarce=other)
    built = []
    lazily = Surrogate.load(tmp_path / "s.pt", scarce=lambda: built.append(1) or ring_scarce)
    assert built == [1] and lazily.scarce is ring_scarce
    with pytest.raises(InputError, match="input set 'scarce', the config asks for 'per_view'"):
        Surrogate.load(tmp_path / "s.pt", inputs="per_view", scarce=lambda: built.append(2) or ring_scarce)
    assert built == [1]                          # the config's mismatch is named before any coverage is built


def test_a_per_view_checkpoint_without_the_scarce_field_loads(tmp_path):
    """Checkpoints of the other input sets carry no scarce_digest (and those saved before it existed load)."""
    s = random_surrogate(6, per_view=True)
    s.save(tmp_path / "s.pt")
    doc = torch.load(tmp_path / "s.pt", weights_only=True)
    assert "scarce_digest" not in json.loads(doc["metadata_json"])
    off = np.random.default_rng(0).normal(0, 1, (2, 6, 4))
    np.testing.assert_array_equal(Surrogate.load(tmp_path / "s.pt").predict(off), s.predict(off))


def test_view_query_update_view_moves_the_base():
    s = random_surrogate(6)
    query = ViewQuery(s, np.zeros((6, 4)))
    off = np.array([0.5, -0.2, 0.1, 0.05])
    query.update_view(2, off)
    expect = np.zeros((1, 6, 4))
    expect[0, 2] = off
    cand = np.array([[0.1, 0.1, 0.1, 0.0]])
    expect_q = expect.copy()
    expect_q[0, 4] = cand[0]
    np.testing.assert_allclose(query.errors(4, cand), s.predict(expect_q), atol=2e-5)


def test_checkpoint_round_trip(tmp_path):
    s = random_surrogate(7, digest="abc123")
    file = tmp_path / "s.pt"
    s.save(file)
    loaded = Surrogate.load(file, n_views=7, path_digest="abc123")
    x = np.random.default_rng(0).normal(size=(5, 7, 4))
    np.testing.assert_array_equal(loaded.predict(x), s.predict(x))
    assert loaded.meta == s.meta
    assert temporaries(tmp_path) == []


def test_checkpoint_refuses_other_path(tmp_path):
    s = random_surrogate(7, digest="abc123")
    s.save(tmp_path / "s.pt")
    with pytest.raises(InputError, match="7 viewpoints"):
        Surrogate.load(tmp_path / "s.pt", n_views=8)
    with pytest.raises(InputError, match="trained for path abc123"):
        Surrogate.load(tmp_path / "s.pt", n_views=7, path_digest="ffff")


def test_checkpoint_refuses_corrupt_foreign_and_old_files(tmp_path):
    s = random_surrogate(5)
    good = tmp_path / "s.pt"
    s.save(good)
    data = good.read_bytes()
    (tmp_path / "cut.pt").write_bytes(data[: len(data) // 2])
    (tmp_path / "text.pt").write_text("hello")
    torch.save({"weights": torch.zeros(2)}, tmp_path / "foreign.pt")
    doc = torch.load(good, weights_only=True)
    doc["version"] = 99
    torch.save(doc, tmp_path / "old.pt")
    doc["version"] = CHECKPOINT_VERSION
    doc["state_dict"] = {k: v for k, v in list(doc["state_dict"].items())[:-1]}
    torch.save(doc, tmp_path / "missing.pt")
    for name, pattern in [("cut.pt", "not a readable"), ("text.pt", "not a readable"),
                          ("foreign.pt", "not a wrp-eval surrogate"), ("old.pt", "version 99"),
                          ("missing.pt", "damaged"), ("absent.pt", "no such")]:
        with pytest.raises(InputError, match=pattern) as err:
            Surrogate.load(tmp_path / name)
        assert "\n" not in str(err.value)


def test_checkpoint_is_not_a_pickle_of_objects(tmp_path):
    """A file holding an arbitrary Python object is refused by weights_only loading."""
    import argparse
    torch.save({"format": "wrp-eval-surrogate", "obj": argparse.Namespace(a=1)}, tmp_path / "evil.pt")
    with pytest.raises(InputError, match="not a readable"):
        Surrogate.load(tmp_path / "evil.pt")


def test_predict_checks_shape():
    s = random_surrogate(4)
    with pytest.raises(ValueError):
        s.predict(np.zeros((2, 5, 4)))


def test_checkpoint_refuses_an_older_format_and_another_input_set(tmp_path):
    """Version-1 checkpoints (before the per-view inputs) and a checkpoint of another input set than the config
    asks for are refused with one line."""
    s = random_surrogate(6, per_view=True)
    s.save(tmp_path / "s.pt")
    assert Surrogate.load(tmp_path / "s.pt", inputs="per_view").meta.inputs == "per_view"
    with pytest.raises(InputError, match="input set 'per_view', the config asks for 'offsets'") as err:
        Surrogate.load(tmp_path / "s.pt", inputs="offsets")
    assert "\n" not in str(err.value)
    doc = torch.load(tmp_path / "s.pt", weights_only=True)
    doc["version"] = 1
    torch.save(doc, tmp_path / "v1.pt")
    with pytest.raises(InputError, match="version 1 is not"):
        Surrogate.load(tmp_path / "v1.pt")


def test_per_view_inputs_see_the_conditions_and_default_to_the_forecast():
    s = random_surrogate(6, per_view=True)
    off = np.random.default_rng(0).normal(0, 0.5, (3, 6, 4))
    ref = np.broadcast_to(s.views.condition_reference, (3, 6, 5))
    np.testing.assert_allclose(s.predict(off), s.predict(off, ref), atol=1e-6)
    windy = np.array(ref) + [20.0, 8.0, 0.0, 0.0, 0.0]
    assert np.all(np.abs(s.predict(off, windy) - s.predict(off)) > 1e-6)
    nan = np.array(windy)
    nan[:, 2] = np.nan                     # not recorded at view 2: the forecast stands in
    expect = np.array(windy)
    expect[:, 2] = ref[:, 2]
    np.testing.assert_allclose(s.predict(off, nan), s.predict(off, expect), atol=1e-6)
