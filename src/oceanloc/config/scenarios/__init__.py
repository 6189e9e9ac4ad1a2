"""The built-in scenario files, one folder per kind: ``survey/``, ``flock/`` and ``drift/`` (TOML, and the
NetCDF current product of ``dillard-drift-gyre-netcdf``). Load them by name with the ``load_*_scenario``
functions of :mod:`oceanloc.config`; ``oceanloc scenarios list`` names them.
"""
