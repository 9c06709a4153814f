"""Thin pythonfmu shell around a navcore :class:`~navcore.core.component.Component`.

Each FMU script in ``fmus/`` is a few lines: a class deriving directly from ``Fmi2Slave``,
defined in the script itself, whose ``__init__`` calls :func:`setup` with the navcore component
it wraps and whose other FMI methods are the functions of this package.  (pythonfmu's native
loader finds the slave class in the script's module and keeps the module alive only in that
shape: with an intermediate base class, or without an ``__init__`` of the script's own, a
second instantiation of the same FMU in one process crashed the interpreter.)  This package
does the FMI side once for all of them, one concern per module:

* registers every declared parameter, input and output with legal causality, variability and
  initial (Integer/Boolean ``discrete``; parameters ``fixed`` with ``initial="exact"``;
  outputs ``calculated`` and listed as InitialUnknowns; :mod:`fmushell.shell`);
* writes SI units and their UnitDefinitions into the model description, and the Outputs' and
  InitialUnknowns' dependencies as the FMU behaves (pythonfmu does neither;
  :mod:`fmushell.model_description`);
* saves the full internal state (the registered values and the component's declared state,
  :mod:`navcore.core.state`) behind ``canGetAndSetFMUstate`` / ``canSerializeFMUstate``, and
  serializes it in the checked plain-data format of :mod:`navcore.core.state_format`: a blob is
  never code, and one that is refused leaves the instance as it was (:mod:`fmushell.fmu_state`);
* never lets a Python exception escape an FMI call (but the refusals of the statuses
  paragraph below, where the binary turns them into fmi2Error): a user error (NaN input)
  is one message ``<instance>: <what> (at t = <time> s)`` (the first Error-level message of
  the instance: a master reports it as the cause), fmi2Error from ``do_step`` with the
  instance in FMI's error state (the patched library; with pythonfmu's own, logged and
  fmi2Discard); after such an error every further ``do_step`` is refused too.
  A bug's traceback follows in a second message (category ``traceback``).
* hands the experiment's stop time (fmi2SetupExperiment) to the component before it
  initializes, so a component can refuse a run it cannot cover.
* keeps the build's packages, which carry names private to the build, importable from a
  folder that exists (:mod:`fmushell.private_paths`);
* works around two defects of pythonfmu 0.7's native binary that corrupted the heap at
  process exit: its loader's extra ``Py_DECREF`` of the script's globals and its interpreter
  teardown running after the C++ static destructors, followed by a second reset of its
  destroyed interpreter owner; the latter for every pythonfmu binary in the process, a third
  party's FMU's too (:mod:`fmushell.pythonfmu_fixes`).

Hostile or careless host calls (FMI rules checked here and in
:meth:`navcore.core.component.Component.advance`):

* ``doStep`` whose communication point is not where the previous step ended (back or ahead),
  or whose step size is not > 0: refused, nothing changes, a following legal step works;
* get/set of an unknown value reference or one of another type, set of an output, set of a
  (fixed) parameter after ``fmi2ExitInitializationMode``: refused, nothing is written, the
  message names the value reference or variable;
* a parameter the component refuses at ``fmi2ExitInitializationMode``; a state
  ``fmi2SetFMUstate`` or ``fmi2DeSerializeFMUstate`` refuses (:mod:`fmushell.fmu_state`).

Statuses: each such call returns fmi2Error with its message logged at fmi2Error and the
instance stays usable where the FMU's binary is the patched pythonfmu library; with
pythonfmu's own library nothing may raise, and the refusal is reported as
:mod:`fmushell.refusals` describes.
"""
from __future__ import annotations

from . import private_paths
from .refusals import FmiCallRefused, refusals_return_error
from .shell import bind_methods, do_step, setup

__all__ = ["private_paths", "setup", "do_step", "bind_methods", "FmiCallRefused",
           "refusals_return_error"]
