"""Co-simulation: the one instance interface (``backends``) with its two backends, FMUs through
fmpy (``fmu_instance``) and navcore components directly (``direct_instance``), what is known of
a component before it is instantiated (``component_description``), the Gauss-Seidel and Jacobi
exchange (``exchange``), the fixed-step multirate master (``master``), a model run in libcosim
(``libcosim_run``) and Ctrl-C deferred to the master's safe points (``interrupts``).

Wing order: imports ``results``, ``building`` and ``model``; imported by ``running`` and above.
"""
