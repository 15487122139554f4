"""The journal inventory of a batch: which run's entry is in which shard folder
(``runs/``), which runs are missing, duplicated or damaged, and run lists as text."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from savant_cli.errors import ConfigError, DamagedFileError
from savant_cli.montecarlo.batch import read_manifest, scan_entries


@dataclass
class Inventory:
    """The journal files of a batch, by run number; with :func:`inventory`'s ``verify``,
    only the entries that read back whole and match their checksum, the damaged ones in
    ``damaged`` (and so counted as missing)."""

    files: dict[int, Path]
    manifest: dict
    duplicates: dict[int, list[Path]] = field(default_factory=dict)
    damaged: dict[int, DamagedFileError] = field(default_factory=dict)

    def missing(self, expected: range | list[int]) -> list[int]:
        return [r for r in expected if r not in self.files]


def inventory(run_dirs: list[Path], verify: bool = False) -> Inventory:
    """Index the journal folders (``runs/``) of one batch; every folder must hold the
    same configuration (manifest fingerprint). ``verify``: read every entry back and
    check it (``montecarlo/journal.py``); a damaged one goes to ``Inventory.damaged``."""
    files: dict[int, Path] = {}
    dups: dict[int, list[Path]] = {}
    damaged: dict[int, DamagedFileError] = {}
    manifest: dict | None = None
    for d in run_dirs:
        m = read_manifest(d / "manifest.json")
        if manifest is None:
            manifest = m
        elif m["fingerprint"] != manifest["fingerprint"]:
            raise ConfigError("collect", str(d), f"holds runs of a different configuration than {run_dirs[0]}")
        if verify:
            found = scan_entries(d)
            entries = found.good
            for run, exc in found.damaged.items():
                damaged.setdefault(run, exc)
        else:
            entries = {int(p.stem[4:]): p for p in sorted(d.glob("run_*.npz"))}
        for run, p in sorted(entries.items()):
            if run in files:
                dups.setdefault(run, [files[run]]).append(p)
            else:
                files[run] = p
    if manifest is None:
        raise ConfigError("collect", [str(d) for d in run_dirs], "no batch journal (runs/manifest.json) found")
    return Inventory(files, manifest, dups, damaged)


def ranges_text(runs: list[int]) -> str:
    """``[1, 2, 3, 7]`` → ``"1-3, 7"``."""
    out, start, prev = [], None, None
    for r in runs + [None]:
        if start is not None and (r is None or r != prev + 1):
            out.append(f"{start}" if start == prev else f"{start}-{prev}")
            start = None
        if r is not None and start is None:
            start = r
        prev = r
    return ", ".join(out)
