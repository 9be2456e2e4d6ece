"""robot entities."""
