"""Strict-priority least squares: the lexicographic cascade of thesis Eq. 4.4 and 2.59, its
linear algebra, its closed-form active set and its ProxQP levels."""

from dgraph.control.cascade.lexicographic import LexicographicCascade

__all__ = ["LexicographicCascade"]
