"""Inertial navigation: physical constants and unit factors (``constants``), the WGS-84 earth
model (``earth``), attitude representations (``rotations``, ``mrp``), the strapdown mechanization
and its exact inverse (``strapdown``), the 15-state INS error model (``error_model``), motion
profiles and their kinematics (``motion_profiles``, ``profile_segments``) and the truth
trajectory with its ideal IMU increments (``trajectory``, shared per process by ``ideal_track``),
and how far a sampled truth is from its own kinematics (``truth_consistency``).

Wing order: imports ``core`` only; imported by ``sensors``, ``filters`` and ``components``.
"""
