"""Each scenario planned once for a test module: ``core.planner.plan`` remembered by the
scenario's contents and its options (the progress display, on or off, changes nothing of the
result). For tests whose subject is what a command does with a plan (prints, writes, flies)
and that run the same plan more than once: the search itself is tested elsewhere, and the
first call of each question still searches. The Plan is frozen; the same one is handed back."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from .flown_route_memo import contents


def plan_each_scenario_once() -> Iterator[dict]:
    """For a module-scoped fixture: ``plan`` remembered until it ends; yields the memory (one
    entry a question) for tests that assert a plan was shared."""
    import gcs_planner.core.planner as planner

    search = planner.plan
    plans: dict[object, object] = {}

    def planned_once(scenario, **options):  # noqa: ANN001, ANN202 - planner.plan's
        asked = tuple(sorted((k, repr(v)) for k, v in options.items() if k != "progress"))
        key = (contents(scenario), asked)
        if key not in plans:
            plans[key] = search(scenario, **options)
        return plans[key]

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(planner, "plan", planned_once)
        yield plans
