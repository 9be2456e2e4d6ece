"""Reference generators: signals that are functions of time."""

from dgraph.entities.references.sinusoid import Sinusoid

__all__ = ["Sinusoid"]
