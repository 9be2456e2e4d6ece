"""tasks entities."""
