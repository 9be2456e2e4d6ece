"""Walking: footstep plans, the contact schedule, the ZMP/LIPM pattern generator, swing trajectories
(thesis §2.4, §4.4; the walking pattern generator of Ch. 4's flat walks)."""

from dgraph.entities.walking.footsteps import (
    Footstep,
    FootstepPlan,
    Phase,
    SoleShape,
    lateral_walk,
    straight_walk,
    turning_walk,
)

__all__ = ["Footstep", "FootstepPlan", "Phase", "SoleShape", "lateral_walk", "straight_walk", "turning_walk"]
