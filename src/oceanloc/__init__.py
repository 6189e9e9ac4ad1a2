"""oceanloc: surface-based underwater acoustic localization.

Data flows one way through the subpackages::

    config -> models -> estimation -> planning -> sim / evaluation -> reproduce / report -> cli

Each subpackage imports only from the ones to its left; the CLI is a thin shell over functions a
notebook user can call directly.
"""

__version__ = "0.1.0"
