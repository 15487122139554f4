"""The upper-stage loop's engagement at the J-2X start, in flight (issue 26 item 8).

The corner: the dispersed batches' worst separation state. In the 200-run full-fidelity
batch of docs/design_studies.md the vehicle separated up to 2.5° off its command in
pitch (run 197: −2.48°, −0.57 deg/s) and 1.8° in yaw (run 14: −1.82°, −0.16 deg/s),
left so by the first-stage tail-off. The default upper-stage flight is started from the
shipped staging state (−0.23 deg/s pitch, −0.01 deg/s yaw) with its attitude turned by
both errors at once and its rates brought to those, at full fidelity (4 bending modes,
slosh, tail-wags-dog). Before the engagement law (``models/fcs.py::engagement``) this
corner held the J-2X nozzle on its 15 deg/s rate limit for 0.16 s, from separation,
and on its 5° gimbal stop for 0.70 s; with it the nozzle peaks at 3.8 deg/s, 2.9 s after
the ignition command (measured). The same corner flown with the fade switched off (gains
stepped in at the ignition command) touches the limit (0.20 s) and the stop (0.72 s):
the fade is what keeps it inside.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from conftest import compose_config
from savant_cli.config import validate
from savant_cli.models import quaternion as qt
from savant_cli.paths import shipped_config_dir
from savant_cli.studies import flight as flight_mod

#: The corner's attitude error at separation (body pitch, yaw; deg) and the body rates
#: added to the staging state's (deg/s): −0.57 deg/s pitch and −0.16 deg/s yaw in all.
ERROR_DEG = (-2.5, -1.8)
RATE_DEG_S = (-0.34, -0.15)
#: The upper-stage TVC rate limit (deg/s; conf/actuator/third_order.yaml).
RATE_LIMIT_DEG_S = 15.0


def _corner_state(tmp_path: Path) -> Path:
    """The shipped staging state turned ERROR_DEG off its command, with RATE_DEG_S added."""
    doc = json.loads((shipped_config_dir() / "phase" / "ares_i_peg_staging_state.json").read_text())
    s = doc["state"]
    q = qt.qmul(np.array([s["q_w"], s["q_x"], s["q_y"], s["q_z"]]),
                qt.from_rotation_vector(np.radians([0.0, *ERROR_DEG])))
    s["q_w"], s["q_x"], s["q_y"], s["q_z"] = map(float, q)
    s["q"] += float(np.radians(RATE_DEG_S[0]))
    s["r"] += float(np.radians(RATE_DEG_S[1]))
    path = tmp_path / "corner_staging_state.json"
    path.write_text(json.dumps(doc))
    return path


def _fly(tmp_path: Path, extra: list[str]) -> dict:
    cfg = validate(compose_config(["phase=upper_stage", f"phase.staging_state_file={_corner_state(tmp_path)}",
                                   "flex=on", "flex.n_modes=4", "slosh=on", "twd=on", "sim.max_time_s=150",
                                   "sim.progress=false"] + extra))
    assert cfg.actuator.upper_stage.rate_limit_deg_s == RATE_LIMIT_DEG_S
    return flight_mod.fly(cfg, progress=False).summary


@pytest.mark.slow
def test_the_worst_separation_state_starts_the_j2x_clear_of_the_rate_limit(tmp_path):
    s = _fly(tmp_path, [])
    assert s["time_upper_stage_ignition_s"] < 135.0  # the start-up was flown
    assert s["time_at_rate_limit_upper_stage_s"] == 0.0 and s["time_at_gimbal_stop_upper_stage_s"] == 0.0
    assert s["max_gimbal_rate_upper_stage_deg_s"] < RATE_LIMIT_DEG_S


@pytest.mark.slow
def test_without_the_fade_the_same_corner_touches_the_rate_limit(tmp_path):
    s = _fly(tmp_path, ["controller.ignition_fade.start_s=0", "controller.ignition_fade.end_s=0"])
    assert s["time_at_rate_limit_upper_stage_s"] > 0.0 and s["time_at_gimbal_stop_upper_stage_s"] > 0.0
    assert s["max_gimbal_rate_upper_stage_deg_s"] == pytest.approx(RATE_LIMIT_DEG_S)
