"""``python -m savant_cli.models``: print the reference table of every plant field (the
one in ``docs/models.md``; ``tests/test_field_reference.py`` keeps the two equal)."""

from __future__ import annotations

from savant_cli.models import layout  # every model is imported first; layout declares the held inputs


def field_reference() -> str:
    """Markdown table of every declared field of the plant's vectors.

    Returns
    -------
    str
        One row per field: vector, key, size (``table`` for packed tables), SI units and
        description (with the frame and the signal name of a logged diagnostic), in
        declaration order.
    """
    lines = ["| vector | field | size | units | description |", "|---|---|---|---|---|"]
    for f in layout.all_fields():
        size = "table" if f.vector == "tb" else str(f.size)
        text = f.description
        if f.logged is not None:
            text += (f", {f.logged.frame}" if f.logged.frame else "") + f"; logged as `{f.logged.name}`"
        lines.append(f"| `{f.vector}` | `{f.key}` | {size} | {f.units} | {text} |")
    return "\n".join(lines)


if __name__ == "__main__":
    print(field_reference())
