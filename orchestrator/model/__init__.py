"""The system model: the SSP XML layer (``ssp_xml``), reading a System Structure Description
with its parameter bindings (``ssp``), a model from a folder, an .ssd or an .ssp archive
(``ssp_archive``) and where a component's FMU is found (``fmu_path``).

Wing order: imports ``results`` and ``building``; imported by ``cosim`` and above.
"""
