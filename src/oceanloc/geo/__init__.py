"""Geodesy: pure functions between geodetic coordinates, Earth-centred and local frames, and plate motion.

:mod:`.enu` converts WGS84 latitude, longitude and ellipsoidal height to and from local East-North-Up
about a stated origin (through pymap3d); :mod:`.projection` is the local tangent-plane frame of gridded
longitude/latitude ocean products; :mod:`.plate_motion` gives ITRF2014 plate-model site velocities, so that
seafloor surveys made months apart can be compared at one epoch.
"""
