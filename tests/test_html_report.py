"""``report.html`` (savant_cli/html_report.py): its verdicts, configuration diff and
events from the run folder, its self-containment, its regeneration by ``savant report``,
and the page in a real headless Chromium (tests/browser.py): no console error, no broken
image, a screenshot that is not blank. The browser check is itself checked on pages made
to fail it."""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest

import savant_cli
from browser import check_page, find_chromium, is_blank
from conftest import assert_report_page, assert_report_redraws
from savant_cli.html_report import config_diff, verdicts

ROOT = Path(__file__).resolve().parents[1]
#: .ci/run sets it: there a missing Chromium is a failure, not a skip
REQUIRE = os.environ.get("SAVANT_REQUIRE_CHROMIUM") == "1"


def _chromium():
    if find_chromium() is None:
        if REQUIRE:
            pytest.fail("SAVANT_REQUIRE_CHROMIUM=1 but no Chromium on PATH")
        pytest.skip("no Chromium on PATH (apt-get install chromium)")


@pytest.fixture(scope="module")
def short_run(tmp_path_factory):
    return savant_cli.run(["sim.max_time_s=140", "sim.progress=false", "winds=design_gust"],
                          out_dir=tmp_path_factory.mktemp("report") / "short")


def test_a_study_writes_its_page_and_report_writes_it_again(short_run):
    page = short_run.run_dir / "report.html"
    assert page.is_file()
    assert_report_page(short_run.run_dir)
    assert_report_redraws(short_run.run_dir)  # same figures, same page


def test_verdicts_name_what_fails(short_run):
    """The design gust takes the flight (to 140 s, past separation) above the q-alpha allowable: that line is
    red (False) while the status stays complete (green)."""
    lines = dict(verdicts(short_run))
    status = next(k for k in lines if k.startswith("status: "))
    assert lines[status] is True
    loads = next(k for k in lines if k.startswith("loads: "))
    assert "EXCEEDED" in loads and lines[loads] is False
    text = (short_run.run_dir / "report.html").read_text()
    assert 'class="verdict bad">loads: max q·α_total' in text


def test_config_diff_lists_exactly_the_overrides(short_run):
    """Against the shipped defaults the run differs in sim.max_time_s, sim.progress and the
    winds group's keys, and in nothing else."""
    diff = {k: (d, v) for k, d, v in config_diff(short_run)}
    assert diff["sim.max_time_s"][1] == 140
    assert diff["winds.name"] == ("ksc_mean_annual", "design_gust")
    assert diff["winds.gust.enabled"] == (False, True)
    assert {k.split(".")[0] for k in diff} == {"sim", "winds"}
    assert {k for k in diff if k.startswith("sim.")} == {"sim.max_time_s", "sim.progress"}


def test_events_and_provenance_are_on_the_page(short_run):
    text = (short_run.run_dir / "report.html").read_text()
    assert "<svg" in text and 'aria-label="events timeline"' in text
    assert short_run.provenance["savant_version"] in text
    for name, t in short_run.events.items():
        assert f"{name} {t:.2f} s" in text


def test_the_browser_check_fails_a_broken_page(tmp_path):
    """A broken image, a console error and a blank page are each seen."""
    _chromium()
    bad = tmp_path / "bad.html"
    bad.write_text('<!DOCTYPE html><html><head><title>bad</title></head><body><p>text</p>'
                   '<img alt="broken" src="data:image/png;base64,AAAA"><script>console.error("boom")</script>'
                   "</body></html>")
    seen = check_page(bad)
    assert seen.broken_images == ["broken"] and any("boom" in e for e in seen.console_errors)
    blank = tmp_path / "blank.html"
    blank.write_text("<!DOCTYPE html><html><body></body></html>")
    assert is_blank(check_page(blank).screenshot_png)


def _assert_renders(run_dir: Path) -> bytes:
    seen = check_page(run_dir / "report.html")
    assert seen.console_errors == [] and seen.broken_images == []
    assert seen.images == len(list((run_dir / "plots").rglob("*.png"))) > 0
    assert seen.sections == 6 and seen.title.startswith("savant ")
    assert not is_blank(seen.screenshot_png)
    return seen.screenshot_png


@pytest.mark.slow
def test_reports_render_in_headless_chromium(tmp_path, short_run):
    """A flight, a linear study and a Monte Carlo: each page loads in Chromium with no
    console error and no broken image, and its screenshot is not blank."""
    _chromium()
    lin = savant_cli.run(["study=linear", "study.times=[55,130]", "sim.progress=false"], out_dir=tmp_path / "lin")
    mc = savant_cli.run(["study=montecarlo", "study.n_runs=4", "study.workers=1", "sim.progress=false",
                         "study.linear_times=[55]"], out_dir=tmp_path / "mc")
    for r in (short_run, lin, mc):
        _assert_renders(r.run_dir)
        assert re.search(r'class="verdict (ok|bad)">status: ', (r.run_dir / "report.html").read_text())
