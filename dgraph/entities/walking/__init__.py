"""Walking: footstep plans, the contact schedule, the ZMP/LIPM pattern generator, swing trajectories
(thesis §2.4, §4.4; the walking pattern generator of Ch. 4's flat walks)."""

from dgraph.entities.walking.footsteps import (
    Footstep,
    FootstepPlan,
    Phase,
    SoleShape,
    lateral_walk,
    straight_walk,
    terrain_walk,
    turning_walk,
)
from dgraph.entities.walking.pattern_generator import ComPlan, ZmpPatternGenerator
from dgraph.entities.walking.planner import FootstepPlanner
from dgraph.entities.walking.scheduler import ContactScheduler
from dgraph.entities.walking.swing import SwingPath, SwingTrajectory, swing_clearance, swing_clearances
from dgraph.entities.walking.terrain import TERRAINS, Surface, Terrain

__all__ = ["TERRAINS", "ComPlan", "ContactScheduler", "Footstep", "FootstepPlan", "FootstepPlanner", "Phase",
           "SoleShape", "Surface", "SwingPath", "SwingTrajectory", "Terrain", "ZmpPatternGenerator", "lateral_walk",
           "straight_walk", "swing_clearance", "swing_clearances", "terrain_walk", "turning_walk"]
