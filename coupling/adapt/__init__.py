"""Adaptive mesh refinement: a posteriori estimator (:mod:`.estimator`), Doerfler
marking (:mod:`.marking`), refinement and transfer of the iterate (:mod:`.transfer`) and
the loop solve -> estimate -> mark -> refine (:mod:`.loop`); docs/design/estimator.md."""
from coupling.adapt.estimator import Estimate, estimate
from coupling.adapt.loop import AdaptOptions, Level, adapt
from coupling.adapt.marking import doerfler_marking

__all__ = [
    "Estimate",
    "estimate",
    "doerfler_marking",
    "AdaptOptions",
    "Level",
    "adapt",
]
