"""Scenario files: TOML -> validated, frozen, typed objects; every error names the file, table and field.

:mod:`.survey` (transponder surveys), :mod:`.flock` (flock tracking) and :mod:`.drift` (drift planning,
and the planning problem a scenario describes); :mod:`.toml_fields` is the typed TOML access they share
and :mod:`.builtin` finds the papers' scenarios shipped in ``scenarios/``. (The settings a survey journal
keeps are part of the journal's format: :mod:`oceanloc.field.survey.settings`.)
"""
