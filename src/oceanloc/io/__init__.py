"""The edge to files: readers with line-level quality control, and writers of results with provenance.

Readers: :mod:`.nmea` (GPS logs), :mod:`.usbl` (range logs and their alignment with GPS), :mod:`.gnssa`
(GNSS-Acoustic ping files), :mod:`.wav` (hydrophone recordings); :mod:`.qc` names every skipped line by
file, line and reason. Writers: :mod:`.records` (JSON, CSV and NetCDF records with provenance),
:mod:`.csv_tables`, :mod:`.geojson` and :mod:`.paths` (drift plans). The SQLite survey journal is the
survey's own store: :mod:`oceanloc.field.survey.journal`.
"""
