"""Every field the models declare in the plant's vectors has units and a description,
the vectors are laid out without gaps or overlaps, and docs/models.md lists every field
exactly as declared."""

from __future__ import annotations

from pathlib import Path

import savant_cli.models  # noqa: F401  (declares every field)
from savant_cli.models import blocks, layout
from savant_cli.models.__main__ import field_reference

DOCS = Path(__file__).resolve().parents[1] / "docs" / "models.md"


def test_every_field_has_units_and_a_description():
    for f in layout.all_fields():
        assert f.units.strip(), f.key
        assert len(f.description.strip()) > 3, f.key


def test_vectors_are_contiguous_and_sized_as_the_layout_says():
    for vector, size in ((blocks.STATE, layout.N_STATE), (blocks.PARAMETERS, layout.N_PARAM), (blocks.DIAGNOSTICS, layout.N_AUX),
                         (blocks.DISCRETE, layout.N_DISC), (blocks.INPUTS, layout.N_INPUT)):
        pos = 0
        for f in vector.fields:
            assert f.index == pos, f"{vector.name}: {f.key} at {f.index}, expected {pos}"
            pos += f.size
        assert pos == size == vector.size
    assert [f.index for f in blocks.TABLES.fields] == list(range(len(blocks.TABLES.fields)))


def test_core_state_order_is_the_staging_file_order():
    """The staging-state files and the logged histories name the states in this order:
    the rigid body, the vehicle's tanks in order, the gimbal channels, the roll jets, then
    the optional blocks; a model imported out of order would silently move them."""
    assert layout.STATE_NAMES[:layout.W + 3][-3:] == ["p", "q", "r"]
    lay = layout.StateLayout(tanks=("grain", "lox", "lh2"), simplex=True, slosh_tanks=("lox", "lh2"), n_modes=2)
    assert (layout.R, layout.V, layout.Q, layout.W, layout.N_STATE) == (0, 3, 6, 10, 13)
    assert ([lay.tank(t) for t in lay.tanks], lay.channel(0), lay.channel(1), lay.rcs, lay.n_core) == (
        [13, 14, 15], 16, 19, 22, 24)
    assert (lay.valve, lay.slosh_offset, lay.flex, lay.n) == (24, 28, 36, 40)
    names = lay.names()
    assert names[13:24] == ["prop_grain", "prop_lox", "prop_lh2", "dp", "dp_dot", "dp_piston", "dy", "dy_dot",
                            "dy_piston", "rcs_pos", "rcs_neg"]
    assert names[24:28] == ["valve_p", "valve_p_dot", "valve_y", "valve_y_dot"] and len(names) == lay.n


def test_docs_list_every_field_as_declared():
    text = DOCS.read_text(encoding="utf-8")
    begin, end = "<!-- field reference: begin -->\n", "\n<!-- field reference: end -->"
    assert begin in text and end in text
    documented = text.split(begin, 1)[1].split(end, 1)[0]
    assert documented == field_reference(), "docs/models.md is stale: run `python -m savant_cli.models`"
