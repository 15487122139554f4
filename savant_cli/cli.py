"""The ``savant`` command.

``savant run [overrides]`` is Hydra's main (all Hydra flags work: ``-m``, ``--cfg job``,
``--help``, ``hydra.run.dir=…``, ``-cd DIR``); ``savant report DIR`` redraws a run's
plots from its ``savant.h5``; ``savant convert-vehicle FILE`` converts a vehicle file of
the old two-stage schema; ``savant --version``; ``savant --help``.
"""

from __future__ import annotations

import logging
import sys
from pathlib import Path

from rich.console import Console

from savant_cli.errors import ConfigError, SavantError
from savant_cli.version import __version__

USAGE = """\
usage: savant <command> [arguments]

commands:
  run [overrides]     fly the configured study (Hydra: -m for sweeps, --cfg job to
                      print the config, --help for the config groups)
  report RUN_DIR      redraw the plots, report.html and console summary of a finished run
  collect DIR [--allow-missing]
                      merge the shard folders of a Monte Carlo multirun
                      into DIR; with runs missing it lists them and writes
                      nothing (exit 1), or with --allow-missing writes the
                      partial result (exit 1)
  rerun DIR run=N     fly run N of the Monte Carlo batch in DIR again, with its
                      whole time history and plots (DIR/rerun_<N>/)
  compare RUN_DIR REFERENCE --map MAP.yaml [--out DIR]
                      compare a run with another simulation's time history
  convert-vehicle FILE [--out NEW]
                      convert a vehicle file of the old two-stage schema (in
                      place, the original kept as FILE.v1; docs/vehicles.md)
  --version           print the version
  --help              this text

examples:
  savant run
  savant run winds=none sim.plant_rate_hz=400
  savant run -m winds=none,ksc_mean_annual
  savant report outputs/2026-11-23/10-00-00_nominal
  savant run study=montecarlo study.n_runs=200
  savant rerun outputs/2026-11-23/11-00-00_montecarlo run=137
  savant run -m study=montecarlo study.shards=40 'study.shard=range(0,40)' \\
      study.workers=8 hydra/launcher=savant_slurm \\
      hydra.launcher.partition=compute
  savant collect multirun/2026-11-23/12-00-00
"""


_task_started = False


def _hydra_task(cfg) -> int:
    """Body of ``savant run``: validate, then hand over to the study."""
    global _task_started
    _task_started = True
    from hydra.core.hydra_config import HydraConfig
    from hydra.types import RunMode

    from savant_cli import lifecycle, run_lock
    from savant_cli.config import validate
    from savant_cli.runner import run_study

    console = Console(stderr=True)
    hc = HydraConfig.get()
    out_dir = Path(hc.runtime.output_dir)
    multirun = hc.mode == RunMode.MULTIRUN
    try:
        typed = validate(cfg)
        # held since the callback's on_run_start in a single run; a multirun job, or a
        # config tree without the callback, locks its folder here
        run_lock.acquire(out_dir)
        lifecycle.stage("startup")
        code = run_study(typed, cfg, out_dir)
        lifecycle.clear_marker(out_dir)
    except ConfigError as exc:
        console.print(f"[bold red]configuration error[/]: {exc}")
        code = ConfigError.exit_code
        # refused before the study wrote anything: a folder this command made goes again
        # (a multirun job's folder stays, its log saying why)
        if multirun or not any(lifecycle.discard_if_untouched(lock) for lock in run_lock.held(out_dir)):
            logging.getLogger("savant").error("configuration error: %s", exc)
    if multirun:  # the next job of the sweep may run in this process
        for lock in run_lock.held(out_dir):
            lock.release()
    if code and not multirun:
        raise SystemExit(code)
    return code


