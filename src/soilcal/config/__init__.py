"""Soil configuration: schema validation and loading.

One soil is one YAML file ``config/soils/<soil>.yaml`` validated against
``soil.schema.yaml`` (JSON Schema 2020-12) and then against the rules a schema cannot state
(levels in order, references between stages, the published tables' shape). Every failure raises
:class:`soilcal.errors.InputError` naming the file, the field and what was expected, before any
result is written.

Nothing is imported here eagerly: a module of this package that needs no schema
(:mod:`~soilcal.config.parameters`, which a DEM job reads) loads without jsonschema and yaml.
"""

_LOAD = ("SOIL_SCHEMA", "Soil", "design_runs", "load_soil", "load_workflow_config", "read_yaml")


def __getattr__(name):
    if name in _LOAD:
        from soilcal.config import load

        return getattr(load, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = list(_LOAD)
