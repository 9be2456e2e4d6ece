"""estimators entities."""
