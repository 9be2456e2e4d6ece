"""Contacts: rigid contacts and their force variables for inverse-dynamics solvers."""

from dgraph.entities.contacts.contact6d import Contact6d
from dgraph.entities.contacts.point_contact import PointContact

__all__ = ["Contact6d", "PointContact"]
