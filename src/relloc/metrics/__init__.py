"""Metrics: errors with angle wrapping, RMSE, NEES/NIS with chi-square bands, conditioning."""
