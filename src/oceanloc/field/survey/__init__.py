"""An open survey and everything about it, in one place.

- :mod:`.journal`: the SQLite survey journal (the storage: records, events, derived results);
- :mod:`.settings`: the settings a journal keeps (:class:`~.settings.JournalSettings`, stored in its
  ``meta`` table);
- :mod:`.estimates`: the beacon estimates and the next waypoint computed from a journal's records (the
  batch reference), and the survey commands' operations;
- :mod:`.state`: the estimates kept up to date as records arrive (the live loop's estimator);
- :mod:`.export`, :mod:`.check`: exports (GeoJSON, CSV) and the journal check.

Nothing is imported here, so ``import oceanloc.field.survey.journal`` costs only what it needs.
"""
