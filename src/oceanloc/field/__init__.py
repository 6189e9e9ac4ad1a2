"""Field services: work on recorded or live survey data, neither simulation nor paper reproduction.

- :mod:`.survey`: an open survey and everything about it: its SQLite journal, the settings it keeps,
  the estimates (batch and incremental), the next waypoint, the status, check and exports (GeoJSON, CSV);
- :mod:`.replay`, :mod:`.replay_records`: planning replayed on recorded logs and GNSS-A surveys (journal
  Section VI, PLANS eq. 31);
- :mod:`.gnssa_surveys`, :mod:`.repeatability`: GNSS-A surveys of one site read, solved and compared at
  one epoch, with the site velocity chosen from the survey's location (plate-motion model);
- :mod:`.range_logs`: GPS + range log pairs read and aligned (one ENU origin rule), beacons located,
  range noise measured.
"""
