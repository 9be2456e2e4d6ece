"""Glue operators: constants, sums, gains, selections, replacements, switches and saturations."""

from dgraph.entities.operators.add import Add
from dgraph.entities.operators.constant import Constant
from dgraph.entities.operators.gain import Gain
from dgraph.entities.operators.replace import Replace
from dgraph.entities.operators.saturation import Saturation
from dgraph.entities.operators.selector import Selector
from dgraph.entities.operators.switch import Switch

__all__ = ["Add", "Constant", "Gain", "Replace", "Saturation", "Selector", "Switch"]
