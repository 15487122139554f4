"""Hydra search-path plugin: keeps savant's shipped config tree on the search path.

With it, ``savant run -cd MY_CONFIGS`` (or ``--config-dir``) layers a user's own config
folder over the shipped one: the user's groups and ``config.yaml`` win, every group they
do not define still comes from savant.
"""

from hydra.core.config_search_path import ConfigSearchPath
from hydra.plugins.search_path_plugin import SearchPathPlugin


class SavantSearchPathPlugin(SearchPathPlugin):
    def manipulate_search_path(self, search_path: ConfigSearchPath) -> None:
        from savant_cli.paths import shipped_config_dir

        search_path.append(provider="savant", path=f"file://{shipped_config_dir()}")
