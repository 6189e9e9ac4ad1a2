"""Field services: work on recorded or live survey data, neither simulation nor paper reproduction.

- :mod:`.survey_journal`, :mod:`.survey_journal_export`: the SQLite survey journal's estimates, next
  waypoint and exports (GeoJSON, CSV);
- :mod:`.replay`, :mod:`.replay_records`: planning replayed on recorded logs and GNSS-A surveys (journal
  Section VI, PLANS eq. 31);
- :mod:`.repeatability`: GNSS-A surveys of one site compared at one epoch (plate-motion site velocity).
"""
