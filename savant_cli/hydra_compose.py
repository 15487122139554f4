"""Hydra and savant's config: the schema in Hydra's ConfigStore, composition with the
command line's search path, the task's config, and our explanation of an override Hydra
refuses.

Below the entry points (:mod:`savant_cli.cli`, :mod:`savant_cli.api`,
:mod:`savant_cli.hydra_callback`) and :mod:`savant_cli.html_report`, which all compose or
hand a composed config on; above :mod:`savant_cli.config`, whose schema and validation
know nothing of Hydra. Registering the schema is an explicit call
(:func:`register_schema`), made by those entry points, not a side effect of an import.
"""

from __future__ import annotations

import copy
from pathlib import Path
from typing import TYPE_CHECKING

from savant_cli.errors import ConfigError

if TYPE_CHECKING:
    from omegaconf import DictConfig

#: The name of :class:`savant_cli.config.SavantConfig` in Hydra's ConfigStore.
SCHEMA_NAME = "savant_schema"


def register_schema() -> None:
    """Put the schema (:class:`savant_cli.config.SavantConfig`) in Hydra's ConfigStore as
    ``savant_schema`` (for ``--info`` and for users' own configs that want to extend it).

    Idempotent: storing it again replaces the entry with the same schema. Called by every
    entry point that composes (``savant run``, :func:`compose_config`, the run-folder
    callback).
    """
    from hydra.core.config_store import ConfigStore

    from savant_cli.config import SavantConfig

    ConfigStore.instance().store(name=SCHEMA_NAME, node=SavantConfig)


def compose_config(overrides: list[str], config_dir: Path | None) -> DictConfig:
    """The composed config with its ``hydra`` node, as ``savant run`` composes it.

    The search path is the command line's: the shipped tree as the primary config
    folder and, with ``config_dir``, that folder in front of it (what ``savant run -cd``
    does, Hydra's ``command-line`` search-path entry). A Hydra instance the caller has
    initialised (a notebook's own) is restored afterwards.

    Parameters
    ----------
    overrides : list of str
        Hydra overrides, as on the command line.
    config_dir : pathlib.Path or None
        A config folder in front of the shipped tree (``-cd DIR``), or ``None``.

    Returns
    -------
    omegaconf.DictConfig
        The composed config, ``hydra`` node included.

    Raises
    ------
    ConfigError
        Hydra refused the overrides (unknown key or option, bad syntax): the override it
        names, with :func:`variant_hint`'s explanation when there is one.
    """
    from hydra import compose, version
    from hydra._internal.hydra import Hydra
    from hydra._internal.utils import create_config_search_path
    from hydra.core.global_hydra import GlobalHydra
    from hydra.errors import HydraException
    from hydra.initialize import get_gh_backup, restore_gh_from_backup

    from savant_cli.paths import shipped_config_dir

    register_schema()
    backup = get_gh_backup()  # a notebook may have its own Hydra initialised: keep it
    GlobalHydra.instance().clear()
    try:
        version.setbase("1.3")
        search_path = create_config_search_path(search_path_dir=f"file://{shipped_config_dir()}")
        if config_dir is not None:
            search_path.prepend(provider="command-line", path=f"file://{config_dir}")
        Hydra.create_main_hydra2(task_name="savant", config_search_path=search_path)
        return compose(config_name="config", overrides=overrides, return_hydra_config=True)
    except HydraException as exc:
        text = str(exc).strip()
        culprit = next((o for o in overrides if o in text or o.split("=", 1)[0].lstrip("+~") in text), None)
        if culprit is None:
            key, value = "overrides", overrides
        else:
            key, _, value = culprit.partition("=")
            key = key.lstrip("+~") or culprit
        hint = variant_hint(overrides)
        raise ConfigError(key, value, f"{hint} (Hydra: {text.splitlines()[0]})" if hint else text) from None
    finally:
        restore_gh_from_backup(backup)


def task_config(cfg: DictConfig) -> DictConfig:
    """What Hydra hands a task: a copy of the composed config without its ``hydra`` node.

    Parameters
    ----------
    cfg : omegaconf.DictConfig
        A config composed with its ``hydra`` node (:func:`compose_config`, or the one a
        Hydra callback receives).

    Returns
    -------
    omegaconf.DictConfig
        A deep copy without ``hydra``.
    """
    from omegaconf import open_dict, read_write

    task = copy.deepcopy(cfg)
    with read_write(task), open_dict(task):
        del task["hydra"]
    return task


def variant_hint(argv: list[str]) -> str:
    """Our explanation of an override Hydra refused because it names a key of another
    option of its group (the shipped defaults say which option is chosen).

    Parameters
    ----------
    argv : list of str
        The command line's arguments (or the API's overrides); flags are ignored.

    Returns
    -------
    str
        The explanation (:func:`variant_key_hint`), ``""`` when there is none or it
        cannot be made (a hint never hides Hydra's own message).
    """
    from omegaconf import OmegaConf

    from savant_cli.paths import shipped_config_dir

    try:
        defaults = {}
        for entry in OmegaConf.to_container(OmegaConf.load(shipped_config_dir() / "config.yaml")).get("defaults", []):
            if isinstance(entry, dict):
                defaults.update({str(k): str(v) for k, v in entry.items()})
        return variant_key_hint([a for a in argv if "=" in a and not a.startswith("-")], defaults)
    except Exception:  # noqa: BLE001 - a hint must never hide Hydra's own message
        return ""


def variant_key_hint(overrides: list[str], defaults: dict[str, str]) -> str:
    """For command-line overrides Hydra refused before validation: the first one that
    names a key of another option of a :data:`savant_cli.config.GROUP_VARIANTS` group,
    explained (``flex.n_modes`` with ``flex=off``).

    Parameters
    ----------
    overrides : list of str
        ``key=value`` overrides.
    defaults : dict of str to str
        The option of each group when the overrides do not choose one.

    Returns
    -------
    str
        The explanation, a :class:`ConfigError`'s text; ``""`` when no override names
        another option's key.
    """
    from savant_cli.config import GROUP_VARIANTS, has_key

    chosen = dict(defaults)
    for o in overrides:
        k, _, v = o.lstrip("+~").partition("=")
        if k in GROUP_VARIANTS:
            chosen[k] = v
    for o in overrides:
        k, _, v = o.lstrip("+~").partition("=")
        group, _, sub = k.partition(".")
        if group in GROUP_VARIANTS and sub and chosen.get(group) in GROUP_VARIANTS[group]:
            flown = chosen[group]
            if has_key(GROUP_VARIANTS[group][flown], sub.split(".")):
                continue
            where = [opt for opt, schema in GROUP_VARIANTS[group].items() if opt != flown
                     and has_key(schema, sub.split("."))]
            if where:
                return str(ConfigError(k, v, f"not a key of {group}={flown}; it belongs to "
                                             f"{' and '.join(f'{group}={w}' for w in where)}"))
    return ""
