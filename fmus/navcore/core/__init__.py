"""The component core, navcore's lowest wing: the step-wise ``Component`` contract every
FMU wraps (``component``: parameters, inputs, outputs, limits, refused calls), declared state and
its serialized byte format (``state``, ``state_format``), the exact text of FMI start values
(``start_text``), the signal contracts shared between components (``signals``), times on a
sample grid with the one time tolerance (``timing``), the decorator of the compiled kernels
over a run axis, with their cache (``kernels``), and the LAPACK routines those kernels call
(``lapack_kernels``).

Wing order: the lowest wing; imports only :mod:`navcore.errors`; every other wing may import it.
"""
