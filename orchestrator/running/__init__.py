"""One scenario run: the scenario facade that loads a scenario, swaps its filter, runs it and
computes its metrics (``scenarios``), what is checked before a run starts (``prechecks``), sensor
logs recorded and replayed in place of the sensors (``replay``), our numbers next to the paper's
(``comparison``, ``comparison_text``) and the files of ``navfmu run``/``compare``
(``run_outputs``).

Wing order: imports ``results``, ``building``, ``model`` and ``cosim``; imported by
``campaigns`` and above.
"""
