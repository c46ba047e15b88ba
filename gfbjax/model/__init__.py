"""The GFB-rotor model: finite-difference Reynolds equation, bump-foil strips, Jeffcott/rigid rotor."""

from .grid import Grid, StateLayout
from .reynolds import bearing_force, film_thickness, gauge, mean_gauge_pressure, pressure_rates
from .system import (
    balanced_vector_field,
    core_rates,
    film,
    foil_drive,
    forced_vector_field,
    grid_of,
    initial_state,
    layout,
    plain_bearing_rates,
    runup_vector_field,
    vector_field,
)

__all__ = [
    "Grid",
    "StateLayout",
    "bearing_force",
    "film_thickness",
    "gauge",
    "mean_gauge_pressure",
    "pressure_rates",
    "balanced_vector_field",
    "core_rates",
    "film",
    "foil_drive",
    "forced_vector_field",
    "grid_of",
    "initial_state",
    "layout",
    "plain_bearing_rates",
    "runup_vector_field",
    "vector_field",
]
