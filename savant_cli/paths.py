"""Where the shipped config tree lives, and how data files named in configs are found.

A data file named in a config group (``vehicle.data_dir``, ``guidance.command_file``) is
looked up, in order: as an absolute path; under ``<source>/<group>/`` for every config
source Hydra composed from (so a user's own ``-cd DIR`` or ``--config-dir`` tree wins
over the shipped one); then relative to the current directory.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from savant_cli.errors import ConfigError


def shipped_config_dir() -> Path:
    """Directory of the config tree installed with the package (``savant_cli.conf``), or
    ``conf/`` beside the package when running from a source checkout."""
    here = Path(__file__).resolve().parent
    installed = here / "conf"
    if (installed / "config.yaml").is_file():
        return installed
    return here.parent / "conf"


def shipped_reference_dir() -> Path:
    """Directory of the reference flights of other simulations shipped for ``savant
    compare`` (``references/`` in a source checkout, ``savant_cli.references`` when
    installed). Kept out of ``conf/``: Hydra would list it as a config group."""
    here = Path(__file__).resolve().parent
    installed = here / "references"
    if (installed / "jsbsim_names.yaml").is_file():
        return installed
    return here.parent / "references"


def hydra_search_dirs() -> list[Path]:
    """File-system config directories of the running Hydra job, highest priority first;
    the shipped tree when Hydra is not running."""
    dirs: list[Path] = []
    try:
        from hydra.core.hydra_config import HydraConfig

        if HydraConfig.initialized():
            for src in HydraConfig.get().runtime.config_sources:
                if src.schema == "file" and src.path:
                    dirs.append(Path(src.path))
                elif src.schema == "pkg" and src.path:
                    pkg = resources.files(src.path)
                    if hasattr(pkg, "_paths"):  # namespace package (MultiplexedPath)
                        dirs.extend(Path(str(x)) for x in pkg._paths)
                    else:
                        dirs.append(Path(str(pkg)))
    except Exception:  # noqa: BLE001 - any Hydra trouble falls back to the shipped tree
        dirs = []
    shipped = shipped_config_dir()
    if shipped not in dirs:
        dirs.append(shipped)
    return dirs


def resolve_data_path(key: str, group: str, name: str, search_dirs: list[Path] | None = None,
                      must_be_dir: bool = False) -> Path:
    """Find a data file or folder named in config group ``group``.

    Raises
    ------
    ConfigError
        When no candidate exists, listing where it looked.
    """
    if not name:
        raise ConfigError(key, name, "must name a file or folder")
    p = Path(name).expanduser()
    candidates = [p] if p.is_absolute() else [d / group / p for d in (search_dirs or hydra_search_dirs())] + [Path.cwd() / p]
    for c in candidates:
        if (c.is_dir() if must_be_dir else c.is_file()):
            return c.resolve()
    kind = "folder" if must_be_dir else "file"
    raise ConfigError(key, name, f"no such {kind}; looked in " + ", ".join(str(c) for c in candidates))
