"""Vehicles a sensor can ride on: the point-mass fixed-wing UAV of a guidance study
(``point_mass_uav``), the waypoint route and its L1 guidance (``route_guidance``), the Dryden
turbulence it flies through (``turbulence``) and the choice, by time tag, of the navigation
solution its guidance flies on (``tagged_solutions``).

Wing order: imports ``core`` and ``ins``; imported by ``components`` only.
"""
