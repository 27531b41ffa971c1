"""Plane geometry helpers for the air-ground team (triangle bearing construction, seed 003)."""

from relloc.geometry.triangle import TriangleBearing, side_of, triangle_bearing

__all__ = ["TriangleBearing", "side_of", "triangle_bearing"]
