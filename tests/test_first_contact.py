"""First contact (issue 27 item 9): the first ``savant run`` on a fresh machine says that
it compiles the plant, and where it keeps it; the compile time is its own summary key,
not counted in the real-time factor; a warm run says nothing of it.

The end-to-end tests run the installed ``savant`` command in a fresh, empty
``SAVANT_CACHE_DIR`` (one cold compile shared by the module's tests)."""

from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from savant_cli.sim import compile_notice

LINE = "compiling the plant for this machine, once"


def _savant(args: list[str], cache: Path, out: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ, SAVANT_CACHE_DIR=str(cache))
    env.pop("NUMBA_CACHE_DIR", None)
    return subprocess.run(["savant", "run", f"hydra.run.dir={out}", "sim.progress=false", *args],
                          capture_output=True, text=True, env=env, check=True, timeout=900)


@pytest.fixture(scope="module")
def first_contact(tmp_path_factory):
    """A cold first run (empty cache) and a warm second one in the same cache:
    ``(cache, cold process, cold folder, warm process, warm folder)``."""
    root = tmp_path_factory.mktemp("first_contact")
    cache = root / "cache"
    cold = _savant([], cache, root / "cold")
    warm = _savant(["output.plots=false"], cache, root / "warm")
    return cache, cold, root / "cold", warm, root / "warm"


@pytest.mark.slow
def test_cold_run_says_it_compiles_and_where(first_contact):
    cache, cold, *_ = first_contact
    lines = [ln for ln in cold.stderr.splitlines() if LINE in ln]
    assert len(lines) == 1, cold.stderr
    assert str(cache) in lines[0]
    assert "mission: SUCCESS" in cold.stdout


@pytest.mark.slow
def test_warm_run_says_nothing_of_compiling(first_contact):
    *_, warm, warm_dir = first_contact
    assert LINE not in warm.stderr
    assert "compiling" not in warm.stderr + warm.stdout
    assert (warm_dir / "summary.json").is_file()


@pytest.mark.slow
def test_compile_time_is_its_own_key(first_contact):
    _, _, cold_dir, _, warm_dir = first_contact
    cold = json.loads((cold_dir / "summary.json").read_text())
    warm = json.loads((warm_dir / "summary.json").read_text())
    assert cold["compile_time_s"] > 1.0  # compiled
    assert cold["compile_time_s"] > 5 * cold["sim_wall_time_s"]  # not in the flight's wall time
    assert 0.0 < warm["compile_time_s"] < cold["compile_time_s"]  # loaded
    for s in (cold, warm):  # the flight loop alone
        assert s["realtime_factor"] == pytest.approx(s["final_time_s"] / s["sim_wall_time_s"], rel=1e-12)
        assert s["realtime_factor"] > 100.0


# ----------------------------------------------------------------- the notice itself

KERNEL = textwrap.dedent('''
    from numba import njit

    @njit(cache=True)
    def twice(a):
        return 2.0 * a
''')


def _load(path: Path, name: str):
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_cached_is_known_before_the_call(tmp_path, monkeypatch):
    """Cold: not cached; after one call, cached in the process; a new dispatcher of the
    same source (another process) finds it in the on-disk index without compiling."""
    import numba

    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path / "cache"))
    src = tmp_path / "fc_kernel.py"
    src.write_text(KERNEL)
    first = _load(src, "fc_kernel_a")
    assert not compile_notice.kernel_cached(first.twice, (1.5,))
    assert first.twice(1.5) == 3.0
    assert compile_notice.kernel_cached(first.twice, (1.5,))
    again = _load(src, "fc_kernel_b")
    assert not again.twice.overloads  # nothing compiled in this dispatcher yet
    assert compile_notice.kernel_cached(again.twice, (1.5,))
    assert not compile_notice.kernel_cached(again.twice, (1,))  # another signature: would compile
    assert compile_notice.kernels_cached([(again.twice, (1.5,))])


def test_cold_load_says_the_line_once_and_times_it(tmp_path, monkeypatch, capsys):
    import numba

    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "cache"))
    src = tmp_path / "fc_kernel2.py"
    src.write_text(KERNEL)
    kernel = _load(src, "fc_kernel_c")
    assert compile_notice.load_kernels([(kernel.twice, (2.0,))]) > 0.0
    err = capsys.readouterr().err
    assert err.count(LINE) == 1 and str(tmp_path / "cache") in err
    compile_notice.load_kernels([(kernel.twice, (2.0,))])  # warm: silent
    assert LINE not in capsys.readouterr().err


