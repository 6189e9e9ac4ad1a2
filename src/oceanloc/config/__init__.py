"""Scenario files: TOML -> validated, frozen, typed objects; every error names the file, table and field.

:mod:`.survey` (transponder surveys), :mod:`.flock` (flock tracking), :mod:`.drift` (drift planning, and
the planning problem a scenario describes) and :mod:`.survey_journal` (the settings a survey journal
keeps); :mod:`.toml_fields` is the typed TOML access they share and :mod:`.builtin` finds the papers'
scenarios shipped in ``scenarios/``.
"""
