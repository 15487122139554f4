"""``python -m savant_cli.models``: print the reference table of every plant field (the
one in ``docs/models.md``)."""

from savant_cli.models import blocks

print(blocks.field_reference())
