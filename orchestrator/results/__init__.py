"""A run's results, the master's lowest wing: the recorded table (``run_results``), where the
master's rows go (``recorder``: memory or streamed chunks), the metric definitions as in the
papers' tables (``metrics``) and what is made of several filters' metrics
(``metric_comparisons``), the named windows and phases of a scenario (``windows``, ``phases``),
the output folder written whole (``outputs``), JSON-ready values (``jsonsafe``) and the PNG plots
of results (``plots``).

Wing order: imports only :mod:`orchestrator.errors` and navcore; every other wing may import it.
"""