def test_a_second_cold_process_waits_for_the_first_compile_and_loads_it(tmp_path, monkeypatch):
    """Two processes on one cold cache compile once: a subprocess that finds the kernel
    cold says the line, then waits on the cache directory's lock, held here; this
    process compiles the kernel into the cache meanwhile and releases the lock; the
    subprocess then loads it (numba counts a cache hit, no miss). Without the lock it
    would have compiled it itself in the second it was given."""
    import time

    import numba

    cache = tmp_path / "cache"
    cache.mkdir()
    src = tmp_path / "fc_kernel3.py"
    src.write_text(KERNEL)
    code = textwrap.dedent("""
        import fc_kernel3 as kernel
        from savant_cli.sim import compile_notice
        compile_notice.load_kernels([(kernel.twice, (2.0,))])
        print(sum(kernel.twice.stats.cache_hits.values()), sum(kernel.twice.stats.cache_misses.values()))
    """)
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache), PYTHONPATH=str(tmp_path))
    with compile_notice.compile_lock(str(cache)):
        proc = subprocess.Popen([sys.executable, "-c", code], env=env, stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, text=True)
        said = proc.stderr.readline()
        assert LINE in said, said
        time.sleep(1.0)
        assert proc.poll() is None  # waiting on the lock
        monkeypatch.setattr(numba.config, "CACHE_DIR", str(cache))
        monkeypatch.syspath_prepend(str(tmp_path))
        assert importlib.import_module("fc_kernel3").twice(2.0) == 4.0  # compiled here, into the cache
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 0, err
    assert out.split() == ["1", "0"]  # loaded, not compiled


def test_silenced_says_nothing(capsys):
    with compile_notice.silenced():
        with compile_notice.compiling("/somewhere"):
            pass
    assert capsys.readouterr().err == ""
    with compile_notice.silenced(False):
        with compile_notice.compiling("/somewhere"):
            pass
    err = capsys.readouterr().err
    assert LINE in err and "/somewhere" in err


def test_compile_time_s_is_a_wall_clock_key():
    from savant_cli.io.bitwise import WALL_CLOCK_KEYS
    from savant_cli.montecarlo.batch import WALL_KEYS

    assert "compile_time_s" in WALL_CLOCK_KEYS and "compile_time_s" in WALL_KEYS


@pytest.mark.slow
def test_nominal_path_imports_no_scipy_stats_or_ndimage(first_contact, tmp_path):
    """A nominal flight (plots off) through the API loads neither ``scipy.stats`` nor
    ``scipy.ndimage`` (seconds of import a flight does not need)."""
    cache = first_contact[0]
    code = textwrap.dedent(f"""
        import sys
        import savant_cli
        savant_cli.run(["output.plots=false", "sim.progress=false"], out_dir={str(tmp_path / "run")!r}, quiet=True)
        print(sorted(m for m in ("scipy.stats", "scipy.ndimage") if m in sys.modules))
    """)
    env = dict(os.environ, SAVANT_CACHE_DIR=str(cache))
    env.pop("NUMBA_CACHE_DIR", None)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True,
                         timeout=600)
    assert out.stdout.strip().splitlines()[-1] == "[]", out.stdout
    assert LINE not in out.stderr  # warm, and quiet


@pytest.mark.slow
def test_parallel_figures_are_the_serial_ones(first_contact, tmp_path, monkeypatch):
    """The PNGs drawn by forked workers (the cold run's) have the names and bytes of the
    same figures drawn serially in this process."""
    from savant_cli.io.hdf5 import read_run
    from savant_cli.plots import ascent

    cold_dir = first_contact[2]
    monkeypatch.setattr(ascent, "_draw_workers", lambda: 1)
    serial = ascent.plot_ascent(read_run(cold_dir / "savant.h5"), tmp_path / "plots")
    parallel = sorted((cold_dir / "plots").glob("*.png"))
    assert [p.name for p in serial] == [s.filename for s in ascent.FIGURES if (cold_dir / "plots" / s.filename).is_file()]
    assert sorted(p.name for p in serial) == [p.name for p in parallel] and len(parallel) >= 7
    for p in parallel:
        assert p.read_bytes() == (tmp_path / "plots" / p.name).read_bytes(), p.name


def test_figures_are_drawn_in_parallel_only_in_a_forking_main_process(monkeypatch):
    import multiprocessing

    from savant_cli.plots import ascent
    from savant_cli.processes import default_workers

    if sys.platform.startswith("linux"):
        assert ascent._draw_workers() == default_workers()
    monkeypatch.setattr(multiprocessing, "parent_process", lambda: object())
    assert ascent._draw_workers() == 1
