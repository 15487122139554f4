"""``study=flyoff``: two or more controllers fly the same nominal and the same dispersed
runs (source paper §IV), compared metric by metric, the winner of each marked.

Each controller (a member of the ``controller`` config group) flies the batch of the
study's Monte Carlo keys (``study.n_runs``, ``study.seed`` …; ``n_runs: 1`` is the
nominal alone) with the vehicle's dispersion set (``dispersions``) into ``<out>/<controller>/`` with every Monte Carlo
output there. The same seed and dispersion names give every controller exactly the same
dispersed vehicles. The comparison: ``flyoff.csv`` and ``summary.json`` (per metric and
controller the nominal value and the 99.865 / 0.135 percentile over the runs, and the
winner), a console table, overlay plots of the nominal histories and of the dispersed
distributions, and ``savant.h5`` (group ``flyoff``: the comparison, every run's metrics
and each controller's nominal histories) from which ``savant report`` redraws the plots.
"""

from __future__ import annotations

import copy
import csv
import io
import json
from pathlib import Path

import h5py
import numpy as np
from omegaconf import DictConfig, OmegaConf
from rich.table import Table

from savant_cli.config import FlyoffStudyConfig, SavantConfig, check_physics
from savant_cli.errors import ConfigError
from savant_cli.io.atomic import write_json_atomic, write_text_atomic
from savant_cli.io.console import print_verdict, study_console
from savant_cli.io.hdf5 import write_study_file
from savant_cli.io.provenance import collect_provenance
from savant_cli.io.record import FLOWN
from savant_cli.montecarlo.analysis import PERCENTILES
from savant_cli.montecarlo.console_summary import print_mission
from savant_cli.montecarlo.targets import load_group_option
from savant_cli.paths import hydra_search_dirs
from savant_cli.studies.montecarlo import fly_batch

#: metric → (summary key or margin selector, better: "low" or "high", unit)
METRICS: dict[str, tuple[str, str, str]] = {
    "max attitude error": ("max_attitude_error_deg", "low", "deg"),
    "RMS attitude error": ("rms_attitude_error_deg", "low", "deg"),
    "max alpha": ("max_alpha_deg", "low", "deg"),
    "max q-alpha": ("max_qalpha_Pa_deg", "low", "Pa deg"),
    "max pitch q-alpha": ("max_qalpha_pitch_Pa_deg", "low", "Pa deg"),
    "max q-beta": ("max_qbeta_Pa_deg", "low", "Pa deg"),
    "time above q-alpha limit": ("time_above_qalpha_limit_s", "low", "s"),
    "max gimbal angle": ("max_gimbal_deg", "low", "deg"),
    "max gimbal rate": ("max_gimbal_rate_deg_s", "low", "deg/s"),
    "propellant remaining": ("propellant_remaining_kg", "high", "kg"),
    "RCS on-time": ("rcs_on_time_s", "low", "s"),
    "smallest rigid gain margin": ("margin:gain", "high", "dB"),
    "smallest rigid phase margin": ("margin:phase", "high", "deg"),
    "smallest margin-to-requirement ratio": ("requirements:ratio", "high", "1"),
}


def _controllers(study: FlyoffStudyConfig, dirs: list[Path]) -> dict:
    out = {}
    for i, name in enumerate(study.controllers):
        try:
            out[name] = load_group_option("controller", name, dirs)
        except ConfigError as exc:
            raise ConfigError(f"study.controllers[{i}]", name, exc.allowed) from None
    return out


def _per_run(h5: Path) -> dict[str, np.ndarray]:
    """Per run (row order of the file; run 0 first): every metric's value."""
    with h5py.File(h5) as f:
        g = f["montecarlo"]
        runs = g["runs/run"][()]
        status = g["runs/status"].asstr()[()]
        ok = np.isin(status, FLOWN)  # flew to its end (its health is counted separately)
        order = np.argsort(runs)
        out = {"run": runs[order], "ok": ok[order], "healthy": (status == "complete")[order],
               "meets_requirements": _meets(g, runs)[order]}
        for metric, (key, _, _) in METRICS.items():
            if key == "requirements:ratio":
                out[metric] = _requirement_ratio(g, runs)[order]
            elif key.startswith("margin:"):
                kind = key.split(":")[1]
                col = np.full(runs.size, np.nan)
                m = g["margins"]
                if m["run"].size:
                    mr, mv = m["run"][()], m["value"][()]
                    sel = (m["kind"].asstr()[()] == kind) & (m["band"].asstr()[()] == "rigid/aero")
                    for j, r in enumerate(runs):
                        vals = np.abs(mv[sel & (mr == r)])
                        col[j] = vals.min() if vals.size else np.nan
                out[metric] = col[order]
            else:
                out[metric] = g[f"summary/{key}"][()][order] if key in g["summary"] else np.full(runs.size, np.nan)
        return out


