"""stvm's version: part of every cache key, so it lives below the project driver that computes them."""

__version__ = "0.1.0"
