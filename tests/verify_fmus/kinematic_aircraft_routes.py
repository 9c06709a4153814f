"""A module of the kinematic aircraft's own project (the ``project_module`` variant ships it
in the FMU's resources): the routes an aircraft instance flies, each claimed by one.  It lives
in the host's one ``sys.modules``, shared by every instance of the FMU in that process: the
second instance finds the route claimed by the first."""
_CLAIMED = set()


def claim(name):
    if name in _CLAIMED:
        raise RuntimeError(f"route {name!r} is already flown by another aircraft")
    _CLAIMED.add(name)
