"""``report.html`` (savant_cli/html_report.py): its verdicts, configuration diff and
events from the run folder, its self-containment, its regeneration by ``savant report``,
and the page in a real headless Chromium (tests/browser.py): no console error, no broken
image, a screenshot that is not blank. The browser check is itself checked on pages made
to fail it."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

import savant_cli
from browser import assert_page_reads, check_page, clipped_labels, is_blank, overlapping_labels, require_chromium
from conftest import assert_report_page, assert_report_redraws
from savant_cli.html_report import (
    LABEL_CHAR_W, TIMELINE_LEFT, TIMELINE_WIDTH, WORST_PREFIX, config_diff, timeline_layout, verdicts
)
from savant_cli.html_tables import summary_tables, worst_offender

ROOT = Path(__file__).resolve().parents[1]
#: .ci/run sets it: there a missing Chromium is a failure, not a skip
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
    require_chromium()
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
    require_chromium()
    lin = savant_cli.run(["study=linear", "study.times=[55,130]", "sim.progress=false"], out_dir=tmp_path / "lin")
    mc = savant_cli.run(["study=montecarlo", "study.n_runs=4", "study.workers=1", "sim.progress=false",
                         "study.linear_times=[55]"], out_dir=tmp_path / "mc")
    for r in (short_run, lin, mc):
        _assert_renders(r.run_dir)
        assert re.search(r'class="verdict (ok|bad)">status: ', (r.run_dir / "report.html").read_text())


# ------------------------------------------------------------- a page a reviewer reads
def _page_text(html_text: str) -> str:
    """The text of an HTML fragment (tags dropped, entities decoded)."""
    import html as _html

    return _html.unescape(re.sub(r"<[^>]+>", " ", html_text))


MC_LIKE = {
    "loads": {"runs_with_results": 50, "max_qalpha_Pa_deg": {"max": 168769.8129200502, "max_run": 26},
              "max_qbeta_Pa_deg": {"max": 53277.6, "max_run": 3}, "runs_above_qalpha_limit_list": [26, 31]},
    "requirements": {"set": "ares_i", "passed": False, "line": "requirements ares_i: FAIL",
                     "points": [{"time_s": 55.0, "stage": "first_stage", "passed": True,
                                 "worst": {"time_s": 55.0, "axis": "yaw", "mode": "aero", "criterion": "gain margin",
                                           "value": -7.47999999999997, "required": 6.0, "unit": "dB"}},
                                {"time_s": 130.0, "stage": "first_stage", "passed": False,
                                 "worst": {"time_s": 130.0, "axis": "yaw", "mode": "rigid",
                                           "criterion": "phase margin", "value": 14.6, "required": 30.0,
                                           "unit": "deg"}}]},
    "margin_spread": [{"time_s": 55.0, "axis": "pitch", "kind": "gain", "worst": 13.26958573859917, "worst_run": 4,
                       "runs_below_requirement": 0},
                      {"time_s": 55.0, "axis": "pitch", "kind": "phase", "worst": 28.1, "worst_run": 7,
                       "runs_below_requirement": 2}],
}


def test_summary_tables_are_tables_with_units_and_significant_digits():
    """The issue's reprs (``{'max': 168769.8129200502, 'max_run': 26}``) and float noise
    (``7.47999999999997``) become table cells: 168,800 under max, 26 under max run, the
    unit in the row's name, -7.48 in a flattened ``worst value`` column."""
    page = summary_tables(MC_LIKE, worst_offender(MC_LIKE))
    text = _page_text(page)
    assert "{" not in text and "}" not in text and "7.4799" not in text and "168769" not in text
    assert '<td class="num">168,800</td><td class="num">26</td>' in page
    assert "max qalpha (Pa·deg)" in text and "worst value" in text and '<td class="num">-7.48</td>' in page
    assert "26, 31" in text
    assert page.count("<table") == 5  # loads scalars, loads by quantity, requirements, its points, margin spread


def test_worst_offender_is_the_smallest_requirement_ratio_and_is_highlighted():
    """14.6 deg of 30 (0.49) is worse than 7.48 dB of 6 (1.25); its row is marked, and the
    failing rows (passed false, runs below the requirement) are red."""
    worst = worst_offender(MC_LIKE)
    assert worst is not None and worst.table == "requirements: points" and worst.row == 1 and worst.failing
    assert worst.line == "130 s yaw rigid phase margin 14.6 deg (required 30 deg)"
    page = summary_tables(MC_LIKE, worst)
    assert page.count('class="fail worst"') == 1 and page.count("◀ worst") == 1
    assert page.count('<tr class="fail">') == 1  # the margin-spread row with 2 runs below
    assert worst_offender({"margin_spread": MC_LIKE["margin_spread"]}).table == "margin_spread"  # first failing
    assert worst_offender({"margin_spread": MC_LIKE["margin_spread"][:1]}) is None


