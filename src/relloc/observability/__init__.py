"""Observability: Lie derivatives, rank tests, RPMG graph tests, PCRLB."""