def _run_hydra(argv: list[str]) -> None:
    """``savant run ARGV``: Hydra's main over the shipped config tree, with our schema in
    its ConfigStore; Hydra's own refusals exit with status 2."""
    import hydra

    from savant_cli.hydra_compose import register_schema, variant_hint
    from savant_cli.paths import shipped_config_dir

    register_schema()
    main = hydra.main(config_path=str(shipped_config_dir()), config_name="config", version_base="1.3")(_hydra_task)
    sys.argv = ["savant run", *argv]
    try:
        main()
    except SystemExit as exc:
        # Hydra reports its own composition errors (unknown group option, override of an
        # unknown key, bad override syntax) with exit status 1 before our task runs: those
        # are configuration errors, status 2.
        if exc.code == 1 and not _task_started:
            hint = variant_hint(argv)
            if hint:
                Console(stderr=True).print(f"[bold red]configuration error[/]: {hint}")
            raise SystemExit(ConfigError.exit_code) from None
        raise


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``savant`` console script.

    A Ctrl-C at any moment ends the command with one line on stderr and exit status 130,
    after the run folders it holds are settled: removed when nothing was written into a
    folder it created, else marked ``interrupted.json`` (:mod:`savant_cli.lifecycle`).
    """
    try:
        return _main(argv)
    except KeyboardInterrupt as exc:
        from savant_cli.lifecycle import settle_interrupt

        sys.stderr.write(settle_interrupt(exc, restore=False) + "\n")
        sys.stderr.flush()
        return 130


def _main(argv: list[str] | None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    console = Console()
    if not args or args[0] in ("-h", "--help", "help"):
        console.print(USAGE, highlight=False, markup=False)
        return 0
    if args[0] in ("-V", "--version", "version"):
        console.print(f"savant {__version__}", highlight=False)
        return 0
    cmd, rest = args[0], args[1:]
    if cmd == "run":
        _run_hydra(rest)
        return 0
    if cmd == "report":
        if len(rest) != 1:
            Console(stderr=True).print("usage: savant report RUN_DIR")
            return 2
        from savant_cli import lifecycle, run_lock
        from savant_cli.report import report

        try:
            if not Path(rest[0]).is_dir():
                raise FileNotFoundError(f"{rest[0]} is not a folder")
            with run_lock.acquire(Path(rest[0]), key="RUN_DIR"):
                lifecycle.stage("plots")
                paths = report(Path(rest[0]))
                lifecycle.clear_marker(Path(rest[0]))
        except SavantError as exc:  # a damaged savant.h5 or a busy folder (2), or an output not written (1)
            Console(stderr=True).print(f"[bold red]error[/]: {exc}", highlight=False)
            return exc.exit_code
        except (FileNotFoundError, OSError) as exc:  # no such folder or file, not a savant file
            Console(stderr=True).print(f"[bold red]error[/]: {exc}", highlight=False)
            return 2
        console.print(f"{len(paths)} plots written to {Path(rest[0]) / 'plots'}")
        return 0
    if cmd in ("collect", "rerun"):
        return _batch_command(cmd, rest)
    if cmd == "compare":
        return _compare_command(rest)
    if cmd == "convert-vehicle":
        return _convert_vehicle_command(rest)
    Console(stderr=True).print(f"unknown command {cmd!r}\n\n{USAGE}", markup=False)
    return 2


def _parsed(ap, rest: list[str]):
    """A subcommand's parsed arguments, or its exit status: 0 after ``--help``, 2 after
    argparse printed the usage and the problem."""
    if any(a in ("-h", "--help") for a in rest):
        ap.print_help()
        return 0
    try:
        return ap.parse_args(rest)
    except SystemExit:
        return 2


def _compare_command(rest: list[str]) -> int:
    """``savant compare RUN_DIR REFERENCE --map MAP.yaml [--out DIR]``."""
    import argparse

    err = Console(stderr=True)
    ap = argparse.ArgumentParser(
        prog="savant compare", description="Compare a run's time histories with another simulation's "
        "(CSV or HDF5): overlay and difference plots, statistics and tolerances (docs/design_studies.md).")
    ap.add_argument("run_dir", type=Path, help="run folder holding savant.h5")
    ap.add_argument("reference", type=Path, help="the other simulation's history, CSV or HDF5")
    ap.add_argument("--map", type=Path, required=True, dest="mapping",
                    help="YAML mapping of names, units, window and tolerances (e.g. references/jsbsim_names.yaml)")
    ap.add_argument("--out", type=Path, default=None, help="output folder (default: RUN_DIR/compare_<reference>)")
    ap.add_argument("--no-plots", action="store_true", help="statistics only")
    args = _parsed(ap, rest)
    if isinstance(args, int):
        return args
    if not (args.run_dir / "savant.h5").is_file():
        err.print(f"[bold red]error[/]: {args.run_dir} holds no savant.h5")
        return 2
    from savant_cli.compare import compare

    try:
        return compare(args.run_dir, args.reference, args.mapping, args.out, plots=not args.no_plots)
    except ConfigError as exc:
        err.print(f"[bold red]error[/]: {exc}")
        return ConfigError.exit_code


def _convert_vehicle_command(rest: list[str]) -> int:
    """``savant convert-vehicle FILE [--out NEW]``."""
    import argparse

    ap = argparse.ArgumentParser(
        prog="savant convert-vehicle", description="Convert a vehicle file of the old two-stage schema to the "
        "vehicle tree's (docs/vehicles.md): the same vehicle, flown bit for bit.")
    ap.add_argument("file", type=Path, help="the vehicle YAML (conf/vehicle/<name>.yaml of your config folder)")
    ap.add_argument("--out", type=Path, default=None, help="where to write it (default: in place, the original "
                                                           "kept as FILE.v1)")
    args = _parsed(ap, rest)
    if isinstance(args, int):
        return args
    from savant_cli.vehicle.convert import convert_file

    try:
        written = convert_file(args.file, args.out)
    except SavantError as exc:
        Console(stderr=True).print(f"[bold red]error[/]: {exc}", highlight=False)
        return exc.exit_code
    kept = "" if args.out else f" (the original kept as {args.file}.v1)"
    Console().print(f"converted {args.file} -> {written}{kept}", highlight=False)
    return 0


def _batch_command(cmd: str, rest: list[str]) -> int:
    """``savant collect DIR [--allow-missing]`` and ``savant rerun DIR run=N``."""
    err = Console(stderr=True)
    usage = "usage: savant collect DIR [--allow-missing]" if cmd == "collect" else "usage: savant rerun DIR run=N"
    allow_missing = cmd == "collect" and "--allow-missing" in rest
    if allow_missing:
        rest = [a for a in rest if a != "--allow-missing"]
    if (cmd == "collect" and len(rest) != 1) or (cmd == "rerun" and (len(rest) != 2 or not rest[1].startswith("run="))):
        err.print(usage)
        return 2
    folder = Path(rest[0])
    if folder.name.startswith("-"):
        err.print(f"[bold red]error[/]: unknown option {rest[0]!r}\n{usage}")
        return 2
    if not folder.is_dir():
        err.print(f"[bold red]error[/]: {folder} is not a folder\n{usage}")
        return 2
    from savant_cli import run_lock
    from savant_cli.html_report import write_report_or_say
    from savant_cli.studies import montecarlo

    try:
        if cmd == "collect":
            run_lock.refuse_if_busy(folder, key="DIR")  # a sweep still writing its shards
            code = montecarlo.collect(folder, allow_missing=allow_missing,
                                      before_write=lambda: run_lock.acquire(folder, key="DIR"))
            if (code == 0 or allow_missing) and (folder / "savant.h5").is_file():  # written just now
                code = max(code, write_report_or_say(folder, err))
            return code
        try:
            number = int(rest[1][4:])
        except ValueError:
            raise ConfigError("run", rest[1][4:], "must be an integer run number") from None
        target = folder / f"rerun_{number:06d}"  # montecarlo.rerun's folder
        run_lock.refuse_if_busy(target, key="DIR")
        with run_lock.acquire(target, key="DIR") as lock:
            try:
                code = montecarlo.rerun(folder, number)
            except SavantError:
                lock.discard()  # refused before writing: leave no folder behind (discard keeps anything written)
                raise
            if (target / "savant.h5").is_file():
                code = max(code, write_report_or_say(target, err))
        return code
    except SavantError as exc:  # bad input or a damaged file (2), an output not written (1)
        err.print(f"[bold red]error[/]: {exc}", highlight=False)
        return exc.exit_code


if __name__ == "__main__":
    sys.exit(main())
