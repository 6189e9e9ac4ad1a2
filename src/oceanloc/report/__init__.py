"""What a person reads: figures and terminal tables, one module per domain.

:mod:`.figures` (matplotlib PNG: survey, replay, field, flock, drift) and :mod:`.tables` (rich tables,
units in every column header). The report layer only draws results computed below it.
"""
