"""The numba cache directory is keyed on the compiled modules' sources, can be moved with
SAVANT_CACHE_DIR, and an unwritable one is said once and replaced by a temporary one."""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numba

from savant_cli import jit_cache


def test_cache_dir_keyed_on_source_and_old_versions_pruned(tmp_path, monkeypatch):
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    monkeypatch.setattr(numba.config, "CACHE_DIR", numba.config.CACHE_DIR)
    stale = tmp_path / "savant" / "numba-0000000000000000"
    recent = tmp_path / "savant" / "numba-1111111111111111"
    for d in (stale, recent):
        d.mkdir(parents=True)
    old = time.time() - 30 * 86400
    os.utime(stale, (old, old))
    jit_cache.configure()
    expected = tmp_path / "savant" / f"numba-{jit_cache.source_key()}"
    assert os.environ["NUMBA_CACHE_DIR"] == str(expected)
    assert numba.config.CACHE_DIR == str(expected)
    assert expected.is_dir()
    assert not stale.exists() and recent.exists()


def test_source_key_changes_with_any_compiled_module(tmp_path, monkeypatch):
    """An edit to a callee's file (not only the caller's) gives a new key."""
    pkg = tmp_path / "savant_cli"
    for sub in ("models", "sim"):
        (pkg / sub).mkdir(parents=True)
        (pkg / sub / "a.py").write_text("x = 1\n")
    monkeypatch.setattr(jit_cache, "__file__", str(pkg / "jit_cache.py"))
    k0 = jit_cache.source_key()
    (pkg / "models" / "a.py").write_text("x = 2\n")
    assert jit_cache.source_key() != k0


def test_user_cache_dir_respected(tmp_path, monkeypatch):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "mine"))
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    jit_cache.configure()
    assert os.environ["NUMBA_CACHE_DIR"] == str(tmp_path / "mine")
    assert not (tmp_path / "savant").exists()


def test_savant_cache_dir_holds_the_keyed_cache(tmp_path, monkeypatch, capsys):
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.setenv("SAVANT_CACHE_DIR", str(tmp_path / "shared"))
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "home"))
    monkeypatch.setattr(numba.config, "CACHE_DIR", numba.config.CACHE_DIR)
    jit_cache.configure()
    expected = tmp_path / "shared" / f"numba-{jit_cache.source_key()}"
    assert os.environ["NUMBA_CACHE_DIR"] == str(expected) == numba.config.CACHE_DIR
    assert expected.is_dir() and not (tmp_path / "home").exists()
    assert list(expected.iterdir()) == []  # the probe file is removed
    assert capsys.readouterr().err == ""


def test_unwritable_cache_warns_once_and_falls_back(tmp_path, monkeypatch, capsys):
    """A cache root that cannot be created (here under a regular file, which stops root
    too): one warning naming the directory, the reason and SAVANT_CACHE_DIR, and the
    kernels go to a temporary directory instead of being recompiled silently."""
    blocker = tmp_path / "read-only-home"
    blocker.write_text("a file, not a folder\n")
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.delenv("SAVANT_CACHE_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(blocker / ".cache"))
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "tmp"))
    monkeypatch.setattr(numba.config, "CACHE_DIR", numba.config.CACHE_DIR)
    jit_cache.configure()
    err = capsys.readouterr().err
    wanted = blocker / ".cache" / "savant" / f"numba-{jit_cache.source_key()}"
    assert err.count("warning") == 1 and len(err.strip().splitlines()) == 1
    assert str(wanted) in err and "not writable" in err and "NotADirectoryError" in err
    assert "set SAVANT_CACHE_DIR" in err
    fallback = Path(os.environ["NUMBA_CACHE_DIR"])
    assert fallback.is_relative_to(tmp_path / "tmp") and fallback.is_dir()
    assert numba.config.CACHE_DIR == str(fallback) and str(fallback) in err
    jit_cache.configure()  # as a worker process would, inheriting the fallback: silent
    assert capsys.readouterr().err == ""


def test_unwritable_savant_cache_dir_is_named(tmp_path, monkeypatch, capsys):
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.setenv("SAVANT_CACHE_DIR", str(tmp_path / "x"))
    monkeypatch.setattr(os, "access", lambda *a, **k: False)  # not what decides: the probe does
    monkeypatch.setattr(tempfile, "mkstemp", _refuse)
    monkeypatch.setattr(numba.config, "CACHE_DIR", numba.config.CACHE_DIR)
    jit_cache.configure()
    err = capsys.readouterr().err
    assert "PermissionError" in err and str(tmp_path / "x") in err and "compiles anew in every process" in err
    assert os.environ.get("NUMBA_CACHE_DIR") is None  # nothing writable: numba's own default


def _refuse(*args, **kwargs):
    raise PermissionError(13, "Permission denied")


def test_import_warns_on_stderr_when_the_cache_is_unwritable(tmp_path):
    """The real entry point: importing savant_cli (every savant command does) says so."""
    blocker = tmp_path / "home"
    blocker.write_text("")
    (tmp_path / "t").mkdir()
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", "SAVANT_CACHE_DIR")}
    env.update(XDG_CACHE_HOME=str(blocker / "c"), TMPDIR=str(tmp_path / "t"))
    proc = subprocess.run([sys.executable, "-c", "import savant_cli, os; print(os.environ['NUMBA_CACHE_DIR'])"],
                          env=env, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr.count("savant: warning: the numba cache") == 1 and str(blocker / "c") in proc.stderr
    assert proc.stdout.strip().startswith(str(tmp_path / "t"))
