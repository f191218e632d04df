"""Bad capture-realism settings (issue 16) are one line naming the key, exit status 2, nothing written."""

import pytest

from wrp_eval.cli import main


@pytest.mark.parametrize("yaml_text, key", [
    ("sim: {navigation: {preset: galileo-hd}}\n", "sim.navigation.preset"),
    ("sim: {navigation: {horizontal_sigma_m: -0.5}}\n", "sim.navigation.horizontal_sigma_m"),
    ("sim: {capture: {exposure_s: 0}}\n", "sim.capture.exposure_s"),
    ("sim: {capture: {mode: hover-and-pray}}\n", "sim.capture.mode"),
    ("sim: {battery: {reserve: 1.0}}\n", "sim.battery.reserve"),
    ("sim: {gimbal: {pitch_range_deg: [30, -90]}}\n", "sim.gimbal"),
    ("ship: {motion: {sea_state: 9}}\n", "ship.motion.sea_state"),
    ("wind: {air_wake: {lee_deficit: -0.2}}\n", "wind.air_wake.lee_deficit"),
    # the mission section (issue 26)
    ("sim: {mission: {max_sorties: 0}}\n", "sim.mission.max_sorties"),
    ("sim: {mission: {swap_time_s: -5}}\n", "sim.mission.swap_time_s"),
    ("sim: {mission: {px4_wind_limit_m_s: -1}}\n", "sim.mission.px4_wind_limit_m_s"),
    ("sim: {mission: {headway_timeout_s: 0}}\n", "sim.mission.headway_timeout_s"),
    ("sim: {mission: {battery_swaps: 2}}\n", "sim.mission.battery_swaps"),
    ("sim: {wind_limit_m_s: -3}\n", "sim.mission.operator_wind_limit_m_s"),
])
def test_bad_capture_settings_exit_2_with_one_line(tmp_path, capsys, yaml_text, key):
    config = tmp_path / "bad.yaml"
    config.write_text(yaml_text)
    out = tmp_path / "out"
    assert main(["campaign", str(config), "--trials", "1", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and key in err[0] and str(config) in err[0]
    assert not out.exists()
