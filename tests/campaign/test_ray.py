"""The Ray backend (on a local Ray instance) gives the same records as the local backend for the same seed,
and a worker's set-up error stops the campaign with its message."""

from __future__ import annotations

import pytest
import ray  # the [cluster] extra; `make test` installs it, so its absence is a failure, not a skip

from wrp_eval.campaign.store import TrialStore
from wrp_eval.errors import InputError


def test_ray_matches_local_and_shuts_down_its_instance(tmp_path, path_file, make_config, comparable, run_analytic):
    local = run_analytic(make_config(path_file, n_trials=10), tmp_path / "local", fail_trial_ids=[3])
    on_ray = run_analytic(make_config(path_file, n_trials=10, backend={"kind": "ray", "workers": 2}),
                          tmp_path / "ray", fail_trial_ids=[3])
    assert on_ray.done == 10 and on_ray.errors == 1
    assert not ray.is_initialized()   # the instance started for the campaign was shut down
    assert comparable(TrialStore(local.out_dir).read_table()) == comparable(TrialStore(on_ray.out_dir).read_table())


def test_ray_set_up_error_is_the_campaigns_input_error(tmp_path, path_file, make_config):
    from wrp_eval.campaign.jobs import campaign_job
    from wrp_eval.config import ExperimentConfig
    from wrp_eval.experiment import ExperimentContext
    doc = make_config(path_file, backend={"kind": "ray", "workers": 1}).model_dump(mode="json")
    doc["ship"]["mesh"] = {"path": str(tmp_path / "no_such_ship.stl")}
    ray.init(num_cpus=1, include_dashboard=False, log_to_driver=False)   # reused by the campaign
    try:
        with pytest.raises(InputError, match="no_such_ship"):
            campaign_job(ExperimentContext(ExperimentConfig.model_validate(doc)), out_dir=tmp_path / "c")
        assert ray.is_initialized()   # an instance the caller started is left running
    finally:
        ray.shutdown()
