"""features entities."""
