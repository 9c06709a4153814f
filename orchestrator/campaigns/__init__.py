"""Many runs: the serial, process-pool and Dask executors (``executor``), resumable Monte
Carlo campaigns (``campaign``) and their summary (``campaign_summary``) with the statistics of
runs (``statistics``), the parameter-scale sweep (``sweep``), the genetic algorithm and the tuner
built on it (``genetic``, ``tune``) and the benchmark of the executors (``campaign_bench``).

Wing order: imports the wings below it up to ``running``; imported by ``reporting``,
``packaging`` and ``cli``.
"""
