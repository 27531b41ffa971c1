"""Fusion of beliefs between robots: pose composition, covariance intersection, de-correlation."""
