"""pymavlink, loaded once with the ArduPilot dialect on MAVLink 2 (the vehicle adapter, the boat simulator).

pymavlink picks MAVLink 1 or 2 from the ``MAVLINK20`` environment variable when a dialect is loaded, and
keeps the dialect module global; ArduPilot and MAVSDK speak MAVLink 2, so the variable is set (unless the
user set it) before the dialect is loaded. ``mavlink`` is the dialect module: message classes, enums and
constants (``mavlink.MAV_CMD_DO_SET_MODE``).
"""

from __future__ import annotations

import os

os.environ.setdefault("MAVLINK20", "1")

from pymavlink import mavutil

mavutil.set_dialect("ardupilotmega")
mavlink = mavutil.mavlink

__all__ = ["mavlink", "mavutil"]
