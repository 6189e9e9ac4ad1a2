"""The file readers' per-line rules, for streams: re-exported from the readers' own modules.

One implementation serves files and live streams (UDP, TCP, serial, gpsd, SeaTrac):
:func:`~oceanloc.io.qc.decode_line` (the line rule of :func:`~oceanloc.io.qc.read_lines`),
:class:`~oceanloc.io.nmea.NmeaLineParser` (the loop of :func:`~oceanloc.io.nmea.read_nmea`) and
:class:`~oceanloc.io.usbl.UsblLineParser` (the loop of :func:`~oceanloc.io.usbl.read_usbl`). Import
from those modules; this one keeps the older import path working.
"""

from oceanloc.io.nmea import GpsFix, Heading, NmeaLineParser, gps_log_from_records
from oceanloc.io.qc import decode_line
from oceanloc.io.usbl import RangeRecord, UsblLineParser, range_log_from_records

__all__ = [
    "GpsFix",
    "Heading",
    "NmeaLineParser",
    "RangeRecord",
    "UsblLineParser",
    "decode_line",
    "gps_log_from_records",
    "range_log_from_records",
]
