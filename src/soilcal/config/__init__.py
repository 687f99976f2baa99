"""Soil configuration: schema validation and loading.

One soil is one YAML file ``config/soils/<soil>.yaml`` validated against
``soil.schema.yaml`` (JSON Schema 2020-12) and then against the rules a schema cannot state
(levels in order, references between stages, the published tables' shape). Every failure raises
:class:`soilcal.errors.InputError` naming the file, the field and what was expected, before any
result is written.
"""

from soilcal.config.load import (
    SOIL_SCHEMA,
    Soil,
    design_runs,
    load_soil,
    load_workflow_config,
    read_yaml,
)

__all__ = ["SOIL_SCHEMA", "Soil", "design_runs", "load_soil", "load_workflow_config", "read_yaml"]
