"""The numba cache directory is keyed on the compiled modules' sources."""

from __future__ import annotations

import os
import time

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
