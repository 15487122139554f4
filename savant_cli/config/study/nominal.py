"""``study=nominal``: one flight."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass
class StudyConfig:
    """``study=nominal``: one flight."""

    name: str = "nominal"