def _requirement_ratio(g: h5py.Group, runs: np.ndarray) -> np.ndarray:
    """Per run: the smallest ratio of a margin (or a bending mode's attenuation) to its
    requirement over the run's checks (< 1: a requirement missed); NaN for a run without
    linear points. Closed-loop stability is counted by ``meets_requirements``."""
    out = np.full(runs.size, np.nan)
    c = g["requirements/checks"]
    run, crit = c["run"][()], c["criterion"].asstr()[()]
    value, required = c["value"][()], c["required"][()]
    ratio = np.where(crit == "attenuation", value, np.abs(value)) / np.where(required > 0, required, np.nan)
    for j, r in enumerate(runs):
        sel = (run == r) & (crit != "stability") & np.isfinite(ratio)
        if sel.any():
            out[j] = ratio[sel].min()
    return out


def _meets(g: h5py.Group, runs: np.ndarray) -> np.ndarray:
    """Per run: 1 if every requirement check passes, 0 if one fails, NaN if not judged."""
    out = np.full(runs.size, np.nan)
    c = g["requirements/checks"]
    run, passed = c["run"][()], c["passed"][()]
    for j, r in enumerate(runs):
        sel = run == r
        if sel.any():
            out[j] = float(passed[sel].all())
    return out


def compare(tables: dict[str, dict[str, np.ndarray]]) -> list[dict]:
    """Per metric: each controller's nominal (run 0) value and its dispersed worst-case
    percentile (``<controller>_dispersed``: 99.865 % for lower-is-better, 0.135 % for
    higher-is-better, over the runs that completed), its worst run's value and number
    (``<controller>_worst``, ``<controller>_worst_run``: the largest value for
    lower-is-better, the smallest for higher-is-better; −1 when none), and the winner on
    that percentile (on the nominal alone when there are no dispersed runs)."""
    rows = []
    for metric, (_, better, unit) in METRICS.items():
        pct = PERCENTILES[2] if better == "low" else PERCENTILES[0]
        row: dict = {"metric": metric, "unit": unit, "better": better, "percentile": pct}
        score = {}
        for ctrl, t in tables.items():
            v = t[metric]
            nominal = float(v[0]) if t["run"].size and t["run"][0] == 0 else float("nan")
            good = v[t["ok"] & np.isfinite(v)]
            tail = float(np.percentile(good, pct)) if good.size > 1 else nominal
            row[f"{ctrl}_nominal"] = nominal
            row[f"{ctrl}_dispersed"] = tail
            sel = t["ok"] & np.isfinite(v)
            if sel.any():
                j = int(np.argmax(v[sel]) if better == "low" else np.argmin(v[sel]))
                row[f"{ctrl}_worst"], row[f"{ctrl}_worst_run"] = float(v[sel][j]), int(t["run"][sel][j])
            else:
                row[f"{ctrl}_worst"], row[f"{ctrl}_worst_run"] = float("nan"), -1
            if np.isfinite(tail):
                score[ctrl] = tail
        if score:
            best = (min if better == "low" else max)(score, key=score.get)
            tied = [c for c, s in score.items() if np.isclose(s, score[best], rtol=1e-9, atol=0.0)]
            row["winner"] = best if len(tied) == 1 else "tie"
        else:
            row["winner"] = ""
        rows.append(row)
    return rows


