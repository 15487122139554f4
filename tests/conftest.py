"""Shared fixtures: composing configs with hydra.compose, as `savant run` does."""

from __future__ import annotations

import pytest
from hydra import compose, initialize_config_dir

from savant_cli.config import linear_settings  # noqa: F401  (the tests import it from here)
from savant_cli.paths import shipped_config_dir


def compose_config(overrides: list[str] | None = None):
    """The raw composed config (DictConfig) for the given overrides."""
    with initialize_config_dir(config_dir=str(shipped_config_dir()), version_base="1.3"):
        return compose(config_name="config", overrides=list(overrides or []))


@pytest.fixture
def compose_cfg():
    return compose_config


# The plot modules must never use matplotlib.pyplot (global state, GUI backends): the
# tests check their source and run them in an interpreter where pyplot is this stub.
PYPLOT_STUB = """
import sys, types
class Stub(types.ModuleType):
    def __getattr__(self, name):
        raise AssertionError(f"pyplot.{name} used")
sys.modules["matplotlib.pyplot"] = Stub("matplotlib.pyplot")
"""


def imported_names(path) -> list[str]:
    """Every module and name a Python source file imports (``a.b`` and ``a.b.name``)."""
    import ast
    from pathlib import Path

    tree = ast.parse(Path(path).read_text(encoding="utf-8"))
    names = [a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names]
    return names + [f"{n.module}.{a.name}" for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) for a in n.names]


def assert_report_redraws(run_dir) -> list[str]:
    """``savant report`` on a finished study: with the study's own ``plots/`` moved away,
    it draws every figure again from ``savant.h5`` alone, byte for byte the same PNGs
    (same names, same pixels), and nothing else; it writes ``report.html`` again, the
    same bytes as the study's own when the study wrote one (:func:`assert_report_page`).
    Returns the relative names."""
    import shutil
    from pathlib import Path

    from rich.console import Console

    from savant_cli.report import report

    run_dir = Path(run_dir)
    page = run_dir / "report.html"
    page_as_written = page.read_bytes() if page.is_file() else None
    first = run_dir.parent / f"{run_dir.name}_plots_as_drawn"
    shutil.move(run_dir / "plots", first)
    try:
        paths = report(run_dir, console=Console(quiet=True))
        assert_report_page(run_dir)
        if page_as_written is not None:
            assert page.read_bytes() == page_as_written
        drawn = sorted(str(p.relative_to(first)) for p in first.rglob("*.png"))
        again = sorted(str(p.relative_to(run_dir / "plots")) for p in (run_dir / "plots").rglob("*.png"))
        assert again == drawn, (set(drawn) ^ set(again))
        assert sorted(str(p.relative_to(run_dir / "plots")) for p in paths) == drawn
        for name in drawn:
            assert (first / name).read_bytes() == (run_dir / "plots" / name).read_bytes(), name
        assert_result_plots(run_dir, drawn)
        return drawn
    finally:
        shutil.rmtree(first, ignore_errors=True)


def assert_result_plots(run_dir, drawn: list[str]) -> None:
    """``Result.plot`` returns every figure the study drew: each PNG outside ``linear/``
    (whose charts it draws by chart name and time) is one of ``figure_names()``, and the
    figure ``plot`` returns for the first and the last of the study's own, written by the
    drawing base as ``savant report`` writes that PNG (``Figure.savefig``, or rendered
    and encoded without alpha), is the same file byte for byte."""
    import io
    import tempfile
    from pathlib import Path

    from savant_cli.plots.figure import DPI, PNG_LEVEL, render, write_png
    from savant_cli.result import load

    result = load(run_dir)
    names = set(result.figure_names())
    stems = [n[:-len(".png")] for n in drawn if not n.startswith("linear/")]
    assert not [s for s in stems if s not in names], sorted(set(stems) - names)
    own = [s for s in stems if s in result._study_figures]
    for stem in own[:1] + own[-1:]:
        fig, png = result.plot(stem), (Path(run_dir) / "plots" / f"{stem}.png").read_bytes()
        if png[25] == 2:  # IHDR colour type 2, RGB: rendered and encoded without alpha (save_rendered)
            with tempfile.TemporaryDirectory() as tmp:
                again = write_png(render(fig), Path(tmp) / "fig.png").read_bytes()
        else:  # colour type 6, RGBA: Figure.savefig (save_figure)
            buf = io.BytesIO()
            fig.savefig(buf, format="png", dpi=DPI, pil_kwargs={"compress_level": PNG_LEVEL})
            again = buf.getvalue()
        assert again == png, stem


def assert_report_page(run_dir) -> None:
    """``report.html`` of a run folder is one self-contained page: every image a PNG
    embedded as a ``data:`` URI that decodes (one per PNG of ``plots/``), no external
    resource (``src``/``href`` to anything but an in-page anchor or data), no script,
    and the six sections."""
    import base64
    import html.parser
    from pathlib import Path

    run_dir = Path(run_dir)

    class Page(html.parser.HTMLParser):
        def __init__(self):
            super().__init__()
            self.images, self.external, self.scripts, self.sections = [], [], 0, []

        def handle_starttag(self, tag, attrs):
            a = dict(attrs)
            if tag == "img":
                self.images.append(a.get("src", ""))
            if tag == "script":
                self.scripts += 1
            if tag == "section":
                self.sections.append(a.get("id"))
            for key in ("src", "href"):
                v = a.get(key)
                if v is not None and not (v.startswith("#") or v.startswith("data:")):
                    self.external.append(v)

    page = Page()
    page.feed((run_dir / "report.html").read_text(encoding="utf-8"))
    assert page.sections == ["verdicts", "summary", "events", "figures", "config", "provenance"]
    assert not page.external and page.scripts == 0
    n_png = len(list((run_dir / "plots").rglob("*.png"))) if (run_dir / "plots").is_dir() else 0
    assert len(page.images) == n_png
    for src in page.images:
        assert src.startswith("data:image/png;base64,")
        assert base64.b64decode(src.split(",", 1)[1])[:8] == b"\x89PNG\r\n\x1a\n"
