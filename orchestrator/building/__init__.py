"""The FMUs themselves: building ``fmus/`` into ``fmus/dist/`` when stale (``build``), the
patched pythonfmu library (``native_library``), ``fmpy validate`` of FMUs (``validation``) and the
environment a native host needs (``hostenv``).

Wing order: imports ``results``; imported by ``model`` and every wing above it.
"""
