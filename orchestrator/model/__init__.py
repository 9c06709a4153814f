"""The system model: the SSP XML layer (``ssp_xml``), reading a System Structure Description
with its parameter bindings (``ssp``), a model from a folder, an .ssd or an .ssp archive
(``ssp_archive``), where a component's FMU is found (``fmu_path``), whether an FMU is this
installation's build or foreign (``fmu_origin``) and writing a parameter set (``ssv_writer``).

Wing order: imports ``results`` and ``building``; imported by ``cosim`` and above.
"""
