"""Fusion of beliefs between robots: pose composition, covariance intersection, de-correlation,
equivalent-measurement messages, and seed 002's distributed fuser as a contract estimator."""
