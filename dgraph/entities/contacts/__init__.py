"""contacts entities."""
