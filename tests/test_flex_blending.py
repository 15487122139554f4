"""The shipped stack rate blending nulls the first bending mode in the blended rate, and
the design rule behind it (independent hand computation from the modal data)."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import compose_config
from savant_cli.config import validate
from savant_cli.datagen.flex_filters import stack_blend
from savant_cli.models import layout
from savant_cli.sim.setup import prepare


def test_stack_blend_rule():
    w = stack_blend(2.0e-4, -1.0e-4)
    assert w == [pytest.approx(1 / 3, abs=1e-3), 0.0, pytest.approx(2 / 3, abs=1e-3)]
    with pytest.raises(ValueError):
        stack_blend(2.0e-4, 1.0e-4)  # same sign: no positive-weight null


def test_design_rule_blend_nulls_first_bending_in_both_planes():
    """The design rule's blend (``flex_filters.vehicle_stack_blend``, where study=fcs_design
    starts; the shipped msfc_pid's is tuned from it) nulls the first bending mode's slope
    at the gyros in both planes."""
    from savant_cli.datagen.flex_filters import vehicle_stack_blend

    cfg = validate(compose_config(["flex=on", "flex.n_modes=2"]))
    prep = prepare(cfg)
    model = prep.model
    w = np.asarray(vehicle_stack_blend(cfg.vehicle, prep.vehicle_dir))
    shapes = model.tables.flex_shape[0]  # first-stage liftoff set, (modes, points, 6)
    for mode, comp in ((0, 4), (1, 5)):  # 1st bending x–z plane: body y rotation; x–y plane: body z
        slopes = np.array([shapes[mode, pt, comp] for pt in layout.GYRO_POINTS])
        assert abs(slopes[0]) > 1e-5 and slopes[0] * slopes[2] < 0  # opposite signs: a null exists
        assert abs(w @ slopes) < 0.01 * abs(slopes[0])  # the blended slope is nulled to 1 %
    # and the rigid rate passes unchanged
    assert w.sum() == pytest.approx(1.0)
