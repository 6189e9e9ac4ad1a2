"""Five GNSS-Acoustic surveys of one seafloor transponder offshore La Jolla (BSD-3, see LICENSE)."""
