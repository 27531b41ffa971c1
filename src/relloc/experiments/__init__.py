"""Seed reproductions and the Monte-Carlo runner (one module per experiment)."""
