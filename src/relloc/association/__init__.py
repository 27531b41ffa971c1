"""Gating, hypotheses, assignment and mixture reduction (separate, swappable stages)."""