def test_requirement_verdict_comes_first_then_the_worst_offender(short_run):
    lines = [text for text, _ in verdicts(short_run)]
    status = next(i for i, t in enumerate(lines) if t.startswith("status: "))
    mission = next(i for i, t in enumerate(lines) if t.startswith("mission: "))
    assert mission < status
    page = (short_run.run_dir / "report.html").read_text()
    assert page.index("mission: ") < page.index("status: ")
    if any(t.startswith(WORST_PREFIX) for t in lines):
        assert next(i for i, t in enumerate(lines) if t.startswith(WORST_PREFIX)) < status


def test_timeline_labels_keep_apart_and_inside():
    """The nominal flight's events: separation and ignition 1.5 s apart go to two lanes,
    cutoff at the right edge ends at its mark; no two estimated label extents in one
    lane overlap and none leaves the drawing."""
    events = {"separation": 130.46, "upper_stage_ignition": 131.96, "les_jettison": 161.96, "cutoff": 561.445}
    layout = timeline_layout(events, 561.845)
    lane = {text.split()[0]: ln for text, _, _, ln, _ in layout}
    assert lane["separation"] != lane["upper_stage_ignition"]
    spans = []
    for text, _, xl, ln, anchor in layout:
        w = len(text) * LABEL_CHAR_W
        a = xl if anchor == "start" else xl - w
        assert TIMELINE_LEFT - 30 <= a and a + w <= TIMELINE_WIDTH, text
        spans.append((ln, a, a + w))
    assert next(anchor for text, *_, anchor in layout if text.startswith("cutoff")) == "end"
    for i, (l1, a1, b1) in enumerate(spans):
        for l2, a2, b2 in spans[i + 1:]:
            assert l1 != l2 or b1 <= a2 or b2 <= a1


def test_the_reviewer_checks_fail_a_bad_page(tmp_path):
    """Dict text and overlapping or clipped labels are each seen by the browser checks."""
    require_chromium()
    bad = tmp_path / "bad.html"
    bad.write_text('<!DOCTYPE html><html><body><p>{\'max\': 168769.8129200502}</p>'
                   '<svg viewBox="0 0 300 60" width="300" aria-label="events timeline">'
                   '<text class="event-label" x="10" y="30" font-size="11">separation 130.46 s</text>'
                   '<text class="event-label" x="40" y="30" font-size="11">upper_stage_ignition 131.96 s</text>'
                   '<text class="event-label" x="260" y="50" font-size="11">cutoff 561.45 s</text></svg>'
                   "</body></html>")
    seen = check_page(bad)
    assert "{" in seen.text
    assert overlapping_labels(seen.label_boxes) == [("separation 130.46 s", "upper_stage_ignition 131.96 s")]
    assert clipped_labels(seen.label_boxes, seen.timeline_box) == ["cutoff 561.45 s"]


def test_flight_page_reads_in_chromium(short_run):
    require_chromium()
    assert_page_reads(short_run.run_dir)
    assert len(check_page(short_run.run_dir / "report.html").label_boxes) == len(short_run.events)


#: The runs of the docs' screenshots (docs/outputs.md), one per study, small.
STUDY_RUNS = {
    "nominal": [],
    "linear": ["study=linear", "study.times=[55,130]"],
    "montecarlo": ["study=montecarlo", "study.n_runs=8", "study.workers=1", "study.linear_times=[55]"],
    "time_margins": ["study=time_margins", "study.times=[180]", "study.axes=[yaw]", "study.workers=1"],
    "flex_sweep": ["study=flex_sweep", "flex.n_modes=2", "study.times=[55,180]"],
    "mode_retention": ["study=mode_retention", "study.max_modes=2", "study.times=[55]"],
}
# The pages of study=flyoff and study=fcs_design are read in their own end-to-end runs
# (tests/test_flyoff.py, tests/test_fcs_design.py): a second study only for its page cost
# five minutes of the suite


@pytest.mark.slow
@pytest.mark.parametrize("study", list(STUDY_RUNS))
def test_every_study_page_reads_in_chromium(tmp_path, study):
    """Each study's report.html: no dict text, no float noise, timeline labels apart and
    inside the drawing (bounding boxes from the DOM)."""
    require_chromium()
    r = savant_cli.run(STUDY_RUNS[study] + ["sim.progress=false"], out_dir=tmp_path / study, quiet=True)
    assert_page_reads(r.run_dir)
