"""Co-simulation: the one instance interface (``backends``) with its two backends, FMUs through
fmpy (``fmu_instance``) and navcore components directly (``direct_instance``); an FMU in a
host process of its own (``hosted_instance``, the host ``fmu_host``, which FMUs and how long a
call may take: ``isolation``, the child processes shared with verify: ``host_process``); what
is known of a component before it is instantiated (``component_description``), the
Gauss-Seidel and Jacobi exchange (``exchange``), the fixed-step multirate master
(``master``), a model run in libcosim (``libcosim_run``) and Ctrl-C deferred to the master's
safe points (``interrupts``).

Wing order: imports ``results``, ``building`` and ``model``; imported by ``running`` and above.
"""
