"""Vehicles a sensor can ride on: the point-mass fixed-wing UAV of a guidance study
(``point_mass_uav``), the waypoint route and its L1 guidance (``route_guidance``) and the Dryden
turbulence it flies through (``turbulence``).

Wing order: imports ``core`` and ``ins``; imported by ``components`` only.
"""
