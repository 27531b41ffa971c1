"""Estimators: pure predict/update functions first, thin stateful wrappers second."""