def run(cfg: SavantConfig, raw_cfg: DictConfig, out_dir: Path) -> int:
    """Fly every controller's batch, then compare."""
    study: FlyoffStudyConfig = cfg.study
    console = study_console(cfg.output.console)
    dirs = hydra_search_dirs()
    controllers = _controllers(study, dirs)  # every name checked before anything flies
    cfgs = {}
    for name, ctrl in controllers.items():
        c = copy.deepcopy(cfg)
        c.controller = ctrl
        check_physics(c)
        cfgs[name] = c
    stopped = False
    for name, c in cfgs.items():
        raw = copy.deepcopy(raw_cfg)
        raw.controller = OmegaConf.structured(c.controller)
        _, stop = fly_batch(c, OmegaConf.to_yaml(raw, resolve=True), out_dir / name, console, title=name,
                            print_tables=False)
        stopped |= stop.reason != "done"
    if stopped:
        console.print(f"[bold red]a batch stopped[/]; run the same command with hydra.run.dir={out_dir} to resume")
        return 1
    tables = {name: _per_run(out_dir / name / "savant.h5") for name in cfgs}
    verdicts, passed, missions = {}, {}, {}
    for name in cfgs:
        with h5py.File(out_dir / name / "savant.h5") as f:
            g = f["montecarlo"]
            if g["requirements/checks/run"].size:  # judged: the batch had linear times
                verdicts[name] = str(g["requirements"].attrs["verdict"])
                passed[name] = bool(g["requirements"].attrs["passed"])
            missions[name] = {"reliability": json.loads(g.attrs["reliability"]),
                              "mission": json.loads(g.attrs["mission"])}
    rows = compare(tables)
    console.print(_table(rows, list(cfgs)))  # before the files: shown even if they cannot be written
    for name, line in verdicts.items():
        print_verdict(f"{name}: {line}", passed[name], console)
    for name, m in missions.items():
        console.print(f"{name}:", style="bold", highlight=False)
        print_mission(console, m["mission"])
        print_verdict(f"{name}: {m['reliability']['line']}", m["reliability"]["target_met"], console)
    _write(out_dir, rows, tables, study, verdicts, missions)
    time_s, histories = _nominal_histories(out_dir, list(cfgs))
    write_study_file(out_dir / "savant.h5", "flyoff", OmegaConf.to_yaml(raw_cfg, resolve=True), collect_provenance(),
                     lambda f: write_group(f, rows, tables, time_s, histories))
    if cfg.output.plots:
        draw(rows, tables, time_s, histories, out_dir / "plots")
    console.print(f"outputs: {out_dir}")
    return 0


def _write(out_dir: Path, rows: list[dict], tables: dict, study: FlyoffStudyConfig, verdicts: dict[str, str],
           missions: dict[str, dict]) -> None:
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(rows[0]), lineterminator="\n")
    w.writeheader()
    w.writerows(rows)
    write_text_atomic(out_dir / "flyoff.csv", buf.getvalue())
    write_json_atomic(out_dir / "summary.json", {
        "study": "flyoff", "controllers": list(tables), "n_runs": study.n_runs,
        "linear_times_s": list(study.linear_times), "metrics": rows,
        "wins": {c: sum(r["winner"] == c for r in rows) for c in tables},
        "runs_complete": {c: int(t["healthy"].sum()) for c, t in tables.items()},
        "runs_flagged": {c: int((t["ok"] & ~t["healthy"]).sum()) for c, t in tables.items()},
        "runs_meeting_requirements": {c: _meeting(t) for c, t in tables.items()},
        "requirements_verdict": verdicts,
        # per controller: its batch's mission outcome by class and demonstrated success
        "mission": {c: m["mission"] for c, m in missions.items()},
        "reliability": {c: m["reliability"] for c, m in missions.items()}})


def _meeting(t: dict[str, np.ndarray]) -> str:
    """``"n of m"`` runs meeting the requirement set, of those judged."""
    m = t["meets_requirements"]
    judged = np.isfinite(m)
    return f"{int(m[judged].sum())} of {int(judged.sum())}"


def _table(rows: list[dict], names: list[str]) -> Table:
    tb = Table(title="controller fly-off (nominal / dispersed worst-case percentile, worst run in brackets; ★ = best)")
    tb.add_column("metric")
    for n in names:
        tb.add_column(n, justify="right")
    for r in rows:
        cells = []
        for n in names:
            tail = r[f"{n}_dispersed"]
            star = " ★" if r["winner"] == n else ""
            worst = f" [{int(r[f'{n}_worst_run'])}]" if r.get(f"{n}_worst_run", -1) >= 0 else ""
            cells.append(f"{r[f'{n}_nominal']:.4g} / {tail:.4g}{worst}{star}")
        tb.add_row(f"{r['metric']} [{r['unit']}]", *cells)
    return tb


