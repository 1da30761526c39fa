"""gcs_planner: exact INS-constrained route planning, MAVLink mission export, mock vehicle.

The library's face, in the field's words::

    from gcs_planner import load_scenario, plan, choose, write_mission

    scenario = load_scenario("missions/example/scenario.toml", turn_radius=200)
    result = plan(scenario)               # the Pareto front and a route chosen from it
    shortest = choose(result, "shortest", min_probability=0.9)
    write_mission(shortest, "out/shortest.plan")

* :func:`load_scenario` reads a scenario file, keyword arguments overriding its values;
* :func:`plan` computes the exact Pareto front (``Plan.front``) and chooses one route
  (``Plan.route``, index ``Plan.chosen``) among those at least 0.99 likely to arrive
  (:data:`DEFAULT_MIN_PROBABILITY`);
* :func:`choose` picks another route of the same front;
* :func:`write_mission` writes a route as a .plan, .waypoints, .geojson, .kml or .csv file.

Names are imported on first use, so ``import gcs_planner`` (and the command line's start) stays
light: numpy, scipy and the rest load only when a name that needs them is touched.
"""

from __future__ import annotations

import importlib
import importlib.util
import os
import sys
from typing import TYPE_CHECKING, Any

__version__ = "0.2.0"


class _CheckoutSim:
    """Finds ``gcs_planner.sim`` in a source checkout. The mock vehicle lives in the
    repository's top-level ``sim/`` folder (the layout the project's design card asks for); an
    installed copy has it at ``gcs_planner/sim`` (pyproject's package-dir), but a checkout run
    in place (its tests, ``python -m gcs_planner``) imports this folder, beside which it sits."""

    def __init__(self, folder: str) -> None:
        self.folder = folder

    def find_spec(self, fullname: str, path: object = None, target: object = None) -> Any:
        if fullname != "gcs_planner.sim":
            return None
        init = os.path.join(self.folder, "__init__.py")
        return importlib.util.spec_from_file_location(
            fullname, init, submodule_search_locations=[self.folder]
        )


def _find_sim_in_checkout() -> None:
    here = os.path.dirname(os.path.abspath(__file__))
    beside = os.path.join(os.path.dirname(here), "sim")
    if os.path.isdir(os.path.join(here, "sim")) or not os.path.isfile(
        os.path.join(beside, "__init__.py")
    ):
        return  # installed (or no mock vehicle beside it)
    if not any(isinstance(f, _CheckoutSim) for f in sys.meta_path):
        sys.meta_path.append(_CheckoutSim(beside))


_find_sim_in_checkout()

# A test's hold at one import, to send Ctrl-C there (gcs_planner/runtime/hold.py); never set in use.
if os.environ.get("GCS_PLANNER_HOLD_IMPORT"):
    from gcs_planner.runtime.hold import install_from_environment

    install_from_environment()
# The installed script imports the command line before its main() can catch a Ctrl-C.
if os.path.basename(sys.argv[0] if sys.argv else "") == "gcs-planner":
    from gcs_planner.runtime.interrupt import one_line_if_uncaught

    one_line_if_uncaught()

# public name -> module that defines it
_WHERE = {
    "load_scenario": "gcs_planner.library",
    "choose": "gcs_planner.library",
    "write_mission": "gcs_planner.library",
    "plan": "gcs_planner.core.planner",
    "Plan": "gcs_planner.core.planner",
    "OBJECTIVES": "gcs_planner.core.planner",
    "Route": "gcs_planner.core.route",
    "Scenario": "gcs_planner.scenario.model",
    "Parameters": "gcs_planner.scenario.model",
    "Origin": "gcs_planner.scenario.model",
    "Kind": "gcs_planner.scenario.model",
    "VehicleProfile": "gcs_planner.aircraft.profile",
    "DEFAULT_MIN_PROBABILITY": "gcs_planner.core.choose",
    "RiskyRouteError": "gcs_planner.core.choose",
    "RiskyRouteWarning": "gcs_planner.core.choose",
    "GcsPlannerError": "gcs_planner.errors",
    "InputError": "gcs_planner.errors",
    "InfeasibleError": "gcs_planner.errors",
}
__all__ = [
    "DEFAULT_MIN_PROBABILITY",
    "GcsPlannerError",
    "InfeasibleError",
    "InputError",
    "Kind",
    "OBJECTIVES",
    "Origin",
    "Parameters",
    "Plan",
    "RiskyRouteError",
    "RiskyRouteWarning",
    "Route",
    "Scenario",
    "VehicleProfile",
    "choose",
    "load_scenario",
    "plan",
    "write_mission",
]

if TYPE_CHECKING:
    from gcs_planner.aircraft.profile import VehicleProfile
    from gcs_planner.core.choose import DEFAULT_MIN_PROBABILITY, RiskyRouteError, RiskyRouteWarning
    from gcs_planner.core.planner import OBJECTIVES, Plan, plan
    from gcs_planner.core.route import Route
    from gcs_planner.errors import GcsPlannerError, InfeasibleError, InputError
    from gcs_planner.library import choose, load_scenario, write_mission
    from gcs_planner.scenario.model import Kind, Origin, Parameters, Scenario


def __getattr__(name: str) -> Any:
    module = _WHERE.get(name)
    if module is None:
        raise AttributeError(f"module 'gcs_planner' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # once imported, a plain attribute
    return value


def __dir__() -> list[str]:
    return sorted([*globals(), *_WHERE])