def _nominal_histories(out_dir: Path, names: list[str]) -> tuple[np.ndarray | None, dict[str, dict[str, np.ndarray]]]:
    """The decimated histories of each controller's nominal run (run 0, or the lowest run
    present): signal → controller → history, and their time grid (s)."""
    histories: dict[str, dict[str, np.ndarray]] = {}
    time_s = None
    for n in names:
        with h5py.File(out_dir / n / "savant.h5") as f:
            if "montecarlo/histories" not in f:
                continue
            hg = f["montecarlo/histories"]
            time_s = hg["time"][()]
            row0 = int(np.argmin(f["montecarlo/runs/run"][()]))
            for sig in hg:
                if sig != "time":
                    histories.setdefault(sig, {})[n] = hg[sig][row0]
    return time_s, histories


def write_group(f: h5py.File, rows: list[dict], tables: dict[str, dict[str, np.ndarray]],
                time_s: np.ndarray | None, histories: dict[str, dict[str, np.ndarray]]) -> None:
    """Group ``flyoff`` of the study's ``savant.h5``: attribute ``controllers``;
    ``metrics/<column>`` (the rows of ``flyoff.csv``); ``runs/<controller>/{run, ok,
    <metric>}`` (every run's metric values); ``nominal/time_s`` and
    ``nominal/<controller>/<signal>`` (the nominal histories)."""
    g = f.create_group("flyoff", track_order=True)
    g.attrs["controllers"] = list(tables)
    mg = g.create_group("metrics", track_order=True)
    for col in rows[0]:
        vals = [r[col] for r in rows]
        mg.create_dataset(col, data=np.array(vals, dtype=h5py.string_dtype()) if isinstance(vals[0], str)
                          else np.asarray(vals, dtype=float))
    rg = g.create_group("runs", track_order=True)
    for ctrl, t in tables.items():
        cg = rg.create_group(ctrl, track_order=True)
        for key, v in t.items():
            cg.create_dataset(key, data=v)
    ng = g.create_group("nominal", track_order=True)
    if time_s is not None:
        ng.create_dataset("time_s", data=time_s)
        for ctrl in tables:
            cg = ng.create_group(ctrl, track_order=True)
            for sig, per in histories.items():
                if ctrl in per:
                    cg.create_dataset(sig, data=per[ctrl])


def read_group(path: Path) -> tuple[list[dict], dict[str, dict[str, np.ndarray]], np.ndarray | None,
                                    dict[str, dict[str, np.ndarray]]]:
    """The comparison rows, per-run tables, nominal time grid and histories of a fly-off's
    ``savant.h5`` (the inverse of :func:`write_group`)."""
    with h5py.File(path, "r") as f:
        g = f["flyoff"]
        mg = g["metrics"]
        cols = {c: (mg[c].asstr()[()] if mg[c].dtype.kind == "O" else mg[c][()]) for c in mg}
        n = len(next(iter(cols.values())))
        rows = [{c: (str(v[i]) if isinstance(v[i], str) else float(v[i])) for c, v in cols.items()} for i in range(n)]
        tables = {c: {k: ds[()] for k, ds in g["runs"][c].items()} for c in g["runs"]}
        ng = g["nominal"]
        time_s = ng["time_s"][()] if "time_s" in ng else None
        histories: dict[str, dict[str, np.ndarray]] = {}
        for ctrl in (k for k in ng if k != "time_s"):
            for sig, ds in ng[ctrl].items():
                histories.setdefault(sig, {})[ctrl] = ds[()]
    return rows, tables, time_s, histories


def draw(rows: list[dict], tables: dict[str, dict[str, np.ndarray]], time_s: np.ndarray | None,
         histories: dict[str, dict[str, np.ndarray]], folder: Path) -> list[Path]:
    """The nominal-history overlays and the dispersed metric histograms."""
    from savant_cli.plots.flyoff import plot_history_overlays, plot_metric_histograms

    paths = []
    names = list(tables)
    if histories and time_s is not None:
        paths += plot_history_overlays(time_s, histories, folder)
    if any(t["run"].size > 1 for t in tables.values()):
        values = {r["metric"]: {n: tables[n][r["metric"]][tables[n]["ok"]] for n in names} for r in rows}
        paths.append(plot_metric_histograms(values, folder / "flyoff_histograms.png",
                                            {r["metric"]: r["winner"] for r in rows}))
    return paths
